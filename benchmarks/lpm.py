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
The LPM's speed on a 3x3 record of 10^6 samples beside the obvious per-line least squares.

The record: three white-noise inputs through a 3x3 matrix of low-order filters, 1 % output
noise, started from rest (transient in the record). The LPM (:func:`lpm_lines`) solves all
5 x 10^5 lines of the record's DFT; the naive one builds each window's regressor and calls
``np.linalg.lstsq`` in a Python loop over lines, timed on NAIVE_LINES lines spread over the
spectrum and scaled to all lines (the whole loop would take minutes); both give G on those
lines, the largest difference is printed.

Run: ``python -m benchmarks lpm``.
"""
from __future__ import annotations

import time

from frf_ident.core.estimation.lpm import default_half_width, DEFAULT_ORDER, lpm_lines
from frf_ident.core.estimation.lpm_frames import lpm_frf
import numpy as np
from scipy import signal

N_SAMPLES = 10 ** 6
#: lines the naive loop is timed on (spread over the spectrum)
NAIVE_LINES = 2000


def record(n: int = N_SAMPLES) -> tuple[np.ndarray, np.ndarray]:
    """Return (y, u), each (n, 3): a 3x3 filter matrix driven by white noise, 1 % noise."""
    rng = np.random.default_rng(0)
    u = rng.standard_normal((n, 3))
    y = np.zeros((n, 3))
    for i in range(3):
        for j in range(3):
            b, a = signal.butter(2, 0.05 + 0.1 * i + 0.05 * j)
            y[:, i] += signal.lfilter(b, a, u[:, j]) / (1 + abs(i - j))
    return y + 0.01 * np.std(y, axis=0) * rng.standard_normal(y.shape), u


def naive_lines(Y: np.ndarray, U: np.ndarray, lines: np.ndarray, order: int = DEFAULT_ORDER,
                half_width: int | None = None) -> np.ndarray:
    """Return G (n_out, n_in, len(lines)) by np.linalg.lstsq per line, written plainly."""
    n_in = U.shape[0]
    n = default_half_width(n_in, order) if half_width is None else half_width
    out = np.empty((Y.shape[0], n_in, len(lines)), dtype=complex)
    for c, k in enumerate(lines):
        start = min(max(k - n, 0), Y.shape[1] - 2 * n - 1)
        idx = np.arange(start, start + 2 * n + 1)
        r = (idx - k) / n
        cols = [U[m, idx] * r ** s for m in range(n_in) for s in range(order + 1)]
        cols += [r ** s + 0j for s in range(order + 1)]
        theta = np.linalg.lstsq(np.array(cols).T, Y[:, idx].T, rcond=None)[0]
        out[:, :, c] = theta[0:n_in * (order + 1):order + 1].T
    return out


def rows() -> list[tuple[str, str, str, str]]:
    """Return the bench rows: LPM vs naive per-line lstsq, and the whole lpm_frf."""
    y, u = record()
    Y = np.fft.rfft(y, axis=0).T[:, 1:] / np.sqrt(N_SAMPLES)
    U = np.fft.rfft(u, axis=0).T[:, 1:] / np.sqrt(N_SAMPLES)
    lpm_lines(Y[:, :200], U[:, :200])                     # compile (numba cache)
    t0 = time.perf_counter()
    fit = lpm_lines(Y, U)
    t_lpm = time.perf_counter() - t0
    n_lines = Y.shape[1]
    pick = np.unique(np.linspace(0, n_lines - 1, NAIVE_LINES).astype(int))
    t0 = time.perf_counter()
    g_naive = naive_lines(Y, U, pick)
    t_naive = (time.perf_counter() - t0) / pick.size * n_lines
    diff = np.max(np.abs(g_naive - fit.G[:, :, pick]) / np.abs(fit.G[:, :, pick]).max())
    t0 = time.perf_counter()
    lpm_frf(y, u, 1000.0, frame_samples=N_SAMPLES)
    t_all = time.perf_counter() - t0
    return [
        (f'LPM 3x3, {n_lines:,} lines (10^6 samples)', f'{t_lpm:.2f} s',
         f'{t_naive:.1f} s naive lstsq/line*', f'{t_naive / t_lpm:.0f}x'),
        ('  max |G_lpm - G_naive| / max |G|', f'{diff:.1e}', f'on {pick.size} lines', ''),
        ('lpm_frf 3x3 10^6 samples (DFT, LPM, Welch H1)', f'{t_all:.2f} s', '', ''),
    ]
