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
Refusals of an excitation's settings and plan before anything runs.

- :func:`check_band`, :func:`check_finite` — a setting that is no usable number or band
  (:class:`~frf_ident.errors.DesignError`).
- :func:`check_position_bound` — a planned position beyond the bound around the operating
  point (:class:`~frf_ident.errors.SafetyError`).
- :func:`check_torque_bound` — a predicted peak torque at ``TORQUE_MARGIN`` of a limit
  (:class:`~frf_ident.errors.SafetyError`).
"""
from __future__ import annotations

import math

from frf_ident.core.excitation.procedures import Phase
from frf_ident.errors import DesignError, SafetyError
import numpy as np


def check_band(f_low: float, f_high: float) -> None:
    """
    Refuse an excitation band that is not 0 < f_low < f_high (finite).

    Parameters
    ----------
    f_low, f_high : float
        Band edges [Hz].

    Raises
    ------
    DesignError
        The band is empty, negative or not finite.

    """
    if not (math.isfinite(f_low) and math.isfinite(f_high) and 0 < f_low < f_high):
        raise DesignError(f'f_low={f_low}, f_high={f_high}: expected 0 < f_low < f_high Hz')


def check_finite(*, minimum: float, positive: tuple[str, ...] = (), **values: float) -> None:
    """
    Refuse a setting that is not a finite number of at least ``minimum``.

    Parameters
    ----------
    minimum : float
        The smallest value allowed.
    positive : tuple of str, optional
        Names that must also be above zero.
    **values : float
        The settings by name.

    Raises
    ------
    DesignError
        Naming the first setting that is NaN, infinite, below ``minimum`` or not positive.

    """
    for name, v in values.items():
        if not math.isfinite(v) or v < minimum or (name in positive and v <= 0):
            need = 'positive' if name in positive else f'at least {minimum:g}'
            raise DesignError(f'{name}={v} must be a finite number, {need}')


def check_position_bound(phases: list[Phase], start: np.ndarray, bound: float, dt: float) -> None:
    """Predicted position (integral of the reference) of every excite phase within +-bound."""
    q = np.asarray(start, dtype=float).copy()
    for ph in phases:
        if ph.kind == 'move':
            q = np.asarray(ph.target, dtype=float).copy()
        elif ph.kind == 'excite':
            traj = q + np.cumsum(ph.reference, axis=0) * dt
            peak = np.max(np.abs(traj))
            if peak > bound * (1 + 1e-9):
                raise SafetyError(f'planned position reaches {math.degrees(peak):.2f} deg, '
                                  f'beyond the bound {math.degrees(bound):.2f} deg')
            q = traj[-1]


#: share of the position bound a chirp step capped by it may plan to use (the planned position is
#: the reference's integral; the measured one follows it through the closed loop, which
#: frf_ident/app/excitation_stream.py checks against the wider live bound)
POSITION_MARGIN = 0.95

#: share of each torque limit a plan may use (the predicted peak torque; the rest is left for
#: what the model does not know)
TORQUE_MARGIN = 0.95


def check_torque_bound(peak: np.ndarray, torque_limit: np.ndarray, joints: list[str],
                       what: str, remedy: str, margin: float = TORQUE_MARGIN) -> None:
    """
    Refuse a plan whose predicted peak torque reaches ``margin`` times a torque limit.

    Parameters
    ----------
    peak : array_like, shape (n,)
        Predicted peak absolute torque [N m] of every axis.
    torque_limit : array_like, shape (n,)
        Torque limit [N m] of every axis.
    joints : list of str
        Joint names, for the message.
    what : str
        The plan's name, for the message.
    remedy : str
        What to change, for the message (``MultisineConfig.remedy()``...).
    margin : float, optional
        Share of each limit the plan may use.

    Raises
    ------
    SafetyError
        An axis's predicted peak reaches ``margin`` times its limit (the message names the
        axes, their peaks and limits).

    """
    peak = np.asarray(peak, dtype=float)
    limit = np.asarray(torque_limit, dtype=float)
    over = np.flatnonzero(~(peak < margin * limit))
    if over.size:
        where = ', '.join(f'{joints[i]} {peak[i]:.1f} of {limit[i]:g} N m'
                          + (' (saturated)' if peak[i] >= limit[i] * (1 - 1e-9) else '')
                          for i in over)
        raise SafetyError(f'{what}: the peak torque predicted on the model reaches '
                          f'{margin:g} x the torque limit: {where}; {remedy}')
