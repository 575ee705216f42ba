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
Sweep scenes with a realistic sensor (issue 55 items 1-2; section ``diagnosis_sensor``).

Scenes of the independent reference plant (test/plants/reference.py) read by a realistic
sensor: encoder steps drawn log-uniformly in 1e-6..1e-5 rad per axis, the velocity the
difference of two readings over a sample, 2e-5 rad/s noise. Kind ``sensor``: the nominal
plant (nothing to name but the sensor); kind ``sensor_two``: two small effects of different
kinds on two different axes. Measured: the nominal scenes without a plant effect named, the
sensor named on every axis, the held-out gain rule's false-alarm rate (the share of the
spurious effects the held-out check judged that passed it), and in the two-effect scenes
recall and what the other axes borrowed.

``python -m benchmarks.diagnosis_sensor N [SEED]`` runs N scenes of each kind from SEED
(default 55000), one JSON line per scene, then the aggregate;
``FRF_SENSOR_SCENES`` sets N for the section (default 20); ``FRF_SENSOR_RUNS=FILE`` writes
every scene's score there as JSON.
"""
from __future__ import annotations

import json
import os
from pathlib import Path
import sys
from typing import Any

from benchmarks.diagnosis import sweep

__all__ = ['rows', 'sensor_aggregate', 'sensor_sweep']

SEED = 55000


def sensor_sweep(n: int = 20, seed: int = SEED, verbose: bool = True) -> dict[str, Any]:
    """Run ``n`` scenes of kind 'sensor' and of 'sensor_two' from ``seed`` and aggregate."""
    runs = []
    for kind in ('sensor', 'sensor_two'):
        runs += sweep(n, seed, verbose=verbose, kind=kind)['runs']
    return sensor_aggregate(runs)


def sensor_aggregate(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Return the issue's figures of a list of scored sensor scenes."""
    nominal = [r for r in runs if r['kind'] == 'sensor']
    two = [r for r in runs if r['kind'] == 'sensor_two']
    tests = [(k, t) for r in runs for k, t in r['gain_tests'].items()]
    spurious = [t for r in nominal for t in r['gain_tests'].values()]
    true = [t for _, t in tests if t[3]]
    false_two = [t for r in two for t in r['gain_tests'].values() if not t[3]]
    hidden_axes = [{h.split('@')[1] for h in r['hidden']} for r in two]
    borrowed = sum(sum(f.split('@')[1] in ax and f not in r['hidden'] for f in r['found'])
                   for r, ax in zip(two, hidden_axes))
    res_err = [e for r in runs for e in r['sensor_resolution_error'].values()]
    return {
        'nominal_scenes': len(nominal),
        'nominal_without_plant_effect': sum(r['n_found'] == 0 for r in nominal),
        'sensor_on_every_axis': sum(r['sensor_missed'] == 0 for r in runs),
        'scenes': len(runs),
        'sensor_false': sum(r['sensor_false'] for r in runs),
        'resolution_within_1pct': f'{sum(e < 0.01 for e in res_err)}/{len(res_err)}',
        'gain_rule_false_alarms': f'{sum(t[2] for t in spurious + false_two)}/'
                                  f'{len(spurious) + len(false_two)}',
        'gain_rule_true_passed': f'{sum(t[2] for t in true)}/{len(true)}',
        'two_effect_scenes': len(two),
        'recall': f'{sum(r["hits"] for r in two)}/{sum(r["n_hidden"] for r in two)}',
        'both_found': sum(r['hits'] == r['n_hidden'] for r in two),
        'false_alarms': f'{sum(r["false_alarms"] for r in two)}/'
                        f'{sum(r["n_found"] for r in two)}',
        'borrowed_by_an_effect_axis': borrowed,
        'runs': runs}


def rows() -> list[tuple[str, str, str, str]]:
    """Return the section's rows."""
    n = int(os.environ.get('FRF_SENSOR_SCENES', '20'))
    a = sensor_sweep(n, verbose=False)
    runs = os.environ.get('FRF_SENSOR_RUNS', '')
    if runs:
        Path(runs).write_text(json.dumps(a['runs'], default=float, indent=1))
    return [
        (f'sensor scenes ({a["nominal_scenes"]} nominal): no plant effect named',
         f'{a["nominal_without_plant_effect"]}/{a["nominal_scenes"]}', 'goal all', ''),
        ('... sensor effects named on every axis (all scenes)',
         f'{a["sensor_on_every_axis"]}/{a["scenes"]}',
         f'named where absent: {a["sensor_false"]}', ''),
        ('... encoder step read within 1 %', a['resolution_within_1pct'], '', ''),
        ('... held-out gain rule: spurious effects passing', a['gain_rule_false_alarms'],
         'bound 0.13 % each (z > 3)', ''),
        ('... held-out gain rule: true effects passing', a['gain_rule_true_passed'], '', ''),
        (f'two small effects on two axes ({a["two_effect_scenes"]} scenes): recall',
         a['recall'], f'both found in {a["both_found"]}', ''),
        ('... false alarms among named effects', a['false_alarms'],
         f'borrowed by an effect axis: {a["borrowed_by_an_effect_axis"]}', '')]


if __name__ == '__main__':
    argv = sys.argv[1:]
    out = sensor_sweep(int(argv[0]) if argv else 20, int(argv[1]) if len(argv) > 1 else SEED)
    print(json.dumps({k: v for k, v in out.items() if k != 'runs'}))
