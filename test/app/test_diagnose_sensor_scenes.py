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
Scenes read by a realistic sensor, end to end (issue 55 items 1-2).

The independent reference plant (test/plants/reference.py) read by an encoder of 1e-6 to
1e-5 rad per count, its velocity the difference of two readings over a sample, plus noise:
``identify --plant`` records a bag, ``diagnose`` compares it with the nominal
config/model_3axis.yaml. A checked scene (CHECKED_SEED; FRF_DIAG_SEED=<seed> repeats another,
FRF_DIAG_SEED=random draws afresh, the seed printed): a nominal plant, where only the sensor
may be named, on every axis; and two small effects on two axes, each on its own axis.
Before issue 55 the nominal scenes named a time delay of about half a sample on every axis
(`python -m benchmarks.diagnosis 2 5500 sensor`: 3 of 3 axes in both).

The issue's sweep, >= 20 scenes of each kind drawn afresh: ``FRF_SENSOR_SCENES=20`` runs
:func:`test_sensor_sweep` (about 40 scene-minutes, too long for ``make test``, which runs
the one scene per kind above); the same sweep with its rows printed is
``python -m benchmarks.diagnosis_sensor 20``, and :func:`check_sweep` is what it must show.
"""
import os
import sys

from benchmarks.diagnosis_scene_run import run_scene
from benchmarks.diagnosis_scenes import draw_scene
from benchmarks.diagnosis_sensor import sensor_sweep
import numpy as np
import pytest


#: the scene `make test` repeats (both kinds checked: the sensor alone, and a stiffening gear
#: with a time delay both named). A fresh draw's two small effects may both lie at the noise
#: floor (seed 142097: a viscous friction at 1.59 floors, a 2.6e-5 rad backlash at 0.90, none
#: named), so fresh draws are the sweep's, with its rates (FRF_SENSOR_SCENES=N)
CHECKED_SEED = 5500


def _seed() -> int:
    """Return FRF_DIAG_SEED (a seed, or 'random': a fresh draw), else CHECKED_SEED."""
    given = os.environ.get('FRF_DIAG_SEED', '')
    if given == 'random':
        return int.from_bytes(os.urandom(3), 'little')
    return int(given) if given else CHECKED_SEED


@pytest.mark.slow
@pytest.mark.parametrize('kind', ['sensor', 'sensor_two'])
def test_sensor_scene(kind, tmp_path):
    seed = _seed()
    scene = draw_scene(np.random.default_rng(seed), kind)
    print(f'FRF_DIAG_SEED={seed} kind={kind} hidden={scene["truth"]} encoder='
          f'{scene["scene"]["encoder_resolution"]}', file=sys.stderr)
    r = run_scene(scene, tmp_path)
    msg = f'FRF_DIAG_SEED={seed} kind={kind}: {r}'
    print(f'found {r["found"]}, sensor {r["sensor_found"]}, gain tests {r["gain_tests"]}',
          file=sys.stderr)
    # the sensor on every axis, nowhere else, its step read to 1 %
    assert r['sensor_missed'] == 0 and r['sensor_false'] == 0, msg
    assert all(e < 0.01 for e in r['sensor_resolution_error'].values()), msg
    assert not any(f.startswith('time_delay') for f in r['found']) or any(
        h.startswith('time_delay') for h in r['hidden']), msg
    if kind == 'sensor':
        assert r['n_found'] == 0, msg
        return
    # two small effects: each on its own axis; nothing named on an effect's axis that is
    # not its own (a rate over many scenes is the benchmark's; one scene may miss one)
    assert r['hits'] >= 1, msg
    axes = {h.split('@')[1] for h in r['hidden']}
    assert not [f for f in r['found'] if f not in r['hidden'] and f.split('@')[1] in axes], msg
    assert r['false_alarms'] <= 1, msg


@pytest.mark.slow
def test_a_stiffening_gear_read_as_a_mode_behind_a_gap_is_named_a_gear(tmp_path):
    """
    Seed 13191133 (sensor_two): joint_2's stiffening gear and joint_1's backlash, both named.

    Before stage 1 a second mode at 15.9 Hz was fitted on joint_2 with the axis' stiffness
    raised to the gear's outer k2 (433207 for 433422), and stage 2 added a backlash of 9.1e-5
    rad on top: the gear's line beyond its bends read as a stiffer spring behind a gap, the
    stiffness carried by the mode. Read the other way (the mode without its stiffness and the
    gear from nominal, frf_ident/core/diagnosis/experiments/spring_reading.py) the held-out
    misfit fell 2.58 -> 1.58 floors and the held-out check dropped the mode.
    """
    seed = 13191133
    scene = draw_scene(np.random.default_rng(seed), 'sensor_two')
    r = run_scene(scene, tmp_path)
    msg = f'FRF_DIAG_SEED={seed}: {r}'
    assert r['found'] == r['hidden'] == ['backlash@joint_1',
                                         'stiffness_nonlinearity@joint_2'], msg


@pytest.mark.slow
def test_the_true_model_of_a_coarse_encoder_scene_sits_at_its_floor(tmp_path):
    """
    Seed 13191138 (sensor_two): the true model within its noise floor on every axis.

    joint_2's encoder steps 9.2e-6 rad. Its quantisation error repeats with the multisine's
    period, so the floor from the spread between periods missed it: the true model's
    multisine term sat at 2.77 / 3.80 / 1.88 floors (0.45 on joint_2 with steps of 1e-9,
    ``python -m benchmarks.sensor_floor 13191138 [1e-9]``). The evaluator adds what the
    quantisation puts on the FRF terms, measured by simulating the nominal model with and
    without the encoder in the loop (experiments/quantisation_floor.py): 1.31 / 1.75 / 0.95,
    the misfit 0.83 / 0.88 / 0.77 (1.19 / 1.39 / 1.00 before). The torque and velocity
    terms, which the period spread already held, stay at 1.00 / 0.88 / 1.06.
    """
    from benchmarks.diagnosis_scene_run import identify_scene
    from benchmarks.diagnosis_scenes import scene_of
    from benchmarks.sensor_floor import true_model_terms
    scene = scene_of(13191138, 0, 'sensor_two')
    out = true_model_terms(scene, identify_scene(scene, tmp_path / 'bag'))
    print(out, file=sys.stderr)
    assert all(0.6 < m < 1.1 for m in out['misfit']), out
    assert max(out['terms']['multisine']) < 2.0, out
    assert all(0.8 < t < 1.2 for t in out['terms']['effort']), out


#: scenes of each kind the sweep draws (0: skipped; the issue asks for >= 20)
SWEEP = int(os.environ.get('FRF_SENSOR_SCENES', '0'))


def check_sweep(a: dict) -> None:
    """
    Assert what the issue's sweep must show (the aggregate of ``sensor_sweep``).

    Nominal scenes: no plant effect named, the sensor on every axis, nowhere else. The
    held-out gain rule on effects that buy nothing passes at most 1 % of them (its bound
    is 0.13 % each; 1 % leaves room for a few hundred tests). Two small effects on two axes:
    nothing named on an effect's axis but its own effect; recall and false alarms printed.
    """
    msg = {k: v for k, v in a.items() if k != 'runs'}
    assert a['nominal_scenes'] >= 1 and a['two_effect_scenes'] >= 1, msg
    assert a['nominal_without_plant_effect'] == a['nominal_scenes'], msg
    assert a['sensor_on_every_axis'] == a['scenes'] and a['sensor_false'] == 0, msg
    passed, n = (int(x) for x in a['null_rule_false_alarms'].split('/'))
    assert n >= 12 * a['nominal_scenes'] and passed <= 0.01 * n, msg
    assert a['borrowed_by_an_effect_axis'] == 0, msg


@pytest.mark.slow
@pytest.mark.skipif(SWEEP < 1, reason='FRF_SENSOR_SCENES=N sweeps N scenes of each kind')
def test_sensor_sweep():
    a = sensor_sweep(SWEEP, verbose=False)
    print({k: v for k, v in a.items() if k != 'runs'}, file=sys.stderr)
    check_sweep(a)
