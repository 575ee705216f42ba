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
Standard errors under model error: Monte-Carlo on a plant with a mode the model lacks.

Truth: the independently written reference plant (test/plants/reference.py) with an extra
link-side mode (a share of the link inertia on a spring), measured with a periodic multisine
and velocity noise as test_fit_physical.measure_reference does; each run draws new noise. The
two-mass model cannot have that mode, so the cost test fails and the fit is biased; the true
parameters (the plant's motor inertia, whole link inertia, gear stiffness, damping, viscous
friction, and the zero-order hold's half-sample delay) are what the errors must cover. Baseline
beside: the Cramer-Rao errors alone.
"""
from __future__ import annotations

from core.fit.test_fit_physical import measure_reference, SECTION6
from frf_ident.core.fit.physical import fit_two_mass, PARAMETERS
import numpy as np
import pytest

TRUE = np.array([SECTION6[k] for k in PARAMETERS] + [0.5e-3])
RUNS = 10


@pytest.mark.parametrize('mode', [{'frequency_hz': 20.0, 'mass_ratio': 0.1},
                                  {'frequency_hz': 25.0, 'mass_ratio': 0.2}],
                         ids=['20Hz_10pct', '25Hz_20pct'])
def test_reported_errors_cover_the_true_parameters_under_a_missing_mode(mode):
    est, cr, rep, missing = [], [], [], 0
    for seed in range(RUNS):
        f, g, v = measure_reference(dict(mode, damping_ratio=0.03), seed=100 + seed)
        fit = fit_two_mass(f, g, v, delay_s=None)
        missing += fit.cost.structure_missing
        est.append(np.append(fit.value, fit.delay_s))
        cr.append(np.append(fit.std, fit.delay_std_s))
        rep.append(np.append(fit.reported_std, fit.delay_reported_std_s))
    est, cr, rep = np.array(est), np.array(cr), np.array(rep)
    inside_rep = np.mean(np.abs(est - TRUE) <= 2 * rep, axis=0)
    inside_cr = np.mean(np.abs(est - TRUE) <= 2 * cr, axis=0)
    names = list(PARAMETERS) + ['delay']
    print(f'missing mode {mode}: structure missing in {missing} of {RUNS} runs; inside 2 SE '
          f'(reported / Cramer-Rao): '
          + ', '.join(f'{n} {a:.0%} / {b:.0%}' for n, a, b in zip(names, inside_rep, inside_cr))
          + f'; median reported / CR error {np.median(rep / cr):.3g}')
    assert missing == RUNS
    assert np.all(inside_rep >= 0.9), dict(zip(names, inside_rep))
    assert np.mean(inside_cr) < 0.5          # the Cramer-Rao errors alone cover far fewer


def test_a_right_structure_keeps_the_cramer_rao_errors():
    """Without the extra mode the cost test passes and nothing is added to the errors."""
    f, g, v = measure_reference(None, seed=100)
    fit = fit_two_mass(f, g, v, delay_s=None)
    assert not fit.cost.structure_missing, fit.cost.summary()
    assert np.all(fit.model_error == 0) and fit.delay_model_error_s == 0
    assert np.array_equal(fit.reported_std, fit.std)
    assert fit.cost.verdict == 'parameters describe the data'
