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
What ``tune`` starts from: the measured FRFs of a campaign and the resonances fitted in them.

:func:`read_campaign` reads one FRF or many (the estimate folders of an ``identify --poses``
campaign, FRF files, a folder of them, a glob, ``@list.txt``: the inputs of ``fit``), checks
that they describe the same channels on the same lines, and picks the nominal pose.
:func:`axis_modes` fits every axis's own channel P_ii at every pose: the physical two-mass
model (its resonance and input delay, :func:`frf_ident.core.loop.modes.two_mass_mode`) or the
rational model of the order the cost test picks (its modes).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from frf_ident.app.campaign_inputs import campaign_dirs, expand_inputs
from frf_ident.app.fit import is_fit_input, source_pose
from frf_ident.app.frf_source import axis_channels, read_source
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.fit.physical import fit_two_mass
from frf_ident.core.fit.rational import Mode, select_order
from frf_ident.core.loop.modes import two_mass_mode
from frf_ident.errors import FrfIdentInputError
import numpy as np

__all__ = ['AxisModes', 'Campaign', 'MODE_FITS', 'RATIONAL_ORDERS', 'axis_modes',
           'read_campaign']

#: how the resonances are fitted (``--modes``)
MODE_FITS = ('physical', 'rational')
#: orders the rational mode fit tries (the first the cost test accepts, else the lowest AIC):
#: a per-channel fit of a flexible joint needs 3 (one mode and the rigid pole), room for two
#: more modes
RATIONAL_ORDERS = range(2, 8)


@dataclass
class Campaign:
    """
    The FRFs ``tune`` shapes the loop on.

    Attributes
    ----------
    sources : list of Path
        One per pose, in input order.
    names : list of str
        A short name per pose (its folder or file name).
    frfs : list of FrequencyResponse
        Torque -> velocity FRF per pose, all on the lines of the first.
    poses : list of list of float or None
        The joint positions of each FRF's record when its summary.json has them.
    nominal : int
        Index of the nominal pose.
    channels : list of tuple
        (axis, output index, input index) of every axis (:func:`axis_channels`).

    """

    sources: list[Path]
    names: list[str]
    frfs: list[FrequencyResponse]
    poses: list[list[float] | None]
    nominal: int
    channels: list[tuple[str, int, int]]

    @property
    def freq_hz(self) -> np.ndarray:
        """Return the common lines [Hz]."""
        return self.frfs[0].freq_hz

    def axis_responses(self, j: int) -> tuple[np.ndarray, np.ndarray | None]:
        """Return P_ii of axis j at every pose (n_poses, n_freq) and its variances or None."""
        _, o, i = self.channels[j]
        p = np.stack([f.response[o, i] for f in self.frfs])
        var = [f.variance() for f in self.frfs]
        v = None if any(x is None for x in var) else np.stack([x[o, i] for x in var])
        return p, v


def _centre(frfs: list[FrequencyResponse], channels) -> int:
    """Return the pose whose FRFs lie nearest to all others (least largest median distance)."""
    if len(frfs) < 3:
        return 0
    p = np.stack([[f.response[o, i] for _, o, i in channels] for f in frfs])   # (K, n, F)
    dist = np.abs(p[:, None] - p[None]) / np.abs(p[None])                     # (K, K, n, F)
    return int(np.argmin(np.median(dist, axis=-1).max(axis=(1, 2))))


