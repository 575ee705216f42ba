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
"""The bounded Brent wrapper opens with the points scipy evaluates first and returns its result."""
import math

from frf_ident.core.diagnosis.experiments.brent import bounded_minimum, opening_points
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import optimize


@settings(max_examples=200, deadline=None)
@given(lo=st.floats(-1e4, 1e4), width=st.floats(1e-6, 1e5), rel=st.floats(1e-6, 0.1),
       centre=st.floats(-0.5, 1.5), power=st.sampled_from([1.0, 2.0, 4.0]))
def test_opening_points_are_scipys_first_two_evaluations_and_the_result_is_scipys(
        lo, width, rel, centre, power):
    hi = lo + width
    xatol = rel * width
    m = lo + centre * width

    def f(x):
        return abs(x - m) ** power + math.sin(7 * (x - lo) / width)
    seen = []
    sol = optimize.minimize_scalar(lambda x: seen.append(float(x)) or f(x), bounds=(lo, hi),
                                   method='bounded', options={'xatol': xatol, 'maxiter': 12})
    assert opening_points(lo, hi, xatol) == seen[:2]
    asked, got = [], []
    x = bounded_minimum(lambda x: got.append(x) or f(x), lo, hi, xatol=xatol, maxiter=12,
                        prefetch=asked.extend)
    assert asked == seen[:2] and got == seen and x == float(sol.x)
