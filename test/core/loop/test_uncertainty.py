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
The uncertainty weight W(s) of frf_ident/core/loop/uncertainty.py.

It covers its bound, it is stable and minimum phase, and the set it describes holds the true
plants of a Monte-Carlo campaign.
"""
from frf_ident.core.loop.uncertainty import fit_weight, relative_bound
from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
from plants.campaign import FREQ_HZ, measured, pose_robot, true_frf


@settings(max_examples=15, deadline=None)
@given(st.lists(st.floats(-3.0, 2.0), min_size=4, max_size=4),
       st.floats(0.0, 3.0), st.floats(0.5, 1.8))
def test_weight_covers_any_smooth_bound_and_is_stable_minimum_phase(knots, bump, where):
    f = np.geomspace(1.0, 100.0, 150)
    x = np.log10(f)
    base = np.interp(x, np.linspace(0, 2, 4), knots)
    lr = base + bump * np.exp(-((x - where) / 0.08) ** 2)       # a resonance-like bump
    r = 10.0 ** lr
    w = fit_weight(f, r)
    assert np.all(np.abs(w.response(f)) >= r * (1 - 1e-9))
    num, den = w.num_den()
    assert np.all(np.roots(den).real < 0) and np.all(np.roots(num).real < 0)


def test_the_set_holds_the_true_plants_of_a_noisy_campaign():
    """5 poses, 2 % noise: every true P_k lies in P_0-hat (1 + Delta W) on >= 99 % of the lines."""
    rng = np.random.default_rng(4)
    scales = np.geomspace(0.5, 2.0, 5)
    robots = [pose_robot(s) for s in scales]
    frfs = [measured(r, 0.02, rng) for r in robots]
    inside = []
    for j in range(3):
        p = np.stack([f.response[j, j] for f in frfs])
        v = np.stack([f.noise_variance[j, j] for f in frfs])
        w = np.abs(fit_weight(FREQ_HZ, relative_bound(p, v, 2)).response(FREQ_HZ))
        for r in robots:
            inside.append(np.mean(np.abs(true_frf(r)[j, j] - p[2]) <= w * np.abs(p[2])))
    print('share of lines inside the set, per axis and pose:', np.round(inside, 3))
    assert min(inside) >= 0.99