def read_campaign(specs: Sequence[str | Path], nominal: str | None = None) -> Campaign:
    """
    Read one FRF or a campaign of them and check they can be tuned on together.

    Parameters
    ----------
    specs : sequence of str or Path
        Estimate output folders (frf.json) or FRF files, folders of them, globs,
        ``@list.txt`` (:func:`frf_ident.app.campaign_inputs.expand_inputs`).
    nominal : str, optional
        Name (folder or file name) of the nominal pose; default the pose whose own-axis FRFs
        lie nearest to all others (least largest median relative distance), the first of
        one or two.

    Returns
    -------
    Campaign
        The FRFs, names, poses and the nominal index.

    Raises
    ------
    FrfIdentInputError
        Nothing readable, FRFs with other channels or lines than the first, or an unknown
        nominal name.

    """
    sources = expand_inputs([str(s) for s in specs], member=is_fit_input)
    names = campaign_dirs(sources)
    frfs = [read_source(s) for s in sources]
    first = frfs[0]
    for s, f in zip(sources[1:], frfs[1:]):
        if (f.inputs, f.outputs) != (first.inputs, first.outputs):
            raise FrfIdentInputError(f'{s}: channels {f.inputs} -> {f.outputs}; expected those '
                                     f'of {sources[0]} ({first.inputs} -> {first.outputs})')
        same = (f.freq_hz.shape == first.freq_hz.shape
                and np.allclose(f.freq_hz, first.freq_hz, rtol=1e-9))
        if not same:
            raise FrfIdentInputError(f'{s}: {f.freq_hz.size} lines {f.freq_hz[0]:g}-'
                                     f'{f.freq_hz[-1]:g} Hz; expected the lines of '
                                     f'{sources[0]} (the same experiment design at every pose)')
    channels = axis_channels(first)
    if nominal is None:
        k = _centre(frfs, channels)
    elif nominal in names:
        k = names.index(nominal)
    else:
        raise FrfIdentInputError(f'--nominal {nominal}: no such input; expected one of {names}')
    return Campaign(sources, names, frfs, [source_pose(s) for s in sources], k, channels)


@dataclass
class AxisModes:
    """
    The fitted resonances of one axis at every pose.

    Attributes
    ----------
    axis : str
        The joint.
    modes : list of list of Mode
        Per pose, the fitted modes (sorted by frequency).
    delay_s : list of float or None
        Per pose the fitted input delay [s] (physical fit), None for the rational fit.
    fit : str
        ``'physical'`` or ``'rational'``.
    orders : list of int
        Per pose the rational order chosen (empty for the physical fit).

    """

    axis: str
    modes: list[list[Mode]]
    delay_s: list[float] | None
    fit: str
    orders: list[int]


def axis_modes(camp: Campaign, j: int, how: str = 'physical', order: int | None = None
               ) -> AxisModes:
    """
    Fit the resonances of axis j at every pose.

    Parameters
    ----------
    camp : Campaign
        The FRFs.
    j : int
        Axis index (into ``camp.channels``).
    how : {'physical', 'rational'}, optional
        The two-mass model with a fitted delay, or the rational model.
    order : int, optional
        Rational order; default the lowest of RATIONAL_ORDERS the cost test accepts.

    Returns
    -------
    AxisModes
        The modes per pose.

    Raises
    ------
    FrfIdentInputError
        An unknown ``how``, or a fit the FRF cannot support (too few lines).

    """
    if how not in MODE_FITS:
        raise FrfIdentInputError(f'--modes {how}: expected one of {", ".join(MODE_FITS)}')
    axis = camp.channels[j][0]
    p, var = camp.axis_responses(j)
    f = camp.freq_hz
    modes, delays, orders = [], [], []
    for k in range(p.shape[0]):
        v = None if var is None else var[k]
        try:
            if how == 'physical':
                fit = fit_two_mass(f, p[k], v, delay_s=None, name=axis)
                m = two_mass_mode(fit.value, fit.covariance)
                modes.append([] if m is None else [m])
                delays.append(float(fit.delay_s))
            else:
                sel = select_order(f, p[k], v, [order] if order else RATIONAL_ORDERS)
                modes.append(sel.best.modes())
                orders.append(sel.best.order)
        except ValueError as err:
            raise FrfIdentInputError(f'{camp.sources[k]}: {axis}: the {how} fit fails: {err}'
                                     ) from err
    return AxisModes(axis, modes, delays if how == 'physical' else None, how, orders)
