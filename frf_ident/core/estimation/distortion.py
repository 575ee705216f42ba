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
Nonlinear distortion per frequency line of an odd multisine experiment.

An odd multisine excites odd lines only; the output's power at the odd lines it leaves out
shows odd nonlinearities (a cubic spring, friction, saturation), at the even lines even ones
(asymmetry, gravity), both against the noise level of the period mean (Pintelon & Schoukens,
System Identification, 2nd ed., Sec. 4.3 and their detection-line plots). Levels are
|Y_k|^2 of the mean over periods (DFT scaled 1/N, as
:func:`~frf_ident.core.estimation.spectra.periodic_spectra`), averaged over realisations;
the noise level is the variance of that mean (period-to-period spread / n_periods), smoothed
over :data:`NOISE_SMOOTH_LINES` neighbouring lines, or given when a record holds one period.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from scipy import ndimage, stats

__all__ = ['NOISE_SMOOTH_LINES', 'DistortionLines', 'distortion_lines']

#: the noise variance of one line from n periods has only 2 (n - 1) degrees of freedom;
#: its running median over this many neighbouring lines is the level a line is compared
#: with (noise spectra are smooth over a few lines; 9 lines keep a 2-period record's level
#: within about 2 dB of the truth)
NOISE_SMOOTH_LINES = 9


def _db(p: np.ndarray, ref: np.ndarray) -> np.ndarray:
    return 10 * np.log10(np.maximum(p, 1e-300) / np.maximum(ref, 1e-300))


