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
The robust LPM with several periods: noise from the periods, nonlinear variance from lines.

A Wiener system (Chebyshev filter, then y = x + 0.2 x^3) driven by odd random-phase
multisines, 4 steady-state periods (one transient period discarded), white output noise of
known level. The truth is Monte-Carlo over 30 realisations (with and without noise) and the
analytic noise variance sigma^2 / (P |U_k|^2) of the period mean.
"""
from frf_ident.core.estimation.lpm import robust_lpm
import numpy as np
from scipy import signal

N, PERIODS, SIGMA = 1024, 4, 0.1
LINES = np.arange(1, 400, 2)
B, A = signal.cheby1(2, 3, 0.3)


def _run(seed, noise):
    rng = np.random.default_rng(seed)
    spec = np.zeros(N // 2 + 1, dtype=complex)
    spec[LINES] = np.exp(2j * np.pi * rng.random(LINES.size))
    u = np.tile(np.fft.irfft(spec, N), PERIODS + 1)
    u /= np.std(u)
    x = signal.lfilter(B, A, u)
    y = (x + 0.2 * x ** 3)[N:]
    if noise:
        y = y + SIGMA * np.random.default_rng(1000 + seed).standard_normal(y.size)
    return u[N:], y


def test_noise_and_nonlinear_variance_from_one_realisation():
    noisy = [robust_lpm(*_run(s, True)[::-1], N, LINES) for s in range(30)]
    clean = np.array([robust_lpm(*_run(s, False)[::-1], N, LINES).frf.response[0, 0]
                      for s in range(30)])
    assert noisy[0].noise_from == 'periods'
    u, _ = _run(0, True)
    u2 = np.abs(np.fft.rfft(u[:N]) / np.sqrt(N))[LINES] ** 2
    noise = np.mean([r.frf.noise_variance[0, 0] for r in noisy], axis=0)
    nl = np.mean([r.nonlinear_variance[0, 0] for r in noisy], axis=0)
    total = np.mean([r.frf.total_variance[0, 0] for r in noisy], axis=0)
    mc_total = np.var([r.frf.response[0, 0] for r in noisy], axis=0, ddof=1)
    mc_nl = np.var(clean, axis=0, ddof=1)
    ratios = {'noise / sigma^2 / (P |U|^2)': np.median(noise / (SIGMA ** 2 / PERIODS / u2)),
              'nonlinear / Monte-Carlo without noise': np.median(nl / mc_nl),
              'total / Monte-Carlo': np.median(total / mc_total)}
    print('; '.join(f'{k} {v:.3f}' for k, v in ratios.items())
          + f'; noise share of total {np.median(noise / total):.2f}')
    assert all(0.85 < v < 1.15 for v in ratios.values()), ratios
