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
Diagnosed values against their standard errors, on scenes of the reference plant drawn afresh.

Issue 58: a viscous friction of 334 N m s/rad for a true 45, next to a backlash on its axis,
was printed as a finding, without an error. Each run draws one scene of each kind of two
effects on one axis that trade against each other (backlash with viscous friction, Coulomb
with viscous friction, a stiffening gear with a joint-damping mismatch) with a fresh seed,
printed with the rates (``FRF_DIAG_SEED=<seed> pytest -s test/app/test_diagnose_uncertainty.py
-k <kind>`` repeats one): every value the report names is compared with the plant's. None may
be more than 3x off without the label "not determined"; at most one per scene lies beyond 2
of its standard errors without it (the rate over 21 scenes, and the Monte Carlo of the errors
themselves, are ``python -m benchmarks diagnosis_uncertainty``).
"""
import os
import sys

from benchmarks.diagnosis_scene_run import run_scene
from benchmarks.diagnosis_scenes import scene_of
from benchmarks.diagnosis_uncertainty import draw_pair, PAIRS, rates, run_pair, value_checks
import numpy as np
import pytest


def _seed() -> int:
    """Return FRF_DIAG_SEED when set (to repeat a scene), else a fresh random seed."""
    given = os.environ.get('FRF_DIAG_SEED', '')
    return int(given) if given else int.from_bytes(os.urandom(3), 'little')


#: fresh draws fail at the rate the sweep measures: they are the sweep's, run with
#: FRF_UNCERTAINTY_SCENES=1, not make test's. Before the step bias a stiffening gear found to
#: within 0.05 % lay 25 of its standard errors off (seed 5804 stiffening_damping: k2 231922 +-
#: 4.4 for 231809; now +- 173); the errors still do not cover what else the simulator does
#: differently from the plant (docs/diagnosis/measured.md)
FRESH = os.environ.get('FRF_UNCERTAINTY_SCENES') == '1'


@pytest.mark.slow
@pytest.mark.skipif(not FRESH, reason='FRF_UNCERTAINTY_SCENES=1 draws the scenes afresh')
@pytest.mark.parametrize('kind', list(PAIRS))
def test_values_lie_within_their_errors_or_are_not_determined(kind):
    seed = _seed()
    scene = draw_pair(np.random.default_rng(seed), kind)
    print(f'FRF_DIAG_SEED={seed} kind={kind} hidden={scene["truth"]}', file=sys.stderr)
    r = run_pair(scene, seed)
    got = rates([r])
    print(f'FRF_DIAG_SEED={seed} {kind}: within 2 standard errors of the truth, of the values '
          f'determined {got["within_2se_of_determined"]}; not determined '
          f'{got["not_determined"]}', file=sys.stderr)
    msg = f'FRF_DIAG_SEED={seed} {kind}: {r["values"]}'
    vals = r['values']
    assert not any(v['off_3x'] and v['determined'] for v in vals), msg
    assert sum(v['determined'] and not v['within_2se'] for v in vals) <= 1, msg
    # every value the report names carries its standard error
    assert all(v['se'] is not None for v in vals), msg


def _gear_and_damping_named(seed: int) -> list[dict]:
    """Assert pair scene ``seed`` (stiffening_damping) named as the plant has it; its values."""
    r = run_pair(draw_pair(np.random.default_rng(seed), 'stiffening_damping'), seed)
    msg = f'{r["found"]} {r["values"]}'
    assert r['found'] == r['hidden'] == ['parameter_mismatch@joint_3',
                                         'stiffness_nonlinearity@joint_3'], msg
    vals = r['values']
    assert all(v['determined'] and abs(v['value'] / v['truth'] - 1) < 0.01 for v in vals), msg
    return vals


@pytest.mark.slow
def test_a_stiffening_gear_beside_a_damping_mismatch_is_not_named_a_backlash():
    """
    Seed 3687644 (stiffening_damping on joint_3): the gear, not a backlash on a stiffer spring.

    The stiffening candidate of the first round, fitted without the damping mismatch, lost the
    held-out duel to a parameter mismatch of stiffness and damping; a backlash on top then took
    the gear's bend (the same line beyond the breakpoint): 1.31e-4 +- 2.1e-6 rad was named
    where the plant has none, the mismatch's stiffness 192541 for the plant's 120000 and no
    stiffening gear. Read again as a stiffening gear from the nominal stiffness
    (frf_ident/core/diagnosis/experiments/spring_reading.py), the axis' two effects are named,
    every value within 1 % of the plant's.
    """
    vals = _gear_and_damping_named(3687644)
    assert sum(not v['within_2se'] for v in vals) <= 1, vals


@pytest.mark.slow
def test_a_gear_damping_is_not_named_a_motor_viscous_friction():
    """
    Seed 205727 (stiffening_damping on joint_3): the damping, not a viscous friction of 110.

    joint_3's gear damps with 348.6 N m s/rad for the nominal 250, beside a stiffening gear.
    The torque residual read a viscous friction first (152 for the nominal 10); the FRF shape
    read the damping at 320 later, judged on top of it (doubling the dissipation, worse), and
    the axis was named a viscous friction of 110.2, held-out misfit 1808 noise floors. Offered
    in its place (frf_ident/core/diagnosis/experiments/dissipation_reading.py), the damping
    takes the axis to 19.7 floors: both effects named, every value within 1 % of the plant's.
    """
    _gear_and_damping_named(205727)


@pytest.mark.slow
def test_a_stiffer_spring_behind_a_gap_is_not_named_a_stiffening_gear(tmp_path):
    """
    Scene 9135 of kind mismatch (joint_2 19 % stiffer with a gap): the mismatch and the gap.

    joint_2's stiffness is 356811 N m/rad for the nominal 3e5, behind a backlash of 7.8e-5 rad.
    The search named a stiffening gear from nominal (k2 3.573e5 beyond 2.55e-4 rad), the same
    line beyond its breakpoint; read the other way (frf_ident/core/diagnosis/experiments/
    spring_reading.py) the axis is named as the plant has it. The reading is not taken where
    its mismatch leaves the axis lacking structure (test/app/test_diagnose_scenes.py, scene
    7189810).
    """
    scene = scene_of(9135, 0, 'mismatch')
    r = run_scene(scene, tmp_path, keep_report=True)
    vals = value_checks(scene, r.pop('report'))
    msg = f'{r} {vals}'
    assert r['found'] == r['hidden'] == ['backlash@joint_2', 'parameter_mismatch@joint_2'], msg
    assert all(v['determined'] and abs(v['value'] / v['truth'] - 1) < 0.1 for v in vals), msg
