# Copyright 2026 frf_ident developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
Test whether a position-dependent term extrapolates.

Interleaved held-out blocks cover the configurations the fit saw, so a term that only
interpolates (two large sinusoids cancelling over a short travel) passes them.
:func:`leave_range_out` holds out the ends of the term's configuration range instead: fitted
without the rows at the low end of its argument, is the error there smaller with the term
than without it? And the same at the high end. A term kept by the diagnosis must pass this.
"""
from __future__ import annotations

import numpy as np

from ..selection import lstsq
from ..thresholds import RANGE_OUT_SHARE

__all__ = ['failing_position_terms', 'leave_range_out', 'range_ends']


def range_ends(arg: np.ndarray, rows: np.ndarray, share: float = RANGE_OUT_SHARE
               ) -> list[np.ndarray]:
    """
    Return the rows at the low and at the high end of ``arg``'s range over ``rows``.

    Parameters
    ----------
    arg : ndarray, shape (N,)
        A configuration coordinate (a joint angle or an angle sum) [rad].
    rows : ndarray of bool, shape (N,)
        The rows the range is taken over (the fit rows).
    share : float
        Width of each end as a share of the range (by angle, not by sample count).

    Returns
    -------
    list of ndarray of bool, shape (N,)
        ``[low end, high end]``, each a subset of ``rows``; empty when ``rows`` is.

    """
    if not rows.any():
        return []
    lo, hi = float(arg[rows].min()), float(arg[rows].max())
    w = share * (hi - lo)
    return [rows & (arg <= lo + w), rows & (arg >= hi - w)]


def leave_range_out(groups: dict[str, np.ndarray], chosen: list[str], key: str, y: np.ndarray,
                    fit: np.ndarray, args: list[np.ndarray]) -> tuple[float, float]:
    """
    Return the residual energy at the ends of the range with and without group ``key``.

    For every argument in ``args`` and each of its two ends (:func:`range_ends` over
    ``fit``), the groups ``chosen`` are fitted jointly on the other fit rows, with and
    without ``key`` (without it, with a constant load: the ``gravity_torque`` group), and
    the residual energy of each on the end's rows is summed.

    Parameters
    ----------
    groups : dict of str to ndarray, shape (N, k)
        The regressor groups (low-passed columns).
    chosen : list of str
        The selected groups (``key`` among them).
    key : str
        The position-dependent group under test.
    y : ndarray, shape (N,)
        The low-passed residual.
    fit : ndarray of bool, shape (N,)
        The fit rows.
    args : list of ndarray, shape (N,)
        The configuration coordinates the group depends on.

    Returns
    -------
    (float, float)
        Residual energy at the ends with the group and without it; both 0 when no end
        holds a row.

    """
    # without a load term the axis still carries a constant one (gravity at the mean pose)
    rest = [k for k in chosen if k != key] + [c for c in ('gravity_torque',)
                                              if c in groups and c not in chosen]
    e_with = e_without = 0.0
    for arg in args:
        for end in range_ends(arg, fit):
            train = fit & ~end
            if not end.any() or train.sum() <= sum(groups[k].shape[1] for k in chosen):
                continue
            e_with += _end_energy(groups, chosen, y, train, end)
            e_without += _end_energy(groups, rest, y, train, end)
    return e_with, e_without


def _end_energy(groups: dict[str, np.ndarray], names: list[str], y: np.ndarray,
                train: np.ndarray, end: np.ndarray) -> float:
    """Return the residual energy on ``end`` of the groups ``names`` fitted on ``train``."""
    c, _ = lstsq([groups[k][train] for k in names], y[train])
    r = y[end] - (np.column_stack([groups[k][end] for k in names]) @ c if names else 0.0)
    return float(r @ r)


def failing_position_terms(groups: dict[str, np.ndarray], chosen: list[str], y: np.ndarray,
                           fit: np.ndarray, q: np.ndarray, i: int
                           ) -> dict[str, tuple[float, float]]:
    """
    Return the chosen position-dependent groups of axis i that do not extrapolate.

    A gravity group ``gravity:<set>|<set>`` depends on the angle sum of each joint set, the
    torque ripple on the axis' own angle; each is tested by :func:`leave_range_out` and fails
    when the ends' residual energy with it is not below that without it.

    Parameters
    ----------
    groups, chosen, y, fit
        As for :func:`leave_range_out`.
    q : ndarray, shape (N, n)
        Joint positions (between samples) [rad].
    i : int
        The axis.

    Returns
    -------
    dict
        ``{group: (energy with, energy without)}`` of the failing groups.

    """
    out = {}
    for k in chosen:
        if k.startswith('gravity:'):
            args = [q[:, [int(j) for j in js.split(',')]].sum(axis=1)
                    for js in k.split(':')[1].split('|')]
        elif k == 'torque_ripple':
            args = [q[:, i]]
        else:
            continue
        e = leave_range_out(groups, chosen, k, y, fit, args)
        if e[0] >= e[1]:
            out[k] = e
    return out
