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
The chirp's spectra at its analysis frequencies (Saupe & Knoblach 2015, Section 5.1).

- :func:`chirp_excerpt_dft` — Sec. 5.1 processing of one analysis frequency: an excerpt
  around the time the chirp passes it, decimated, windowed, one DFT line
- :func:`chirp_analysis_frequencies` — the frequencies whose excerpts fit in the record
- :func:`chirp_spectra` — Sec. 5.1 for all analysis frequencies and channels

Used by the chirp iteration (:mod:`.procedures`, which must know the torque's spectrum to
plan the next reference) and by the estimators (:mod:`frf_ident.core.estimation`).
"""
from __future__ import annotations

import functools
import math

from frf_ident.errors import EstimationError
import numba
import numpy as np
from scipy import signal

__all__ = ['chirp_analysis_frequencies', 'chirp_excerpt_dft', 'chirp_spectra',
           'decimation_filter']


@functools.lru_cache(maxsize=None)
def decimation_filter(q: int) -> np.ndarray:
    """
    Return the FIR low-pass that :func:`scipy.signal.resample_poly` designs for down = q.

    The same filter scipy designs by default (Kaiser window, beta 5, cut-off 1/q of the
    Nyquist frequency, 20 q + 1 taps), designed once per q: the chirp processing decimates
    thousands of excerpts with a few factors.

    Parameters
    ----------
    q : int
        Decimation factor (> 1).

    Returns
    -------
    ndarray
        The filter taps (read-only).

    """
    h = signal.firwin(2 * 10 * q + 1, 1.0 / q, window=('kaiser', 5.0))
    h.flags.writeable = False
    return h


def _filter_bank(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the decimation filters of the factors ``q``, concatenated, and where each starts.

    :func:`decimation_filter` of every factor > 1 once, and per element of ``q`` the index of
    its taps in the concatenation (0 for q = 1, which filters nothing).
    """
    bank, at = [np.zeros(0)], {}
    n = 0
    for f in np.unique(q[q > 1]):
        at[int(f)] = n
        bank.append(decimation_filter(int(f)))
        n += bank[-1].size
    return np.concatenate(bank), np.array([at.get(int(f), 0) for f in q], dtype=np.int64)


@numba.njit(cache=True)
def _excerpt_weights(i0, i1, q, f_x, t_center, t_first, fs, bank, start):
    """
    Return the Sec. 5.1 DFT weights of the excerpts x[i0[k]:i1[k]] at f_x[k], all k at once.

    The excerpt's mean removed, the zero-phase FIR of ``bank[start[k]:]`` (2 L + 1 taps,
    L = 10 q) applied with zeros outside the excerpt and every q-th sample kept, as
    ``scipy.signal.resample_poly(seg, 1, q, window=h)`` does (output m at input m q), then a
    periodic Hann window and the DFT at exactly f_x, over the sum of the window. All of it is
    linear in the excerpt, so it is one weight per input sample, c_j = sum_m w_m
    exp(-i 2 pi f_x t_m) h(m q - j): ``c[at[k]:at[k + 1]]`` for excerpt k, with the sum of its
    weights and of its window (:func:`_apply_weights` applies them to every channel).
    """
    n = f_x.size
    at = np.zeros(n + 1, dtype=np.int64)
    for k in range(n):
        at[k + 1] = at[k] + max(i1[k] - i0[k], 0)
    c = np.zeros(at[n], dtype=np.complex128)
    c_sum = np.zeros(n, dtype=np.complex128)
    w_sums = np.zeros(n)
    for k in range(n):
        a, qq = i0[k], q[k]
        n_in = i1[k] - a
        if n_in <= 0:
            continue
        b = at[k]
        n_out = (n_in + qq - 1) // qq
        half = 10 * qq if qq > 1 else 0
        h0 = start[k] + half
        w_sum = 0.0
        for m in range(n_out):
            w = 1.0 if n_out == 1 else 0.5 - 0.5 * math.cos(2.0 * math.pi * m / n_out)
            w_sum += w
            t = t_first + a / fs + m * (qq / fs)
            kern = w * np.exp(-2j * np.pi * f_x[k] * (t - t_center[k]))
            centre = m * qq
            if qq == 1:
                c[b + centre] += kern
                continue
            for d in range(max(-half, centre - n_in + 1), min(half, centre) + 1):
                c[b + centre - d] += kern * bank[h0 + d]
        acc = 0j
        for j in range(n_in):
            acc += c[b + j]
        c_sum[k] = acc
        w_sums[k] = w_sum
    return c, at, c_sum, w_sums


@numba.njit(cache=True)
def _apply_weights(x, i0, c, at, c_sum, w_sums, out):
    """
    Fill out[k] with the DFT of the excerpt x[i0[k]:...] by :func:`_excerpt_weights`' weights.

    NaN for a channel whose excerpt holds a non-finite sample, and for an empty excerpt.
    """
    n_ch = x.shape[1]
    for k in range(at.size - 1):
        a, b = i0[k], at[k]
        n_in = at[k + 1] - b
        if n_in <= 0:
            for ch in range(n_ch):
                out[k, ch] = np.nan + 0j
            continue
        for ch in range(n_ch):
            mean = 0.0
            acc = 0j
            for j in range(n_in):
                mean += x[a + j, ch]
                acc += c[b + j] * x[a + j, ch]
            # a missing sample makes both sums NaN: the channel loses this frequency only
            out[k, ch] = (acc - mean / n_in * c_sum[k]) / w_sums[k]


