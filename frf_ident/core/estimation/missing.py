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
What an estimate did with the samples its record lost: how many were estimated, and how well.

Gaps in a record (a recorder that stalled, a burst of lost messages; NaN rows of a recording
read with ``gaps='mark'``) are kept: the missing samples are estimated together with the FRF
(:mod:`frf_ident.core.estimation.missing_periodic` for periodic records,
:mod:`frf_ident.core.estimation.missing_lpm` for the Local Polynomial Method).
:class:`MissingSamples` is the account of it that every route puts in its estimate's
``meta['missing']`` and prints: the count, the periods or frames that held them, and the
standard deviation of the estimates (of estimate minus true sample, per channel).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ['MissingSamples']


@dataclass
class MissingSamples:
    """
    Missing samples estimated in an estimate's record, merged over its periods or frames.

    Parameters
    ----------
    samples : int
        Missing samples estimated (sample instants; every channel of one counts once).
    analysed : int
        Samples in the periods or frames analysed.
    touched : int
        Periods (or frames) holding at least one missing sample.
    units : int
        Periods (or frames) analysed.
    unit : str
        'period' or 'frame'.
    channels : list of str
        Channel names, e.g. ``dq_m/joint_2``.
    sd_ss : ndarray, shape (n_ch,)
        Sum over the estimated samples of the variance of estimate minus true sample.
    noise_ss : ndarray, shape (n_ch,)
        Residual sum of squares of the local model (per sample) the noise level comes from.
    noise_dof : ndarray, shape (n_ch,)
        Its degrees of freedom (real).
    method : str
        How they were estimated ('periodic': from the other periods; 'lpm': the local
        polynomial model).

    """

    samples: int
    analysed: int
    touched: int
    units: int
    unit: str
    channels: list[str]
    sd_ss: np.ndarray
    noise_ss: np.ndarray
    noise_dof: np.ndarray
    method: str
    notes: list[str] = field(default_factory=list)

    @property
    def sd(self) -> np.ndarray:
        """Root mean square standard deviation of the estimates per channel (nan if none)."""
        with np.errstate(invalid='ignore', divide='ignore'):
            return np.sqrt(self.sd_ss / self.samples) if self.samples else \
                np.full(len(self.channels), np.nan)

    @property
    def noise_sd(self) -> np.ndarray:
        """Per-sample noise standard deviation of each channel (nan without a dof)."""
        with np.errstate(invalid='ignore', divide='ignore'):
            return np.sqrt(np.where(self.noise_dof > 0, self.noise_ss / self.noise_dof, np.nan))

    @property
    def fraction(self) -> float:
        """Missing samples over analysed samples."""
        return self.samples / self.analysed if self.analysed else 0.0

    def merged(self, other: 'MissingSamples | None') -> 'MissingSamples':
        """
        Return the account of both (the same channels), e.g. of two segments or blocks.

        Parameters
        ----------
        other : MissingSamples or None
            Another account of the same estimate's channels; None: this one.

        Returns
        -------
        MissingSamples

        """
        if other is None:
            return self
        return MissingSamples(self.samples + other.samples, self.analysed + other.analysed,
                              self.touched + other.touched, self.units + other.units,
                              self.unit, list(self.channels), self.sd_ss + other.sd_ss,
                              self.noise_ss + other.noise_ss, self.noise_dof + other.noise_dof,
                              self.method, self.notes + [n for n in other.notes
                                                         if n not in self.notes])

    def text(self, units: dict[str, str] | None = None) -> str:
        """
        One line for people: what was estimated and how well.

        Parameters
        ----------
        units : dict, optional
            Unit per channel name ('' where unknown).

        Returns
        -------
        str
            e.g. '540 missing samples (1.1 %) in 4 of 6 periods estimated from the other
            periods, kept: sd of the estimates dq_m/joint_2 0.0021 rad/s (noise 0.002), ...'.

        """
        units = units or {}
        how = 'from the other periods' if self.method == 'periodic' else \
            'with the local polynomial model'
        sd = ', '.join(f'{c} {s:.2g} {units.get(c, "")}'.rstrip() + f' (noise {n:.2g})'
                       for c, s, n in zip(self.channels, self.sd, self.noise_sd))
        return (f'{self.samples} missing samples ({100 * self.fraction:.2g} %) in '
                f'{self.touched} of {self.units} {self.unit}s estimated {how} and kept; '
                f'sd of the estimates: {sd}' + ''.join(f'; {n}' for n in self.notes))

    def to_dict(self) -> dict[str, Any]:
        """
        JSON-ready account (estimates.json meta ``missing``).

        Returns
        -------
        dict
            samples, fraction, touched, units, unit, channels, sd and noise_sd (per channel,
            null where unknown), method, notes, and the sums the merge needs.

        """
        def nums(x):
            return [float(v) if np.isfinite(v) else None for v in np.asarray(x, float)]
        return {'samples': int(self.samples), 'analysed': int(self.analysed),
                'fraction': float(self.fraction), 'touched': int(self.touched),
                'units': int(self.units), 'unit': self.unit, 'channels': list(self.channels),
                'sd': nums(self.sd), 'noise_sd': nums(self.noise_sd), 'method': self.method,
                'notes': list(self.notes), 'sd_ss': nums(self.sd_ss),
                'noise_ss': nums(self.noise_ss), 'noise_dof': nums(self.noise_dof)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> 'MissingSamples':
        """
        Read back :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            As written by :meth:`to_dict`.

        Returns
        -------
        MissingSamples

        """
        def arr(x):
            return np.array([np.nan if v is None else v for v in x], float)
        return cls(int(d['samples']), int(d['analysed']), int(d['touched']), int(d['units']),
                   d['unit'], list(d['channels']), arr(d['sd_ss']), arr(d['noise_ss']),
                   arr(d['noise_dof']), d['method'], list(d.get('notes', [])))
