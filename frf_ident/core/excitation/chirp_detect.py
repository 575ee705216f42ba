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
Detect an exponential chirp f(t) = exp(a0 t + a1) (eq. 16) in a measured signal.

:func:`detect_chirp` takes the instantaneous frequency from zero crossings (with hysteresis)
and a robust log-linear fit (:mod:`frf_ident.core.excitation.sweep_law`); the band
[f_low, f_high] and the active interval [t0, t1] come from a least-squares on-/offset fit of
the waveform. A sweep that follows another law better is refused with what it is.
"""
from __future__ import annotations

from frf_ident.core.excitation.detect_input import prepare_signal
from frf_ident.core.excitation.detection_results import ChirpDetection
from frf_ident.core.excitation.sweep_law import (fit_sweep_laws, half_cycles, LAW_MARGIN,
                                                 robust_law_fit)
from frf_ident.errors import EstimationError
import numpy as np

__all__ = ['detect_chirp']


def _onset(x: np.ndarray, model: np.ndarray, lo: int, hi: int, fit: slice,
           valid: np.ndarray) -> int:
    """
    Index k in [lo, hi] minimising sum_{n<k} x^2 + sum_{n>=k} (x - A cos - B sin)^2.

    ``model`` is (2, N) cos/sin of the fitted chirp phase; A, B are least-squares fitted on
    ``fit`` (whole cycles inside the chirp). Matching the whole waveform makes the onset
    independent of the chirp's starting phase and robust to noise. Missing samples
    (``valid`` false) count in neither sum nor the fit.
    """
    w = valid[fit]
    coef, *_ = np.linalg.lstsq(model[:, fit][:, w].T, x[fit][w], rcond=None)
    m = coef @ model[:, lo:hi]
    seg, v = x[lo:hi], valid[lo:hi]
    off = np.concatenate([[0.0], np.cumsum(seg ** 2 * v)])          # x^2 before k
    on = np.concatenate([[0.0], np.cumsum((seg - m) ** 2 * v)])     # residual from k on
    cost = off + (on[-1] - on)
    return lo + int(np.argmin(cost))


def _cycles_back(phase: np.ndarray, valid: np.ndarray, i: int, cycles: float) -> int:
    """
    Return the index ``cycles`` cycles of present samples before ``i``.

    The phase advance of the missing samples is not counted, so a search window reaches
    across a gap to as many cycles of data as without one. 0 when the data end first.
    """
    step = np.abs(np.diff(phase[:i + 1])) * valid[1:i + 1]
    have = np.cumsum(step[::-1])
    k = int(np.searchsorted(have, 2 * np.pi * cycles))
    return max(0, i - k - 1)


def _chirp_extent(x: np.ndarray, fs: float, a0: float, a1: float, t_first: float,
                  t_last: float, valid: np.ndarray) -> tuple[int, int]:
    """Start index and last index of the chirp around the fitted half cycles [t_first, t_last]."""
    n = x.size
    t = np.arange(n) / fs
    ph = 2 * np.pi * np.exp(a1) * np.expm1(a0 * t) / a0 if a0 != 0 else 2 * np.pi * np.exp(a1) * t
    model = np.stack([np.cos(ph), np.sin(ph)])
    f_first, f_last = np.exp(a0 * np.array([t_first, t_last]) + a1)
    p_first, p_last = int(np.ceil(fs / f_first)), int(np.ceil(fs / f_last))
    i_first = min(max(int(np.floor(t_first * fs)), 0), n - 1)
    i_last = min(max(int(np.ceil(t_last * fs)), 0), n - 1)
    i0 = _onset(x, model, _cycles_back(ph, valid, i_first, 2.0), min(n, i_first + p_first),
                slice(i_first, min(n, i_first + 2 * p_first)), valid)
    j = n - 1 - i_last
    rev = _onset(x[::-1], model[:, ::-1], _cycles_back(ph[::-1], valid[::-1], j, 2.0),
                 min(n, j + p_last), slice(j, min(n, j + 2 * p_last)), valid[::-1])
    return i0, n - rev


def detect_chirp(x: np.ndarray, fs: float, *, min_ratio: float = 1.5,
                 max_scatter: float = 0.08, min_inliers: float = 0.7,
                 hysteresis: float = 0.3) -> ChirpDetection:
    """
    Find an exponential chirp f(t) = exp(a0 t + a1) (eq. 16) in ``x`` sampled at ``fs``.

    Half cycles between zero crossings (hysteresis ``hysteresis`` times the 99th percentile of
    |x|) give f = 1 / (2 duration) at their mid times; a robust fit of ln f over t gives a0, a1.
    t0 and t1 are the on- and offset of the fitted waveform A cos(phase) + B sin(phase)
    (least squares, searched two periods outside the first and last fitted half cycles),
    f_low = f(t0), f_high = f(t1). It is a chirp when at least ``min_inliers`` of
    the half cycles follow the fit with relative scatter below ``max_scatter`` and the band
    spans a ratio of at least ``min_ratio``.

    Raises :class:`EstimationError` (one line) otherwise.

    Parameters
    ----------
    x : ndarray, shape (N,) or (N, n)
        The signal; of a 2-D signal the channel with the largest RMS is analysed. NaN marks
        missing samples.
    fs : float
        Sample rate [Hz].
    min_ratio : float, optional
        Smallest frequency ratio the fitted half cycles must span.
    max_scatter : float, optional
        Largest relative scatter of the half-cycle frequencies around the fit.
    min_inliers : float, optional
        Smallest share of half cycles that must follow the fit.
    hysteresis : float, optional
        Zero-crossing hysteresis as a share of the 99th percentile of |x|.

    Returns
    -------
    ChirpDetection
        Band, active interval, eq. 16 coefficients and quality of the fit.

    """
    x, channel, valid = prepare_signal(x, fs)
    h = hysteresis * float(np.quantile(np.abs(x), 0.99))
    if h <= 0:
        raise EstimationError('no chirp: the signal is constant')
    t_mid, f = half_cycles(x, fs, h)
    if t_mid.size < 10:
        raise EstimationError(f'no chirp: only {t_mid.size} half cycles above the '
                              f'hysteresis level {h:.3g}')
    best, other = fit_sweep_laws(t_mid, f)
    if best.law != 'exponential' and best.scatter < LAW_MARGIN * other.scatter \
            and best.inliers >= min_inliers:
        raise EstimationError(
            f'a {best.describe()}, not an exponential chirp f(t) = exp(a0 t + a1) (eq. 16; '
            f'that law leaves {100 * other.scatter:.2g} % frequency scatter): the chirp '
            f'estimator needs the exponential law')
    a0, a1, keep, scatter = robust_law_fit(t_mid, f, 'exponential')
    frac = float(keep.mean())
    tk = t_mid[keep]
    ratio = float(np.exp(abs(a0) * (tk[-1] - tk[0]))) if tk.size > 1 else 1.0
    if frac < min_inliers or scatter > max_scatter or ratio < min_ratio:
        raise EstimationError(
            f'no exponential chirp: {100 * frac:.0f} % of {t_mid.size} half cycles follow '
            f'ln f = a0 t + a1 with {100 * scatter:.2g} % scatter over a frequency ratio '
            f'{ratio:.3g} (need {100 * min_inliers:.0f} %, < {100 * max_scatter:.2g} %, '
            f'>= {min_ratio:g})')
    i0, i1 = _chirp_extent(x, fs, a0, a1, float(tk[0]), float(tk[-1]), valid)
    t0, t1 = i0 / fs, (i1 - 1) / fs
    return ChirpDetection(float(fs), float(np.exp(a0 * t0 + a1)), float(np.exp(a0 * t1 + a1)),
                          float(t0), float(t1), a0, a1, int(keep.sum()), scatter, channel)
