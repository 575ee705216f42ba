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
The diagnosis' Nelder-Mead against scipy's: the same points, the same result, fewer rounds.

``nelder_mead`` must evaluate exactly the points ``scipy.optimize.minimize(method=
'Nelder-Mead')`` evaluates with the same initial simplex, bounds, tolerances and budget, in
the same order (the diagnosis' reports stay those of scipy's search), while its prefetched
guesses never reach the objective as evaluations.
"""
from __future__ import annotations

from frf_ident.core.diagnosis.experiments.simplex import nelder_mead
from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest
from scipy import optimize


def _objective(seed: int, n: int):
    """Return a bumpy bowl: a quadratic with a random centre and a ripple (local minima)."""
    rng = np.random.default_rng(seed)
    c, a, w = rng.normal(0, 1, n), rng.uniform(0.5, 3, n), rng.uniform(0, 0.3)
    return lambda x: float(np.sum(a * (x - c) ** 2) + w * np.sum(np.sin(7 * x)) + 100)


@pytest.mark.filterwarnings('ignore:Initial guess is not within')
@settings(max_examples=60, deadline=None, derandomize=True)
@given(seed=st.integers(0, 10 ** 6), n=st.integers(1, 4), maxfev=st.integers(3, 60),
       bounded=st.booleans(), xatol=st.sampled_from([1e-4, 0.01, 0.3]),
       fatol=st.sampled_from([1e-3, 0.5]))
def test_the_same_points_as_scipy(seed: int, n: int, maxfev: int, bounded: bool, xatol: float,
                                  fatol: float) -> None:
    """Same evaluation sequence and best vertex as scipy; guesses are not evaluations."""
    f = _objective(seed, n)
    rng = np.random.default_rng(seed + 1)
    x0 = rng.normal(0, 1, n)
    simplex = np.vstack([x0] + [x0 + 0.3 * np.eye(n)[k] for k in range(n)])
    bounds = [(-1.0, 1.2)] * n if bounded else None
    seen_scipy: list[np.ndarray] = []
    seen_ours: list[np.ndarray] = []
    guessed: list[np.ndarray] = []

    def logged(log):
        return lambda x: (log.append(np.copy(x)), f(x))[1]
    sol = optimize.minimize(logged(seen_scipy), x0, method='Nelder-Mead', bounds=bounds,
                            options={'xatol': xatol, 'fatol': fatol, 'maxfev': maxfev,
                                     'initial_simplex': simplex})
    best = nelder_mead(logged(seen_ours), simplex, bounds=bounds, xatol=xatol, fatol=fatol,
                       maxfev=maxfev, prefetch=guessed.extend)
    assert len(seen_ours) == len(seen_scipy)
    assert all(np.array_equal(a, b) for a, b in zip(seen_ours, seen_scipy))
    assert np.array_equal(best, sol.x)
    # every step asked for its reflection (and most for a guess) before evaluating it
    reflections = seen_ours[n + 1:]
    assert not reflections or any(np.array_equal(reflections[0], g) for g in guessed)


def test_a_right_guess_saves_a_round() -> None:
    """On a bowl the steps near the minimum contract: the guess is the next point evaluated."""
    f = _objective(3, 2)
    simplex = np.array([[2.0, 2.0], [2.5, 2.0], [2.0, 2.7]])
    order: list[tuple[str, tuple]] = []
    nelder_mead(lambda x: (order.append(('eval', tuple(x))), f(x))[1], simplex, xatol=1e-3,
                fatol=1e-6, maxfev=60,
                prefetch=lambda xs: order.append(('ahead', tuple(map(tuple, xs)))))
    hits = sum(1 for k, (kind, pts) in enumerate(order[:-2])
               if kind == 'ahead' and len(pts) == 2 and order[k + 1][0] == 'eval'
               and order[k + 2] == ('eval', pts[1]))
    steps = sum(1 for kind, _ in order if kind == 'ahead')
    assert steps > 10 and hits / steps > 0.4, (hits, steps)
