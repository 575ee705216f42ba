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
"""Test the warning range of a validation record against ranges drawn here."""
import math

from frf_ident.core.diagnosis.extrapolation import beyond_fitted_range
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
    assert far['j1']['beyond_deg'] == pytest.approx(math.degrees(0.2), abs=0.05)
    assert far['j1']['reached_deg'][0] == pytest.approx(math.degrees(-0.2), abs=0.01)


def test_only_the_fit_rows_count_as_fitted():
    fit = _rec([0.0, 0.0], [1.0, 1.0])
    rows = np.zeros(fit.t.size - 1, bool)
    rows[:200] = True           # the start of the motion only: positions near 0
    far = beyond_fitted_range(fit, rows, fit, ['j1', 'j2'])
    assert set(far) == {'j1', 'j2'}, far
    assert beyond_fitted_range(fit, np.ones(fit.t.size - 1, bool), fit, ['j1', 'j2']) == {}
