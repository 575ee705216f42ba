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
The noise and stochastic nonlinear variance of one realisation per output and line.

:class:`RobustLpmLevels` is what the robust LPM (:mod:`.lpm`) leaves of an estimate for
people: estimates.json keeps it under ``meta['robust_lpm']``
(:attr:`frf_ident.core.estimation.frd.FrequencyResponse.robust_lpm` reads it back), the
console prints its summary and the report draws it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ['RobustLpmLevels']


@dataclass
class RobustLpmLevels:
    """
    Noise and stochastic nonlinear variance of the FRF per output and line (robust LPM).

    Attributes
    ----------
    freq_hz : ndarray, shape (n_lines,)
        The excited lines [Hz].
    noise : ndarray, shape (n_out, n_lines)
        Noise variance of the FRF Y/U of this realisation.
    total : ndarray, shape (n_out, n_lines)
        Noise plus stochastic nonlinear variance of the FRF (local polynomial residual).
    outputs : list of str
        Output channel names.
    units : list of str
        Unit of the variances per output, e.g. '(rad/s)^2/(N m)^2'.
    periods : int
        Steady periods the estimate used.
    dof : int
        Residual dof of the local polynomial per line (the total variance's); the noise
        variance has 2 (periods - 1) real dof per line.
    noise_from : str
        As :class:`RobustLpmResult`.

    """

    freq_hz: np.ndarray
    noise: np.ndarray
    total: np.ndarray
    outputs: list[str]
    units: list[str]
    periods: int
    dof: int
    noise_from: str

    @property
    def nonlinear(self) -> np.ndarray:
        """Stochastic nonlinear variance of the FRF per output and line, max(total - noise, 0)."""
        return np.maximum(self.total - self.noise, 0.0)

    def above_noise_db(self) -> np.ndarray:
        """
        Median nonlinear variance over median noise variance per output [dB].

        Returns
        -------
        ndarray, shape (n_out,)
            10 log10(median(nonlinear) / median(noise)); -inf where at least half the
            lines show none (a linear system: the total is noise alone).

        """
        with np.errstate(divide='ignore'):
            return 10 * np.log10(np.median(self.nonlinear, axis=1)
                                 / np.median(self.noise, axis=1))

    def summary(self) -> list[str]:
        """
        One line per output: the nonlinear variance over the noise.

        Returns
        -------
        list of str
            e.g. 'dq_m/j: nonlinear variance 12.3 dB above noise (median over 40 lines,
            1-40 Hz; 4 periods, dof 4)'; 'below' when the median nonlinear variance is
            under the median noise, 'none' when it is zero.

        """
        out = []
        span = (f'median over {self.freq_hz.size} lines, {self.freq_hz[0]:.3g}-'
                f'{self.freq_hz[-1]:.3g} Hz; {self.periods} periods, dof {self.dof}')
        for name, db in zip(self.outputs, self.above_noise_db()):
            what = ('none above noise' if not np.isfinite(db) else
                    f'{abs(db):.1f} dB {"above" if db >= 0 else "below"} noise')
            out.append(f'{name}: nonlinear variance {what} ({span})')
        return out

    def to_dict(self) -> dict[str, Any]:
        """
        JSON-ready per-line variances.

        Returns
        -------
        dict
            freq_hz, noise_variance, total_variance and nonlinear_variance (per output,
            lists), outputs,
            units, periods, dof, noise_dof, noise_from and per output
            nonlinear_above_noise_db (None where no nonlinear variance shows).

        """
        db = self.above_noise_db()
        return {'freq_hz': self.freq_hz.tolist(), 'noise_variance': self.noise.tolist(),
                'total_variance': self.total.tolist(),
                'nonlinear_variance': self.nonlinear.tolist(), 'outputs': list(self.outputs),
                'units': list(self.units), 'periods': self.periods, 'dof': self.dof,
                'noise_dof': 2 * (self.periods - 1), 'noise_from': self.noise_from,
                'nonlinear_above_noise_db': [float(x) if np.isfinite(x) else None
                                             for x in db]}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> 'RobustLpmLevels':
        """
        Read back :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            As written by :meth:`to_dict`.

        Returns
        -------
        RobustLpmLevels
            The same variances.

        """
        return cls(np.asarray(d['freq_hz'], float), np.asarray(d['noise_variance'], float),
                   np.asarray(d['total_variance'], float), list(d['outputs']),
                   list(d['units']), int(d['periods']), int(d['dof']), d['noise_from'])
