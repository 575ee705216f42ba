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
Scan the residual spectrum above the analysis band for resonances the model lacks.

Above the analysis band (:mod:`..band`) the extended model's inverse-dynamics residual should
be noise: its Welch PSD (segments of RESONANCE_SEGMENT_S, Hann, half overlap) smooth. A
resonance the model lacks (the drive's flexibility, a second link mode) stands there as a
peak over the residual's local noise floor, the running median over RESONANCE_FLOOR_LINES
lines. The threshold on PSD / floor is the chi-square tail of a Welch line (its equivalent
degrees of freedom, Percival & Walden eq. 292b for a Hann window at half overlap) over the
median of that distribution (its degrees of freedom lowered for the noise of the median
itself), for a false-alarm probability RESONANCE_FALSE_ALARM per axis
over all lines scanned (Bonferroni). A peak above it is reported as ``unexplained`` with its
band: the run of lines around it that stay above the threshold, plus one line each side
(a resonance's skirt above noise, not only its half-power width). A peak whose half-power
width is at most RESONANCE_MIN_WIDTH_LINES lines is as narrow as the window makes a sine: a
``line`` (a periodic disturbance: mains hum, a rotating part), else a ``resonance`` (a mode
of damping ratio zeta is 2 zeta f wide).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import signal, stats
from scipy.ndimage import median_filter

from ..records import Signature, Unexplained
from ..thresholds import (RESONANCE_FALSE_ALARM, RESONANCE_FLOOR_LINES, RESONANCE_MAX,
                          RESONANCE_MIN_WIDTH_LINES, RESONANCE_SEGMENT_S, RESONANCE_TOP)

__all__ = ['peak_threshold', 'resonances_above', 'scan_spectrum']


def peak_threshold(n_segments: int, n_lines: int,
                   alpha: float = RESONANCE_FALSE_ALARM) -> float:
    """
    Return the PSD / local-median ratio noise alone exceeds with probability ``alpha``.

    Parameters
    ----------
    n_segments : int
        Welch segments averaged (Hann window, half overlap).
    n_lines : int
        Lines scanned (the tail probability per line is alpha / n_lines).
    alpha : float
        False-alarm probability of the whole scan.

    Returns
    -------
    float
        The threshold on PSD over its running median.

    """
    # Hann at 50 % overlap: neighbouring segments correlate by rho = 0.167 in power
    dof = 2.0 * n_segments / (1.0 + 2.0 * 0.167 ** 2 * (n_segments - 1) / max(n_segments, 1))
    # the running median is itself noisy: var(median) ~ (pi / 2) var / m over m independent
    # lines, and a Hann window's neighbouring lines share about a third of their information
    dof /= 1.0 + 0.5 * math.pi / (RESONANCE_FLOOR_LINES / 1.5)
    return float(stats.chi2.isf(alpha / max(n_lines, 1), dof) / stats.chi2.median(dof))


def scan_spectrum(x: np.ndarray, fs: float, f_lo: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """
    Return the lines above ``f_lo``, the residual's PSD there, its local floor and the threshold.

    Parameters
    ----------
    x : ndarray, shape (N,)
        One axis' residual (wide band).
    fs : float
        Sample rate [Hz].
    f_lo : float
        Lowest frequency scanned [Hz] (the analysis band's edge).

    Returns
    -------
    f, psd, floor : ndarray
        The lines in (f_lo, RESONANCE_TOP fs] [Hz] and PSD and floor there; empty when the
        record is too short for two segments or the range holds too few lines.
    threshold : float
        :func:`peak_threshold` for those lines (inf when empty).

    """
    x = np.nan_to_num(np.asarray(x, float))
    nper = int(round(RESONANCE_SEGMENT_S * fs))
    if x.size < 2 * nper:
        nper = x.size // 2
    f, p = signal.welch(x, fs=fs, nperseg=nper, noverlap=nper // 2, window='hann')
    floor = median_filter(p, size=RESONANCE_FLOOR_LINES, mode='nearest')
    sel = (f > f_lo) & (f <= RESONANCE_TOP * fs)
    if nper < 8 or sel.sum() < RESONANCE_FLOOR_LINES // 2:
        e = np.zeros(0)
        return e, e, e, math.inf
    n_seg = 1 + (x.size - nper) // (nper - nper // 2)
    return f[sel], p[sel], floor[sel], peak_threshold(n_seg, int(sel.sum()))


def half_power_width(f: np.ndarray, excess: np.ndarray, k: int) -> float:
    """Return the width [Hz] over which ``excess`` stays above half its value at line k."""
    half = 0.5 * excess[k]
    lo, hi = k, k
    while lo > 0 and excess[lo - 1] >= half:
        lo -= 1
    while hi < f.size - 1 and excess[hi + 1] >= half:
        hi += 1
    df = f[1] - f[0]
    left = f[lo] - (df * (excess[lo] - half) / (excess[lo] - excess[lo - 1]) if lo > 0 else 0.0)
    right = f[hi] + (df * (excess[hi] - half) / (excess[hi] - excess[hi + 1])
                     if hi < f.size - 1 else 0.0)
    return float(right - left)


def resonances_above(f_res: np.ndarray, fs: float, fc: float, names: list[str]
                     ) -> list[Unexplained]:
    """
    Return the ``unexplained`` entries of resonances in the residual above the analysis band.

    Parameters
    ----------
    f_res : ndarray, shape (N, n)
        The extended model's inverse-dynamics residual, not low-passed.
    fs : float
        Sample rate [Hz].
    fc : float
        The analysis band's edge [Hz]: the scan starts above it.
    names : list of str
        The axes' names.

    Returns
    -------
    list of Unexplained
        Per peak above the threshold (at most RESONANCE_MAX per axis, strongest first):
        ``axis``, ``kind`` 'resonance above the analysis band' or 'line above the analysis
        band', ``signature`` with ``band_hz`` [f1, f2], ``peak_hz``,
        ``half_power_width_hz``, ``peak_over_floor`` (PSD over its local floor),
        ``threshold`` and ``false_alarm`` (of the scan, per axis).

    """
    out = []
    for i, name in enumerate(names):
        f, p, floor, thr = scan_spectrum(f_res[:, i], fs, fc)
        ratio = p / np.maximum(floor, 1e-300)
        free = np.ones(f.size, bool)
        for _ in range(RESONANCE_MAX):
            k = int(np.argmax(np.where(free, ratio, 0.0))) if f.size else 0
            if not f.size or not free[k] or ratio[k] <= thr:
                break
            lo, hi = k, k
            while lo > 0 and free[lo - 1] and ratio[lo - 1] > thr:
                lo -= 1
            while hi < f.size - 1 and free[hi + 1] and ratio[hi + 1] > thr:
                hi += 1
            lo, hi = max(lo - 1, 0), min(hi + 1, f.size - 1)
            free[lo:hi + 1] = False
            width = half_power_width(f, p - floor, k)
            kind = ('resonance' if width > RESONANCE_MIN_WIDTH_LINES * (f[1] - f[0])
                    else 'line')
            sig = Signature(band_hz=[round(float(f[lo]), 2), round(float(f[hi]), 2)],
                            peak_hz=round(float(f[k]), 2),
                            half_power_width_hz=round(width, 2),
                            peak_over_floor=round(float(ratio[k]), 1), threshold=round(thr, 1),
                            false_alarm=RESONANCE_FALSE_ALARM)
            out.append(Unexplained(name, sig, kind=f'{kind} above the analysis band'))
    return out
