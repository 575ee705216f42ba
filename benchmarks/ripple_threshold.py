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
False-alarm rate of the ripple scan on white noise: the calibrated threshold against ln(M / a).

``find_ripple`` divides each periodogram value by a running median of its neighbours; that
level is itself random, so the threshold ln(M / alpha) of an exact level is passed far more
often than alpha. ``ripple_threshold`` accounts for it (RIPPLE_LEVEL_DOF, RIPPLE_CELL_FACTOR,
fitted on these scans). Rows per record size: the share of noise-only scans above each
threshold at several alpha, and both thresholds at the operating alpha.

Run: ``python -m benchmarks ripple_threshold`` (about a minute per 1,000 scans of all sizes).
"""
from __future__ import annotations

import math

import numpy as np

SIZES = ((4000, 0.05), (8000, 0.3), (20000, 1.0))    # samples, travel [rad]
ALPHAS = (0.1, 0.03, 0.01, 0.003)
SCANS = 1500


def peaks(n: int, travel: float, scans: int = SCANS) -> tuple[np.ndarray, float]:
    """Return the peak ratios of ``scans`` white-noise scans and the scan's resolution cells."""
    from frf_ident.core.diagnosis.regression import find_ripple, ripple_range
    q, mask = np.linspace(0.0, travel, n), np.ones(n, bool)
    s_min, s_max = ripple_range(q, mask)
    out = np.array([find_ripple(np.random.default_rng(s).standard_normal(n), q, mask)[1]
                    for s in range(scans)])
    return out, (s_max - s_min) * travel / (2 * math.pi)


def rows(scans: int = SCANS) -> list[tuple[str, str, str, str]]:
    """Return per size the realised false-alarm shares, calibrated and ln(M / alpha)."""
    from frf_ident.core.diagnosis.regression import ripple_threshold
    from frf_ident.core.diagnosis.thresholds import RIPPLE_FALSE_ALARM, RIPPLE_LEVEL_WINDOW
    out = []
    for n, travel in SIZES:
        pk, cells = peaks(n, travel, scans)
        new = ', '.join(
            f'{a:g}: {np.mean(pk > ripple_threshold(cells, RIPPLE_LEVEL_WINDOW, a)):.3f}'
            for a in ALPHAS)
        old = ', '.join(f'{a:g}: {np.mean(pk > math.log(cells / a)):.3f}' for a in ALPHAS)
        out.append((f'ripple scan on white noise, {n} samples, {cells:.0f} cells, {scans} scans: '
                    'share above the threshold at alpha', new, f'ln(M / alpha): {old}',
                    f'threshold at {RIPPLE_FALSE_ALARM:g}: '
                    f'{ripple_threshold(cells, RIPPLE_LEVEL_WINDOW):.1f} vs '
                    f'{math.log(cells / RIPPLE_FALSE_ALARM):.1f}'))
    return out
