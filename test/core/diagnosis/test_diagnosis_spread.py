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
"""Test the check of standard errors across records on draws of known spread."""
from frf_ident.core.diagnosis.common import Effect
from frf_ident.core.diagnosis.crosscheck.spread import scalar_estimates, spread_check, widened
from frf_ident.core.diagnosis.thresholds import SPREAD_ALPHA
import numpy as np
import pytest


def _runs(rng, n_par: int, se: float, spread: float):
    """Return two records' estimates of ``n_par`` parameters: reported ``se``, true ``spread``."""
    return [{(f'a{k}', 'coulomb_friction'): (1.0 + spread * rng.standard_normal(), se)
             for k in range(n_par)} for _ in range(2)]


def test_errors_that_hold_are_widened_at_the_false_alarm_rate():
    rng = np.random.default_rng(0)
    widened_share = np.mean([spread_check(_runs(rng, 6, 0.1, 0.1)).factor > 1.0
                             for _ in range(400)])
    # 400 checks of standard errors that hold: binomial 5 % +- 3 sigma
    assert abs(widened_share - SPREAD_ALPHA) < 3 * np.sqrt(SPREAD_ALPHA * 0.95 / 400)


def test_errors_3_3_times_too_small_are_widened_by_about_that():
    """The issue's EMPS case: two records 3.3 combined standard errors apart."""
    rng = np.random.default_rng(1)
    f = [spread_check(_runs(rng, 8, 0.1, 0.33)).factor for _ in range(50)]
    assert min(f) > 1.0
    # RMS of z over 8 pairs: chi with 8 dof scaled by 3.3, within about 25 %
    assert np.median(f) == pytest.approx(3.3, rel=0.15)


def test_only_friction_and_inertia_with_an_error_are_compared_and_all_errors_scaled():
    effs = [Effect('coulomb_friction', 'a', 1.0, {'coulomb_friction': 2.0}, '',
                   standard_error={'coulomb_friction': 0.1}),
            Effect('parameter_mismatch', 'a', 1.0, {'gravity_torque': 5.0}, '',
                   standard_error={'gravity_torque': 0.2}),
            Effect('gravity', 'b', 1.0, {'gravity': [{'amplitude': 3.0}]}, '',
                   standard_error={'gravity': [None, {'amplitude': 0.5}]})]
    assert scalar_estimates(effs) == {('a', 'coulomb_friction'): (2.0, 0.1)}
    out = widened(effs, 2.0)
    assert out[0].standard_error == {'coulomb_friction': 0.2}
    assert out[2].standard_error == {'gravity': [None, {'amplitude': 1.0}]}
    assert spread_check([scalar_estimates(effs)]).factor == 1.0
