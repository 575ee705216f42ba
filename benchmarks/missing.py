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
Records with gaps: the missing samples estimated with the FRF, beside the record without gaps.

- LPM (non-periodic): one frame of 32768 samples of :func:`benchmarks.lpm.record` (3 white
  inputs through a 3x3 filter matrix, 1 % output noise) whose outputs lose 5 % of their
  samples in 10 gaps; :class:`~frf_ident.core.estimation.lpm_frames.LpmAccumulator` with the
  missing samples as unknowns (:mod:`frf_ident.core.estimation.missing_lpm`) beside the plain
  LPM of the complete frame: wall time, and the error to the filters' exact FRF. Then the
  cost against the number of missing samples in the frame (it grows with their cube: the
  M x M normal matrix is factored and inverted).
- multisine (periodic): :func:`benchmarks.__main__.periodic_multisine_run`, 64 s without
  descriptors, 5 % of every period lost in one gap, estimated
  (:func:`~frf_ident.core.estimation.described.estimate_recording`) beside the record
  without gaps: wall time, periods used, difference and standard deviation.

Run: ``python -m benchmarks missing``.
"""
from __future__ import annotations

import copy
import time

from benchmarks.lpm import record
from frf_ident.core.estimation.lpm_frames import LpmAccumulator
import numpy as np
from scipy import signal

FRAME = 32768
#: (first sample, length) of the 10 gaps of the LPM frame: 1640 samples, 5.0 %
GAPS = [(1500 + k * 3000, 164) for k in range(10)]


def _gone(n: int, gaps) -> np.ndarray:
    m = np.zeros(n, bool)
    for a, k in gaps:
        m[a:a + k] = True
    return m


def _exact(freq: np.ndarray) -> np.ndarray:
    """Return the exact FRF of :func:`benchmarks.lpm.record`'s filters (3, 3, n_freq)."""
    G = np.empty((3, 3, freq.size), complex)
    for i in range(3):
        for j in range(3):
            b, a = signal.butter(2, 0.05 + 0.1 * i + 0.05 * j)
            G[i, j] = signal.freqz(b, a, worN=freq, fs=1.0)[1] / (1 + abs(i - j))
    return G


def _lpm(y: np.ndarray, u: np.ndarray) -> tuple[float, object]:
    acc = LpmAccumulator(1.0, min(FRAME, y.shape[0]))
    t0 = time.perf_counter()
    acc.add(y, u)
    res = acc.result()
    return time.perf_counter() - t0, res


def lpm_rows() -> list[tuple[str, str, str, str]]:
    """Time the missing-data LPM of one frame beside the plain LPM of the complete frame."""
    y, u = record(FRAME)
    gone = _gone(FRAME, GAPS)
    yg = np.where(gone[:, None], np.nan, y)
    _lpm(np.where(_gone(4096, [(2000, 50)])[:, None], np.nan, y[:4096]), u[:4096])  # compile
    t_plain, plain = _lpm(y, u)
    t_miss, miss = _lpm(yg, u)
    f = plain.frf.freq_hz
    band = f < 0.025                            # below the lowest filter's cut-off
    G0 = _exact(f[band])

    def err(res):
        return np.median(np.abs(res.frf.response[..., band] / G0 - 1))
    sd = np.median(np.sqrt(miss.frf.noise_variance / plain.frf.noise_variance)[..., band])
    rows = [(f'LPM 3x3, one frame of {FRAME} samples, {gone.sum()} outputs samples missing '
             f'({100 * gone.mean():.1f} %, {len(GAPS)} gaps): time',
             f'{t_miss:.2f} s', f'complete frame {t_plain:.2f} s',
             f'{t_miss / t_plain:.1f}x'),
            ('  median |G - G_exact| / |G_exact| (below 0.025 fs)',
             f'{100 * err(miss):.3f} %', f'{100 * err(plain):.3f} %', ''),
            ('  reported sd / that of the complete frame (median)', f'{sd:.3f}', '', '')]
    for m in (1000, 2000, 4000):
        gaps = [(1000 + k * (FRAME - 2000) // (m // 100), 100) for k in range(m // 100)]
        t, _ = _lpm(np.where(_gone(FRAME, gaps)[:, None], np.nan, y), u)
        rows.append((f'  {m} missing samples in the frame (cost ~ M^3)', f'{t:.2f} s',
                     f'complete frame {t_plain:.2f} s', f'{t / t_plain:.1f}x'))
    return rows


def multisine_rows() -> list[tuple[str, str, str, str]]:
    """Time the detected multisine of a record with a gap in every period beside without."""
    from benchmarks.__main__ import periodic_multisine_run
    from frf_ident.core.estimation.described import estimate_recording
    from frf_ident.core.excitation.multisine import design_odd_multisine
    rec = periodic_multisine_run(64.0)
    n_per = design_odd_multisine(2.0, 60.0, bound=0.01, resolution_hz=0.5,
                                 fs=1000.0).period_samples(1000.0)
    gap = copy.deepcopy(rec)
    rng = np.random.default_rng(1)
    k = n_per // 20                                             # 5 % of every period
    for q in range(rec.t.size // n_per):
        a = q * n_per + int(rng.integers(0, n_per - k - 10))
        for x in (gap.velocity, gap.effort, gap.position, gap.reference):
            x[a:a + k] = np.nan
    lost = np.isnan(gap.velocity[:, 0]).mean()
    estimate_recording(rec)                                     # warm up
    t0 = time.perf_counter()
    e0 = estimate_recording(rec)['detected/joint_2']
    t_clean = time.perf_counter() - t0
    t0 = time.perf_counter()
    e1 = estimate_recording(gap)['detected/joint_2']
    t_gap = time.perf_counter() - t0
    j = 1                                                       # the driven channel
    db = np.median(np.abs(20 * np.log10(np.abs(e1.response[j] / e0.response[j]))))
    sd = np.median(np.sqrt(e1.noise_variance[j] / e0.noise_variance[j]))
    return [(f'multisine, {rec.t.size // n_per} periods of {n_per / 1000:g} s, '
             f'{100 * lost:.1f} % lost (a gap in every period): time', f'{t_gap:.2f} s',
             f'without gaps {t_clean:.2f} s', f'{t_gap / t_clean:.1f}x'),
            ('  steady periods used (transient test on the filled periods; before issue 55: none)',
             f'{e1.meta["periods"]}', f'without gaps {e0.meta["periods"]}', ''),
            ('  driven channel: median |P - P_without gaps|, sd / sd without gaps',
             f'{db:.4f} dB, {sd:.3f}', '', '')]


def rows() -> list[tuple[str, str, str, str]]:
    """Return the LPM and the multisine measurements (the bench section)."""
    return lpm_rows() + multisine_rows()
