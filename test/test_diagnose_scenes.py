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
with the nominal config/model_3axis.yaml. Seeds are fixed (FRF_DIAG_SEED=random draws new
ones, printed and reproducible with FRF_DIAG_SEED=<seed>); the sweep over random scenes is
``make bench`` (section diagnosis).
"""
import math
import os
import sys

from benchmarks.diagnosis import draw_scene, run_scene
import numpy as np
import pytest


def _seed(offset: int) -> int:
    # fixed in make test (random seeds failed a per-scene floor in about 1 of 9 runs here, a
    # flaky CI); FRF_DIAG_SEED=<seed> or FRF_DIAG_SEED=random draws others; the rates over
    # random scenes are measured by the sweep (`make bench`)
    given = os.environ.get('FRF_DIAG_SEED', '2026')
    if given == 'random':
        return int.from_bytes(os.urandom(3), 'little')
    return int(given) + offset


@pytest.mark.slow
@pytest.mark.parametrize('kind', ['random', 'clean'])
def test_scene_of_the_reference_plant(kind, tmp_path):
    seed = _seed(0 if kind == 'random' else 1)
    scene = draw_scene(np.random.default_rng(seed), kind)
    print(f'FRF_DIAG_SEED={seed} kind={kind} hidden={scene["truth"]}', file=sys.stderr)
    r = run_scene(scene, tmp_path)
    msg = f'FRF_DIAG_SEED={seed}: {r}'
    if kind == 'clean':
        assert r['n_found'] == 0, msg
        return
    # per scene: at least half of the hidden (effect, axis) pairs named, at most one false
    # alarm, all but one found parameter within 20 % (the rates are measured by the sweep,
    # `make bench`; README lists them)
    assert r['hits'] >= math.ceil(r['n_hidden'] / 2), msg
    assert r['false_alarms'] <= 1, msg
    errs = list(r['param_errors'].values())
    assert sum(e < 0.2 for e in errs) >= len(errs) - 1, msg


@pytest.mark.slow
def test_unmodelled_second_mode_is_unexplained_on_its_axis(tmp_path):
    seed = _seed(2)
    scene = draw_scene(np.random.default_rng(seed), 'second_mode')
    print(f'FRF_DIAG_SEED={seed} mode={scene["mode"]}', file=sys.stderr)
    r = run_scene(scene, tmp_path)
    msg = f'FRF_DIAG_SEED={seed}: {r}'
    # what the diagnosis does in every scene of the sweep: no named effect for the mode, and
    # its axis listed as unexplained; whether the band contains the mode is measured by the
    # sweep (`make bench`: 4 of 6 scenes; README) and is not yet reliable enough to assert here
    assert r['n_found'] == 0, msg
    axis = f'joint_{scene["mode"][0] + 1}'
    assert axis in {u['axis'] for u in r['unexplained']}, msg
