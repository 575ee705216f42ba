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
"""Test leave-range-out and the warning range of a validation record on data drawn here."""
import math

from frf_ident.core.diagnosis.crosscheck.validation import beyond_fitted_range
from frf_ident.core.diagnosis.timeseries.extrapolation import failing_position_terms, range_ends
from frf_ident.core.recording import Recording
import numpy as np
import pytest


def _rec(lo, hi, n=2001):
    t = np.arange(n) * 1e-3
    s = 0.5 - 0.5 * np.cos(np.linspace(0, 2 * math.pi, n))    # 0 .. 1 .. 0
    q = np.column_stack([a + (b - a) * s for a, b in zip(lo, hi)])
    return Recording(t, ['a', 'b'], q, np.gradient(q, 1e-3, axis=0), np.zeros_like(q))


def test_an_axis_beyond_the_fitted_range_is_named_with_its_degrees():
    fit = _rec([0.0, -0.1], [0.5, 0.1])
    rows = np.ones(fit.t.size - 1, bool)
    other = _rec([-0.2, -0.1], [0.5, 0.105])
    far = beyond_fitted_range(fit, rows, other, ['j1', 'j2'])
    # j2 leaves by 0.005 rad = 0.29 deg: within the tolerance
    assert set(far) == {'j1'}, far
    assert far['j1'].beyond_deg == pytest.approx(math.degrees(0.2), abs=0.05)
    assert far['j1'].reached_deg[0] == pytest.approx(math.degrees(-0.2), abs=0.01)


def test_only_the_fit_rows_count_as_fitted():
    fit = _rec([0.0, 0.0], [1.0, 1.0])
    rows = np.zeros(fit.t.size - 1, bool)
    rows[:200] = True           # the start of the motion only: positions near 0
    far = beyond_fitted_range(fit, rows, fit, ['j1', 'j2'])
    assert set(far) == {'j1', 'j2'}, far
    assert beyond_fitted_range(fit, np.ones(fit.t.size - 1, bool), fit, ['j1', 'j2']) == {}


def _travel(n=6000):
    """Return a position sweeping 0 .. 1 rad three times (N, 1) and all rows as fit rows."""
    q = 0.5 - 0.5 * np.cos(np.linspace(0, 6 * math.pi, n))
    return q[:, None], np.ones(n, bool)


@pytest.mark.parametrize('seed', [0, 1, 2])
def test_leave_range_out_keeps_a_ripple_of_the_whole_travel_not_one_of_its_middle(seed):
    """
    A ripple along the whole travel predicts the range's ends; one of the middle does not.

    The middle ripple (0.5 N m between 0.2 and 0.8 rad) is fitted wherever it is seen;
    held out, the ends show that it is absent there.
    """
    q, fit = _travel()
    rng = np.random.default_rng(seed)
    s = 40.0
    groups = {'gravity_torque': np.ones((q.shape[0], 1)),
              'torque_ripple': np.column_stack([np.sin(s * q[:, 0]), np.cos(s * q[:, 0])])}
    chosen = ['gravity_torque', 'torque_ripple']
    noise = 0.05 * rng.standard_normal(q.shape[0])
    everywhere = 0.5 * np.sin(s * q[:, 0] + 1.0) + noise
    middle = np.where((q[:, 0] > 0.2) & (q[:, 0] < 0.8), everywhere - noise, 0.0) + noise
    assert failing_position_terms(groups, chosen, everywhere, fit, q, 0) == {}
    bad = failing_position_terms(groups, chosen, middle, fit, q, 0)
    assert set(bad) == {'torque_ripple'}
    assert bad['torque_ripple'][0] >= bad['torque_ripple'][1]


def test_range_ends_are_shares_of_the_angle_not_of_the_samples():
    q, fit = _travel()
    lo, hi = range_ends(q[:, 0], fit, 0.1)
    assert q[lo, 0].max() <= 0.1 + 1e-12 and q[hi, 0].min() >= 0.9 - 1e-12
    # a cosine sweep dwells at its ends: a tenth of the angle is a fifth of the samples
    assert 0.15 < lo.mean() < 0.25
    assert range_ends(q[:, 0], np.zeros_like(fit)) == []
