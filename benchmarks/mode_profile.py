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
How well the records of a mode scene tell a named mode from the true one.

``python -m benchmarks.mode_profile KIND SEED FREQUENCY_HZ DAMPING_RATIO INERTIA`` identifies
scene SEED of KIND (benchmarks/second_mode.py; FRF_MODE_BAGS=DIR reuses its bags) and prints,
in the diagnosis' noise floors, the misfit of the mode's axis with the true mode and with the
given one (the other hidden effects at their true values), the difference on the scale of the
misfit's own spread (chi-square of 2 x difference / misfit_sd^2, the determination test before
stop 65), the paired test of the records (experiments/noise_gain.py, fit part and held out)
of the given mode over the true one, the misfit with the true mode's frequency moved (damping
ratio and inertia over frequency squared kept) and the paired test of the given mode over
itself with its damping ratio halved and doubled. The figures of docs/diagnosis/measured.md
for scenes 4173340 and 9222933 come from it.
"""
from __future__ import annotations

import json
import os
from pathlib import Path
import sys
import tempfile

from benchmarks.diagnosis_scene_run import identify_scene, scene_search, with_effects
from benchmarks.diagnosis_scenes import scene_of

#: the true mode's frequency moved by these factors for the misfit's profile
PROFILE = (0.88, 0.93, 0.98, 1.0, 1.03, 1.08, 1.13, 1.18, 1.27)


def mode_profile(kind: str, seed: int, named: dict[str, float], bag: Path) -> dict:
    """Return the figures of the module docstring for ``named`` on scene ``seed`` of ``kind``."""
    from frf_ident.core.diagnosis.experiments.noise_gain import held_out_gain
    scene = scene_of(seed, 0, kind)
    (ax, truth), = [(a, p['second_mode']) for n, a, p in scene['truth'] if n == 'second_mode']
    with scene_search(bag) as s:
        base = with_effects(s.robot, [t for t in scene['truth'] if t[0] != 'second_mode'])

        def model(mode: dict[str, float]):
            return with_effects(base, [('second_mode', ax, {'second_mode': mode})])

        def pair(a: dict[str, float], b: dict[str, float], held: bool) -> str:
            g = held_out_gain(s.ev, model(a), model(b), ax, held_out=held)
            return f'z {g.z:.2f}, bound {g.bound_z:.2f}, gain {g.gain:.4f}'
        m_true, m_named = s.ev.loss(model(truth), ax), s.ev.loss(model(named), ax)
        out = {'axis': s.robot.axes[ax].name, 'truth': truth, 'named': named,
               'misfit true': round(m_true, 4), 'misfit named': round(m_named, 4),
               'chi-square on misfit_sd': round(2 * (m_true - m_named) / s.ev.misfit_sd() ** 2,
                                                1),
               'named over true, fit part': pair(named, truth, False),
               'named over true, held out': pair(named, truth, True),
               'misfit with the true frequency moved': {
                   f'{truth["frequency_hz"] * f:.1f} Hz': round(s.ev.loss(model(
                       {**truth, 'frequency_hz': truth['frequency_hz'] * f,
                        'inertia': truth['inertia'] * f ** 2}), ax), 4) for f in PROFILE},
               'named over its damping ratio x': {
                   f: pair(named, {**named, 'damping_ratio': named['damping_ratio'] * f}, False)
                   for f in (0.5, 2.0)}}
    return out


def main(argv: list[str]) -> None:
    kind, seed = argv[0], int(argv[1])
    named = dict(zip(('frequency_hz', 'damping_ratio', 'inertia'), map(float, argv[2:5])))
    bags = os.environ.get('FRF_MODE_BAGS')
    with tempfile.TemporaryDirectory() as tmp:
        bag = Path(bags) / f'{kind}_{seed}' if bags else Path(tmp) / 'bag'
        if not bag.exists():
            identify_scene(scene_of(seed, 0, kind), bag)
        print(json.dumps(mode_profile(kind, seed, named, bag), indent=1, default=float))


if __name__ == '__main__':
    main(sys.argv[1:])
