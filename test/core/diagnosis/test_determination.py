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
"""Which values a record determines: the share rule, the label, the linearised fit's pieces."""
import math

from frf_ident.core.diagnosis.common import Effect
from frf_ident.core.diagnosis.determination import not_determined, undetermined_effects
from frf_ident.core.diagnosis.experiments.standard_errors import between_experiments, sandwich
from frf_ident.core.diagnosis.thresholds import NOT_DETERMINED_SHARE
import numpy as np
import pytest


def test_a_value_whose_error_exceeds_its_share_is_labelled_and_scores_nothing():
    share = NOT_DETERMINED_SHARE
    effects = [
        Effect('viscous_friction', 'j', 0.6, {'viscous_friction': 333.7}, '',
               standard_error={'viscous_friction': 333.7 * 0.6}),
        Effect('coulomb_friction', 'j', 0.9, {'coulomb_friction': 10.0}, '',
               standard_error={'coulomb_friction': 10.0 * share * 0.9}),
        Effect('parameter_mismatch', 'j', 0.1, {'gravity_torque': 11.36}, '',
               standard_error={'gravity_torque': 5.2}),
        Effect('torque_ripple', 'j', 0.2,
               {'torque_ripple': [{'amplitude': 1.0, 'spatial_frequency': 9.0, 'phase': 0.1}]},
               '', standard_error={'torque_ripple': [{'amplitude': 0.5, 'phase': 3.0}]}),
        Effect('backlash', 'j', 0.5, {'backlash': 1e-4}, '')]      # no error: left alone
    out = undetermined_effects(effects)
    visc, coul, load, ripple, gap = out
    assert [n.parameter for n in visc.not_determined] == ['viscous_friction']
    assert visc.score == 0.0 and coul.score == 0.9 and not coul.not_determined
    # a friction cannot be negative: its range stops at 0; a load can
    assert visc.not_determined[0].value_range[0] == 0.0
    assert visc.not_determined[0].value_range[1] == pytest.approx(333.7 * 2.2)
    assert load.not_determined[0].value_range == pytest.approx([11.36 - 10.4, 11.36 + 10.4])
    # a term's amplitude is a scale, its phase is not
    assert [n.parameter for n in ripple.not_determined] == ['torque_ripple amplitude']
    assert gap == effects[4]
    # report.json: the typed entry, the experiment that would determine it
    entry = visc.to_dict()['not_determined'][0]
    assert entry['parameter'] == 'viscous_friction' and 'slower multisine' in entry['experiment']
    assert 'not_determined' not in coul.to_dict()
    # labelling twice adds nothing
    assert undetermined_effects(out)[0].not_determined == visc.not_determined


def test_a_mode_is_judged_value_by_value_and_a_stage_label_scores_nothing():
    """
    A second mode's frequency, damping ratio and inertia are magnitudes too.

    Until stop 65 the share rule skipped a mapping: a mode whose damping ratio had an error
    of 60 % of its value was reported as determined. A label a stage gave (the simulation
    search's damping profile) zeroes the score like the rule's own.
    """
    mode = {'frequency_hz': 43.87, 'damping_ratio': 0.0066, 'inertia': 27.7}
    errs = {'frequency_hz': 0.2, 'damping_ratio': 0.0066 * 0.6, 'inertia': 1.0}
    given = not_determined('second_mode damping_ratio', 0.0066, 0.0, 'its profile', [0.0132])
    out = undetermined_effects([
        Effect('second_mode', 'joint_1', 0.8, {'second_mode': mode}, '',
               standard_error={'second_mode': errs}),
        Effect('second_mode', 'joint_2', 0.7, {'second_mode': mode}, '',
               standard_error={'second_mode': None}, not_determined=[given]),
        Effect('second_mode', 'joint_3', 0.6, {'second_mode': mode}, '',
               standard_error={'second_mode': {**errs, 'damping_ratio': 0.001}})])
    rule, staged, sure = out
    assert [n.parameter for n in rule.not_determined] == ['second_mode damping_ratio']
    assert rule.not_determined[0].value_range == pytest.approx([0.0, 0.0066 * 2.2])
    assert rule.score == 0.0 and 'chirp' in rule.not_determined[0].experiment
    assert staged.not_determined == [given] and staged.score == 0.0
    assert given.value_range == pytest.approx([0.0066, 0.0132])
    assert not sure.not_determined and sure.score == 0.6


def test_the_sandwich_leaves_a_direction_the_rows_cannot_see_free():
    rng = np.random.default_rng(1)
    x = rng.standard_normal(600)
    J = np.column_stack([x, np.zeros(600)])          # the second parameter moves nothing
    r = 0.1 * rng.standard_normal(600) - 0.5 * x
    cov, dx = sandwich(J, r, np.arange(600) // 20)
    assert dx[0] == pytest.approx(0.5, abs=0.02)
    assert cov[1, 1] == math.inf and math.isfinite(cov[0, 0])
    # white noise: the block-robust error is the least-squares one
    assert math.sqrt(cov[0, 0]) == pytest.approx(0.1 / math.sqrt(x @ x), rel=0.25)


def test_the_experiments_spread_widens_the_error_only_as_far_as_they_disagree():
    agree = between_experiments({'a': (np.array([1.0]), np.array([0.1])),
                                 'b': (np.array([1.05]), np.array([0.1]))})
    assert agree[0] == pytest.approx(0.1 / math.sqrt(2))
    apart = between_experiments({'a': (np.array([1.0]), np.array([0.01])),
                                 'b': (np.array([2.0]), np.array([0.01]))})
    # two values 1 apart: the random-effects error of their mean is about half of it
    assert 0.45 < apart[0] < 0.75
    assert between_experiments({'a': (np.array([1.0]), np.array([0.1]))})[0] == 0.0


def test_the_values_on_an_axis_left_unexplained_are_not_determined():
    from frf_ident.core.diagnosis.determination import on_unexplained_axes
    from frf_ident.core.diagnosis.records import Signature, Unexplained
    effects = [Effect('stiffness_nonlinearity', 'j1', 0.9,
                      {'stiffness_k2': 2.369e5, 'stiffness_breakpoint': 2.254e-4}, '',
                      standard_error={'stiffness_k2': 1.5e3, 'stiffness_breakpoint': 9e-6}),
               Effect('coulomb_friction', 'j2', 0.9, {'coulomb_friction': 3.0}, '',
                      standard_error={'coulomb_friction': 0.1})]
    une = [Unexplained('j1', Signature(band_hz=[10.0, 12.0]), misfit_share=0.33),
           Unexplained('j2', Signature(band_hz=[400.0, 410.0], peak_hz=405.0),
                       kind='resonance above the analysis band')]
    k2, fc = on_unexplained_axes(effects, une)
    assert [n.parameter for n in k2.not_determined] == ['stiffness_k2', 'stiffness_breakpoint']
    assert k2.score == 0.0 and '33 %' in k2.not_determined[0].reason
    # a peak above the analysis band says nothing about the axis' fitted values
    assert fc == effects[1]