@dataclass
class DistortionLines:
    """
    Output power per line at excited, non-excited odd and even lines, with the noise level.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_lines,)
        Every DFT line from f0 to the top of the band [Hz].
    kind : ndarray of str, shape (n_lines,)
        'excited', 'odd' (non-excited odd line) or 'even' per line.
    power : ndarray, shape (n_out, n_lines)
        |Y|^2 of the period mean (output units squared).
    noise : ndarray or None, shape (n_out, n_lines)
        Noise variance of the period mean per line (smoothed); None when unknown.
    outputs : list of str
        Output channel names.
    units : list of str
        Unit of each output (e.g. 'rad/s'); '' where unknown.
    residual : ndarray or None, shape (n_out, n_lines)
        At the excited lines, with several realisations: power of Y - G U (G the
        least-squares linear response per line over the realisations), the stochastic
        nonlinear distortion plus noise at the lines an odd nonlinearity shares with the
        excitation (all odd lines, when the multisine excites every one); nan elsewhere.

    """

    freq_hz: np.ndarray
    kind: np.ndarray
    power: np.ndarray
    noise: np.ndarray | None
    outputs: list[str]
    units: list[str] | None = None
    residual: np.ndarray | None = None

    def unit_list(self) -> list[str]:
        """
        Return the unit of each output ('' where unknown).

        Returns
        -------
        list of str
            One unit per output.

        """
        return list(self.units) if self.units is not None else [''] * len(self.outputs)

    def above_noise_db(self, kind: str) -> np.ndarray:
        """
        Median level of the lines of ``kind`` over the noise level, per output [dB].

        Parameters
        ----------
        kind : {'odd', 'even', 'excited', 'residual'}
            Which lines ('residual': the excited lines' :attr:`residual`).

        Returns
        -------
        ndarray, shape (n_out,)
            Median over those lines of 10 log10(power / noise); nan without noise or lines.

        """
        m = self.kind == ('excited' if kind == 'residual' else kind)
        if kind == 'residual' and self.residual is None:
            m = np.zeros_like(m)
        if self.noise is None or not np.any(m):
            return np.full(len(self.outputs), np.nan)
        if kind == 'residual':
            return np.median(_db(self.residual[:, m], self.noise[:, m]), axis=1)
        # |Y|^2 of noise alone is exponentially distributed: its median is ln 2 of the mean;
        # divided out, lines of noise alone come out at 0 dB
        return np.median(_db(self.power[:, m], self.noise[:, m]), axis=1) - _db(np.log(2), 1.0)

    def summary(self) -> list[str]:
        """
        One line per output: odd and even distortion over the noise.

        Returns
        -------
        list of str
            e.g. 'dq_m/joint_2: odd lines +18.2 dB, even lines +0.4 dB above the noise
            (median of 90 and 92 lines, 0.33-60 Hz); excited lines +61.0 dB'.

        """
        odd, even, exc, res = (self.above_noise_db(k)
                               for k in ('odd', 'even', 'excited', 'residual'))
        n_odd, n_even = int(np.sum(self.kind == 'odd')), int(np.sum(self.kind == 'even'))
        band = f'{self.freq_hz[0]:.3g}-{self.freq_hz[-1]:.3g} Hz'
        out = []
        for i, name in enumerate(self.outputs):
            if self.noise is None:
                ex = self.power[i, self.kind == 'excited']
                lv = [_db(np.median(self.power[i, self.kind == k]), np.median(ex))
                      if np.any(self.kind == k) else np.nan for k in ('odd', 'even')]
                out.append(f'{name}: odd lines {_level(lv[0], n_odd)}, even lines '
                           f'{_level(lv[1], n_even)} '
                           f'relative to the excited lines (median; {band}; noise level '
                           f'unknown: one period)')
                continue
            text = (f'{name}: odd lines {_level(odd[i], n_odd)}, even lines '
                    f'{_level(even[i], n_even)} above the noise (median of {n_odd} and '
                    f'{n_even} lines, {band}); excited lines {exc[i]:+.1f} dB')
            if self.residual is not None:
                text += f', their nonlinear residual {res[i]:+.1f} dB'
            out.append(text)
        return out

    def to_dict(self) -> dict[str, Any]:
        """
        JSON-ready per-line levels.

        Returns
        -------
        dict
            freq_hz, kind, power and noise (per output, lists), outputs, units and the
            per-output medians odd_above_noise_db, even_above_noise_db.

        """
        return {'freq_hz': self.freq_hz.tolist(), 'kind': self.kind.tolist(),
                'power': self.power.tolist(),
                'noise': None if self.noise is None else self.noise.tolist(),
                'outputs': list(self.outputs), 'units': self.unit_list(),
                'residual': None if self.residual is None else self.residual.tolist(),
                'odd_above_noise_db': self.above_noise_db('odd').tolist(),
                'even_above_noise_db': self.above_noise_db('even').tolist()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> 'DistortionLines':
        """
        Read back :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            As written by :meth:`to_dict`.

        Returns
        -------
        DistortionLines
            The same levels.

        """
        return cls(np.asarray(d['freq_hz'], float), np.asarray(d['kind']),
                   np.asarray(d['power'], float),
                   None if d.get('noise') is None else np.asarray(d['noise'], float),
                   list(d['outputs']), d.get('units'),
                   None if d.get('residual') is None else np.asarray(d['residual'], float))


def distortion_lines(Y: np.ndarray | Sequence[np.ndarray], bins: np.ndarray,
                     excited_bins: np.ndarray, f0: float, outputs: Sequence[str], *,
                     units: Sequence[str] | None = None, noise: np.ndarray | None = None,
                     U: np.ndarray | Sequence[np.ndarray] | None = None) -> DistortionLines:
    """
    Per-line output levels of an odd multisine experiment.

    Parameters
    ----------
    Y : ndarray (n_q, n_bins, n_out), or a sequence of them (one per realisation)
        DFT of the output periods at ``bins`` (scaled 1/N).
    bins : ndarray of int
        The DFT lines of ``Y`` (1, 2, ... up to the top of the band).
    excited_bins : ndarray of int
        The lines the multisine excites.
    f0 : float
        Frequency of line 1 [Hz].
    outputs : sequence of str
        Output channel names.
    units : sequence of str, optional
        Unit of each output.
    noise : ndarray, optional
        Noise variance of the period mean (n_out,) or (n_out, n_bins), for records of one
        period; default: from the spread over periods (None with one period).
    U : like ``Y``, optional
        The input (one channel) at the same lines; with two or more realisations the
        residual Y - G U at the excited lines is computed (:attr:`DistortionLines.residual`).

    Returns
    -------
    DistortionLines
        Levels per line.

    """
    Ys = [np.asarray(Y)] if isinstance(Y, np.ndarray) else [np.asarray(y) for y in Y]
    bins = np.asarray(bins)
    power = np.mean([np.abs(y.mean(axis=0)) ** 2 for y in Ys], axis=0).T    # (n_out, lines)
    if noise is not None:
        var = np.broadcast_to(np.asarray(noise, float).reshape(power.shape[0], -1),
                              power.shape).copy()
    elif all(y.shape[0] >= 2 for y in Ys):
        var = np.mean([np.var(y, axis=0, ddof=1) / y.shape[0] for y in Ys], axis=0).T
        var = ndimage.median_filter(var, size=(1, NOISE_SMOOTH_LINES), mode='nearest')
        # the median of a chi^2 with 2 (n - 1) degrees of freedom is below its mean
        n = min(y.shape[0] for y in Ys)
        var = var / _chi2_median_ratio(2 * (n - 1))
    else:
        var = None
    exc = np.isin(bins, excited_bins)
    kind = np.where(exc, 'excited', np.where(bins % 2 == 1, 'odd', 'even'))
    residual = None
    if U is not None and len(Ys) >= 2:
        Us = [np.asarray(U)] if isinstance(U, np.ndarray) else [np.asarray(x) for x in U]
        ym = np.array([y.mean(axis=0) for y in Ys])              # (n_p, lines, n_out)
        um = np.array([x.mean(axis=0) for x in Us])[..., :1]    # (n_p, lines, 1)
        g = np.sum(ym * np.conj(um), axis=0) / np.maximum(np.sum(np.abs(um) ** 2, axis=0),
                                                          1e-300)
        # the residual of a least-squares fit over n_p realisations keeps (n_p - 1) / n_p
        # of the scatter
        r = np.mean(np.abs(ym - g * um) ** 2, axis=0) * len(Ys) / (len(Ys) - 1)
        residual = np.where(exc[None, :], r.T, np.nan)
    return DistortionLines(bins * float(f0), kind, power, var, list(outputs),
                           None if units is None else list(units), residual)


def _chi2_median_ratio(dof: int) -> float:
    """Median over mean of a chi^2 variable with ``dof`` degrees of freedom."""
    return float(stats.chi2.median(dof) / dof)


def _level(db: float, n_lines: int) -> str:
    """Format a median level for the summary line: 'none' where no line of that kind is free."""
    return f'{db:+.1f} dB' if n_lines else 'none'
