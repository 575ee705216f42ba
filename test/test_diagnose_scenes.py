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
Hidden effects in the independent reference plant, end to end.

Hidden effects in the independent reference plant (test/plants/reference.py), end to end:
``identify --plant plants.reference:ReferencePlant`` records a bag, ``diagnose`` compares it
with the nominal config/model_3axis.yaml. Seeds are fixed in ``make test`` (random scenes of the
"random" kind break a per-scene floor in about 2 of 12 draws: seeds 9015, 9023 name a Coulomb
term and a damping mismatch for a viscous one; a CI that fails on a draw would be flaky);
FRF_DIAG_SEED=random draws new ones (printed; FRF_DIAG_SEED=<seed> repeats one). The rates over
many scenes are measured by the sweep (``make bench``, section diagnosis).
"""
import math
import os
import sys

from benchmarks.diagnosis import draw_scene, run_scene
import numpy as np
import pytest


def _seed(fixed: int) -> int:
    given = os.environ.get('FRF_DIAG_SEED', '')
    if given == 'random':
        return int.from_bytes(os.urandom(3), 'little')
    return int(given) if given else fixed


@pytest.mark.slow
@pytest.mark.parametrize('kind', ['random', 'clean'])
def test_scene_of_the_reference_plant(kind, tmp_path):
    seed = _seed(2026 if kind == 'random' else 2027)
    scene = draw_scene(np.random.default_rng(seed), kind)
    print(f'FRF_DIAG_SEED={seed} kind={kind} hidden={scene["truth"]}', file=sys.stderr)
    r = run_scene(scene, tmp_path)
    msg = f'FRF_DIAG_SEED={seed}: {r}'
    if kind == 'clean':
        assert r['n_found'] == 0, msg
        return
    # per scene: at least half of the hidden (effect, axis) pairs named, at most one false
    # alarm, at least half of the found parameters within 20 % (floors every one of the 84
    # scenes of both README sweeps meets; the rates are measured by the sweep, `make bench`)
    assert r['hits'] >= math.ceil(r['n_hidden'] / 2), msg
    assert r['false_alarms'] <= 1, msg
    errs = list(r['param_errors'].values())
    assert sum(e < 0.2 for e in errs) >= math.ceil(len(errs) / 2), msg


@pytest.mark.slow
def test_unmodelled_second_mode_is_unexplained_on_its_axis(tmp_path):
    seed = _seed(4707352)
    scene = draw_scene(np.random.default_rng(seed), 'second_mode')
    print(f'FRF_DIAG_SEED={seed} mode={scene["mode"]}', file=sys.stderr)
    r = run_scene(scene, tmp_path)
    msg = f'FRF_DIAG_SEED={seed}: {r}'
    # no named effect for the mode; its axis unexplained with a band around the resonance the
    # extra mode adds (within 10 %)
    assert r['n_found'] == 0, msg
    assert r['mode_unexplained'], msg


@pytest.mark.slow
@pytest.mark.parametrize('scale', [0.8, 1.2])
def test_stiffness_mismatch_is_named_with_its_value(scale, tmp_path):
    """
    Name a linear stiffness the nominal model gets wrong, with its value.

    The reference plant's joint_2 is 20 % softer / stiffer than the nominal model: a
    parameter_mismatch on joint_2 with the plant's stiffness (within 10 %), nothing else named,
    nothing unexplained (the structure is right, only a parameter is off).
    """
    k = 3.0e5 * scale
    scene = {'scene': {'axes': {'1': {'stiffness': k}}, 'velocity_noise': 2e-5, 'seed': 7},
             'truth': [], 'mode': None, 'kind': 'mismatch'}
    r = run_scene(scene, tmp_path)
    assert r['found'] == ['parameter_mismatch@joint_2'], r
    assert r['parameters']['parameter_mismatch@joint_2']['stiffness'] == pytest.approx(k, rel=0.1)
    assert r['unexplained'] == [], r
