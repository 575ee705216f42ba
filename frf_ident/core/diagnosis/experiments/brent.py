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
scipy's bounded Brent minimiser, with its two opening points evaluated at once.

``scipy.optimize.minimize_scalar(method='bounded')`` opens with two golden-section steps,
which need no function value: the first point is the golden section of the interval, the
second the golden section of its larger part. :func:`bounded_minimum` hands both to
``prefetch`` (the evaluator simulates them on two processes) and then runs scipy's method
unchanged, which finds them computed: the same points, the same result, one round of
simulation less per search. The later steps each depend on the value before (a parabola
through the last three points) and stay one after the other.
"""
from __future__ import annotations

import math
from typing import Callable

from scipy import optimize

__all__ = ['bounded_minimum', 'opening_points']


def opening_points(lo: float, hi: float, xatol: float) -> list[float]:
    """
    Return the first two points scipy's bounded Brent method evaluates on [lo, hi].

    One where the interval is within the tolerance. The arithmetic of scipy's
    ``_minimize_scalar_bounded`` before its first parabola (test/core/diagnosis/test_brent.py
    holds it to scipy).
    """
    golden = 0.5 * (3.0 - math.sqrt(5.0))
    xf = lo + golden * (hi - lo)
    xm = 0.5 * (lo + hi)
    tol1 = math.sqrt(2.2e-16) * abs(xf) + xatol / 3.0
    if not abs(xf - xm) > 2.0 * tol1 - 0.5 * (hi - lo):
        return [xf]                 # an interval within the tolerance: one point only
    e = (lo - xf) if xf >= xm else (hi - xf)
    rat = golden * e
    si = -1.0 if rat < 0 else 1.0
    return [xf, xf + si * max(abs(rat), tol1)]


def bounded_minimum(fn: Callable[[float], float], lo: float, hi: float, *, xatol: float,
                    maxiter: int, prefetch: Callable[[list[float]], None] | None = None
                    ) -> float:
    """
    Return the minimiser of ``fn`` on [lo, hi] by scipy's bounded Brent method.

    Parameters
    ----------
    fn : callable
        The objective of a point (a float).
    lo, hi : float
        The bounds.
    xatol : float
        scipy's absolute tolerance on the minimiser.
    maxiter : int
        Evaluations at most.
    prefetch : callable, optional
        Called with the two opening points before the search, so that ``fn`` finds them
        computed; it must not change what ``fn`` returns.

    Returns
    -------
    float
        The minimiser scipy returns.

    """
    if prefetch is not None:
        prefetch(opening_points(lo, hi, xatol))
    sol = optimize.minimize_scalar(lambda x: fn(float(x)), bounds=(lo, hi), method='bounded',
                                   options={'xatol': xatol, 'maxiter': maxiter})
    return float(sol.x)
