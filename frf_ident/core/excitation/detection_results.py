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
What an excitation detector found: a periodic multisine or an exponential chirp.

- :class:`MultisineDetection` — period, block of whole periods, excited DFT lines (odd or
  not), period correlation and drift (Saupe & Knoblach 2015, Sec. 4).
- :class:`ChirpDetection` — band, active interval and eq. 16 coefficients of
  f(t) = exp(a0 t + a1), with the quality of the fit (Sec. 5).

Both say in one sentence what was found (``describe()``) and give a JSON-ready summary
(``to_dict()``); the detectors are in :mod:`frf_ident.core.excitation.multisine_detect` and
:mod:`frf_ident.core.excitation.chirp_detect`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ['ChirpDetection', 'MultisineDetection']


@dataclass
class MultisineDetection:
    """
    A periodic (multisine) excitation found in a signal.

    Parameters
    ----------
    fs : float
        Sample rate [Hz].
    period_samples : int
        Samples per period P.
    n_periods : int
        Whole periods in the periodic block.
    start : int
        Index of the first sample of the periodic block.
    f0 : float
        Fundamental fs / P [Hz].
    harmonics : ndarray of int
        Excited DFT lines h (frequency h * f0), sorted.
    odd : bool
        True when every excited line is an odd multiple of f0.
    correlation : float
        Normalised autocorrelation at lag P (1 = identical periods).
    line_level_db : float
        Weakest excited line over the median non-excited line [dB].
    channel : int, optional
        Column of a 2-D input that was analysed (default 0).
    drift : float, optional
        How far the true period exceeds ``period_samples`` [samples] (measured from the
        phase of the excited lines between the first and last period; 0 for a period of
        whole samples).

    Attributes
    ----------
    kind : str
        Always 'multisine' (not a constructor parameter).

    """

    fs: float
    period_samples: int
    n_periods: int
    start: int
    f0: float
    harmonics: np.ndarray
    odd: bool
    correlation: float
    line_level_db: float
    channel: int = 0
    drift: float = 0.0
    kind: str = field(default='multisine', init=False)

    @property
    def freq_hz(self) -> np.ndarray:
        """Excited frequencies h * f0 [Hz]."""
        return self.harmonics * self.f0

    @property
    def period(self) -> float:
        """Period duration [s]."""
        return self.period_samples / self.fs

    @property
    def stop(self) -> int:
        """Index one past the last sample of the periodic block."""
        return self.start + self.n_periods * self.period_samples

    def describe(self) -> str:
        """
        One sentence a person can check against the design.

        Returns
        -------
        str
            Period, number of whole periods, start, excited lines, line level and period
            correlation.

        """
        f = self.freq_hz
        lines = (f'{f.size} excited lines {f[0]:.3g}-{f[-1]:.3g} Hz, '
                 + ('all odd multiples of f0' if self.odd else 'not all odd multiples of f0'))
        return (f'{"odd " if self.odd else ""}multisine: period {self.period_samples} samples '
                f'({self.period:.6g} s, f0 = {self.f0:.6g} Hz), {self.n_periods} whole periods '
                f'from sample {self.start} (t = {self.start / self.fs:.3f} s), {lines} '
                f'(weakest line {self.line_level_db:.0f} dB above the rest, '
                f'period correlation {self.correlation:.3f})')

    def to_dict(self) -> dict[str, Any]:
        """
        JSON-ready summary.

        Returns
        -------
        dict
            Every field (``harmonics`` as a list) plus ``freq_hz``, the excited frequencies
            [Hz].

        """
        return {'kind': self.kind, 'fs': self.fs, 'period_samples': self.period_samples,
                'n_periods': self.n_periods, 'start': self.start, 'f0': self.f0,
                'harmonics': self.harmonics.tolist(), 'freq_hz': self.freq_hz.tolist(),
                'odd': self.odd, 'correlation': self.correlation,
                'line_level_db': self.line_level_db, 'channel': self.channel,
                'drift': self.drift}


@dataclass
class ChirpDetection:
    """
    An exponential chirp f(t) = exp(a0 t + a1) on [t0, t1] (eq. 16) found in a signal.

    Times are seconds from the first sample (index 0 is t = 0).

    Parameters
    ----------
    fs : float
        Sample rate [Hz].
    f_low, f_high : float
        Instantaneous frequency at t0 and t1 [Hz] (f_low > f_high for a down-sweep).
    t0, t1 : float
        Start and end of the active chirp [s].
    a0, a1 : float
        Eq. 16 coefficients (a0 = sweep rate [1/s]).
    n_half_cycles : int
        Half cycles used in the fit (inliers).
    fit_residual : float
        Standard deviation of ln f around the fit (relative frequency error).
    channel : int, optional
        Column of a 2-D input that was analysed (default 0).

    Attributes
    ----------
    kind : str
        Always 'chirp' (not a constructor parameter).

    """

    fs: float
    f_low: float
    f_high: float
    t0: float
    t1: float
    a0: float
    a1: float
    n_half_cycles: int
    fit_residual: float
    channel: int = 0
    kind: str = field(default='chirp', init=False)

    @property
    def duration(self) -> float:
        return self.t1 - self.t0

    @property
    def start(self) -> int:
        """Index of the first sample of the chirp."""
        return int(round(self.t0 * self.fs))

    @property
    def stop(self) -> int:
        """Index one past the last sample of the chirp."""
        return int(round(self.t1 * self.fs)) + 1

    def frequency(self, t: np.ndarray | float) -> np.ndarray:
        """
        Instantaneous frequency exp(a0 t + a1) [Hz] (eq. 16).

        Parameters
        ----------
        t : float or array_like
            Time [s] from the first sample.

        Returns
        -------
        ndarray
            Frequency [Hz], shaped as ``t``.

        """
        return np.exp(self.a0 * np.asarray(t, dtype=float) + self.a1)

    def describe(self) -> str:
        """
        One sentence a person can check against the design.

        Returns
        -------
        str
            Band, decades, active interval, sweep rate and quality of the fit.

        """
        decades = abs(np.log10(self.f_high / self.f_low))
        return (f'exponential chirp {self.f_low:.3g}-{self.f_high:.3g} Hz '
                f'({decades:.2f} decades) from t0 = {self.t0:.3f} s to t1 = {self.t1:.3f} s '
                f'({self.duration:.3g} s), sweep rate a0 = {self.a0:.4g} 1/s, fitted on '
                f'{self.n_half_cycles} half cycles with {100 * self.fit_residual:.2g} % '
                f'frequency scatter')

    def to_dict(self) -> dict[str, Any]:
        """
        JSON-ready summary.

        Returns
        -------
        dict
            Every field of the detection.

        """
        return {'kind': self.kind, 'fs': self.fs, 'f_low': self.f_low, 'f_high': self.f_high,
                't0': self.t0, 't1': self.t1, 'a0': self.a0, 'a1': self.a1,
                'n_half_cycles': self.n_half_cycles, 'fit_residual': self.fit_residual,
                'channel': self.channel}
