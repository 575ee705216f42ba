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
"""The residual test: false alarms under noise by Monte Carlo, and bands where they are."""
from frf_ident.core.fit.residual_whiteness import RESIDUAL_ALPHA, residual_test
import numpy as np
from scipy import stats

F = np.geomspace(2.0, 60.0, 53)          # the multisine lines of the diagnosis' records


def _noise(rng: np.random.Generator, n: int = F.size) -> np.ndarray:
    return (rng.standard_normal(n) + 1j * rng.standard_normal(n)) / np.sqrt(2.0)


def test_white_noise_passes_at_the_stated_false_alarm_rate():
    """Each test's false-alarm probability is RESIDUAL_ALPHA over all its runs and lags."""
    rng = np.random.default_rng(57)
    runs = 4000
    band = white = 0
    for _ in range(runs):
        t = residual_test(F, _noise(rng))
        band += bool(t.bands)
        white += t.correlated
    # binomial upper 99.9 % bound of the count at probability 2 alpha (Bonferroni is
    # conservative; the band test's runs overlap)
    limit = stats.binom.isf(1e-3, runs, 2 * RESIDUAL_ALPHA)
    print(f'false alarms in {runs} white residuals: bands {band}, whiteness {white} '
          f'(expected at most {runs * RESIDUAL_ALPHA:.0f} each)')
    assert band <= limit and white <= limit


def test_a_misfit_on_neighbouring_lines_is_a_band_with_its_centre():
    """Three lines each below a lone line's limit, their sum far above it."""
    rng = np.random.default_rng(3)
    e = _noise(rng)
    k = int(np.argmin(np.abs(F - 25.0)))
    e[k - 1:k + 2] += 3.0                    # 2|e|^2 = 18 per line: below a lone line's limit
    t = residual_test(F, e)
    assert not t.white
    b = t.bands[0]
    assert b.lo_hz <= F[k - 1] and b.hi_hz >= F[k + 1] and b.n_lines <= 5
    assert abs(b.centre_hz - F[k]) < 0.5 * (F[k + 1] - F[k - 1])
    assert b.excess > 4


def test_a_smooth_misfit_below_every_band_limit_is_not_white():
    """A slow ripple across the lines correlates neighbours: the whiteness test sees it."""
    rng = np.random.default_rng(11)
    caught = 0
    for _ in range(50):
        e = _noise(rng) + 0.9 * np.exp(1j * 2 * np.pi * np.arange(F.size) / 40.0)
        caught += residual_test(F, e).correlated
    assert caught >= 45