#: weights of recent chirp analyses, by their excerpts (:func:`chirp_spectra`): the diagnosis
#: analyses the same chirp segments of every simulated model, and forming the weights was
#: half of the analysis
_WEIGHTS: dict[tuple, tuple] = {}
_WEIGHTS_KEPT = 16


def _weights(i0, i1, q, f, tc, t_first: float, fs: float) -> tuple:
    """Return :func:`_excerpt_weights` of these excerpts, kept for the next call alike."""
    key = (i0.tobytes(), i1.tobytes(), q.tobytes(), f.tobytes(), tc.tobytes(), t_first, fs)
    if key not in _WEIGHTS:
        bank, start = _filter_bank(q)
        while len(_WEIGHTS) >= _WEIGHTS_KEPT:
            del _WEIGHTS[next(iter(_WEIGHTS))]
        _WEIGHTS[key] = _excerpt_weights(i0, i1, q, f, tc, t_first, fs, bank, start)
    return _WEIGHTS[key]


def chirp_excerpt_dft(x: np.ndarray, fs: float, f_x: float, t_center: float, *,
                      n_periods: float = 4.0, samples_per_period: float = 10.0,
                      t_first: float = 0.0) -> np.ndarray:
    """
    One analysis frequency of the Sec. 5.1 chirp processing.

    Takes the excerpt of ``n_periods`` periods of f_x centred on the time ``t_center`` at which
    f_x is excited, subtracts its mean, low-pass filters and downsamples it to about
    ``samples_per_period`` samples per period (polyphase FIR, zero phase: the filter and
    alignment of :func:`scipy.signal.resample_poly` with :func:`decimation_filter`), applies a
    Hann window and evaluates the DFT at exactly f_x.

    ``x`` : (N, ...) samples at rate fs, the first at time ``t_first``. Returns (...) complex,
    NaN for a channel whose excerpt holds a missing (NaN) sample: a gap removes that frequency
    of that channel only.
    """
    return chirp_spectra(x, fs, np.array([f_x], dtype=float), np.array([t_center], dtype=float),
                         t_first=t_first, n_periods=n_periods,
                         samples_per_period=samples_per_period)[0]


def chirp_analysis_frequencies(f_candidates: np.ndarray, t_of_f, t_start: float,
                               t_end: float, n_periods: float = 4.0) -> np.ndarray:
    """Analysis frequencies whose excerpt of ``n_periods`` periods lies inside [t_start, t_end]."""
    f = np.asarray(f_candidates, dtype=float)
    tc = t_of_f(f)
    half = 0.5 * n_periods / f
    return f[(tc - half >= t_start) & (tc + half <= t_end)]


def chirp_spectra(x: np.ndarray, fs: float, freqs: np.ndarray, t_centers: np.ndarray, *,
                  t_first: float = 0.0, n_periods: float = 4.0,
                  samples_per_period: float = 10.0) -> np.ndarray:
    """
    Return the Sec. 5.1 spectra of all channels at the chirp's analysis frequencies.

    :func:`chirp_excerpt_dft` at every analysis frequency, compiled over all of them at once
    (a chirp has hundreds of analysis frequencies; the diagnosis processes one chirp per
    simulated model).

    Parameters
    ----------
    x : ndarray, shape (N, ...)
        Samples at rate ``fs``, the first at time ``t_first``.
    fs : float
        Sample rate [Hz].
    freqs : ndarray, shape (n_freq,)
        Analysis frequencies [Hz].
    t_centers : ndarray, shape (n_freq,)
        Times [s] at which the chirp excites each of them.
    t_first : float
        Time of the first sample [s].
    n_periods : float
        Length of each excerpt in periods of its frequency.
    samples_per_period : float
        Samples per period the excerpt is decimated to.

    Returns
    -------
    ndarray, shape (n_freq, ...)
        Complex spectra; NaN for a channel whose excerpt holds a missing sample.

    Raises
    ------
    EstimationError
        When an excerpt reaches outside the record.

    """
    x = np.asarray(x, dtype=float)
    f = np.asarray(freqs, dtype=float).ravel()
    tc = np.asarray(t_centers, dtype=float).ravel()
    if f.size == 0:
        return np.zeros((0,) + x.shape[1:], dtype=complex)
    half = 0.5 * n_periods / f
    i0 = np.round((tc - half - t_first) * fs).astype(np.int64)
    i1 = np.round((tc + half - t_first) * fs).astype(np.int64)
    outside = (i0 < 0) | (i1 > x.shape[0])
    if outside.any():
        k = int(np.argmax(outside))
        raise EstimationError(f'excerpt for f_x={f[k]:g} Hz around t={tc[k]:g} s is outside '
                              f'the record [{t_first:g}, {t_first + x.shape[0] / fs:g}] s')
    q = np.maximum(1, np.floor(fs / (samples_per_period * f))).astype(np.int64)
    c, at, c_sum, w_sums = _weights(i0, i1, q, f, tc, float(t_first), float(fs))
    flat = np.ascontiguousarray(x.reshape(x.shape[0], -1))
    out = np.empty((f.size, flat.shape[1]), dtype=complex)
    _apply_weights(flat, i0, c, at, c_sum, w_sums, out)
    return out.reshape((f.size,) + x.shape[1:])
