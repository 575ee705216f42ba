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
Where the true model of a sensor scene sits against the noise floor, per loss term.

``python -m benchmarks.sensor_floor SEED [STEP]`` identifies the two-effect sensor scene of
SEED (benchmarks/diagnosis_sensor.py, kind ``sensor_two``) and prints the true model's misfit
per axis and its loss terms in noise floors (the diagnosis' evaluator, with the sensor the
record shows); with STEP [rad] the same scene is drawn again with that encoder step on every
axis. A true model far above 1 on a term shows a floor that misses something no simulation
reproduces (docs/diagnosis/measured.md, "Sensor scenes": seed 13191138, and 1e-9).
"""
from __future__ import annotations

import copy
import json
from pathlib import Path
import sys
import tempfile

from benchmarks.diagnosis_scene_run import identify_scene, scene_search, with_effects
from benchmarks.diagnosis_scenes import scene_of
import numpy as np


def true_model_terms(scene: dict, bag: Path) -> dict:
    """Return the true model's misfit per axis and its loss terms in noise floors."""
    with scene_search(bag) as s:
        terms = s.ev.terms(with_effects(s.robot, scene['truth']))
        return {'misfit': np.round(s.ev.misfit(terms), 3).tolist(),
                'terms': {k: np.round(v / s.ev.floors[k], 3).tolist()
                          for k, v in terms.items()}}


def main(argv: list[str]) -> None:
    seed = int(argv[0])
    scene = copy.deepcopy(scene_of(seed, 0, 'sensor_two'))
    if len(argv) > 1:
        scene['scene']['encoder_resolution'] = [float(argv[1])] * len(
            scene['scene']['encoder_resolution'])
    with tempfile.TemporaryDirectory() as tmp:
        bag = identify_scene(scene, Path(tmp) / 'bag')
        out = true_model_terms(scene, bag)
    print(json.dumps({'seed': seed, 'encoder_resolution': scene['scene']['encoder_resolution'],
                      **out}))


if __name__ == '__main__':
    main(sys.argv[1:])
