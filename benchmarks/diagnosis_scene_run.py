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
One scene of the diagnosis sweep end to end: identify, diagnose, score against its truth.

The scene's reference plant is identified through ``identify --plant`` into a bag
(:func:`identify_scene`), the bag diagnosed against the nominal model (:func:`diagnose_scene`)
and the report compared with the scene's hidden effects (:func:`score_scene`); scenes come
from benchmarks/diagnosis_scenes.py.
"""
from __future__ import annotations

from contextlib import contextmanager
import math
import os
from pathlib import Path
import sys
import time
from typing import Any, Iterator

from benchmarks.diagnosis_scenes import CHECK_KEY, MODEL, nominal_names, second_mode_hz

ROOT = Path(__file__).resolve().parents[1]
PLANT = 'plants.reference:ReferencePlant'
#: the sensor effects the diagnosis names (issue 55), scored apart from the plant's
SENSOR_EFFECTS = ('velocity_from_encoder', 'quantisation')


def identification_config():
    """Short experiments (the demo's design, fewer realisations): a scene in about a minute."""
    from frf_ident.core.excitation.chirp_iteration import ChirpConfig
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    from frf_ident.core.simulation.runner import IdentificationConfig
    return IdentificationConfig(MultisineConfig(n_realisations=3, n_periods=2,
                                                resolution_hz=0.5),
                                ChirpConfig(duration=10.0, max_iterations=3))


def diagnosis_log() -> None:
    """With FRF_DIAG_LOG=1 send the diagnosis' search trace (DEBUG log lines) to stderr."""
    if os.environ.get('FRF_DIAG_LOG', '') not in ('', '0'):
        import logging
        lg = logging.getLogger('frf_ident.core.diagnosis')
        if not lg.handlers:
            lg.addHandler(logging.StreamHandler(sys.stderr))
        lg.setLevel(logging.DEBUG)


def identify_scene(scene: dict[str, Any], bag: Path) -> Path:
    """Identify the scene's plant through ``--plant`` into the bag ``bag``; return it."""
    sys.path.insert(0, str(ROOT / 'test'))
    from frf_ident.app.identify import run_identify
    import plants.reference as ref
    ref.SCENE = scene['scene']
    try:
        run_identify(MODEL, PLANT, identification_config(), bag, progress=lambda _m: None)
    finally:
        ref.SCENE = {}
    return bag


def diagnose_scene(scene: dict[str, Any], bag: Path, out: Path, *, keep_report: bool = False,
                   **kw: Any) -> dict[str, Any]:
    """
    Diagnose a scene's bag against MODEL (``kw``: of ``diagnose``) and score it.

    With ``keep_report`` the score holds the report.json content too (``report``).
    """
    from frf_ident.app.diagnose import diagnose
    t0 = time.perf_counter()
    diagnosis_log()
    res = diagnose(bag, MODEL, out, progress=lambda _m: None, **kw)
    gains = getattr(res.result.detail, 'held_out_gains', {})
    r = score_scene(scene, res.report(), time.perf_counter() - t0, res.result.n_sims,
                    {k: (round(g.gain, 4), round(g.z, 2), g.beyond_noise)
                     for k, g in gains.items()})
    if keep_report:
        r['report'] = res.report()
    return r


def run_scene(scene: dict[str, Any], work: Path, *, keep_report: bool = False
              ) -> dict[str, Any]:
    """Identify the scene's plant through ``--plant`` into a bag, diagnose the bag."""
    return diagnose_scene(scene, identify_scene(scene, work / 'bag'), work / 'diag',
                          keep_report=keep_report)


def param_error(name: str, truth: dict[str, Any], found: dict[str, Any]) -> float:
    """Relative error of the effect's characteristic parameter."""
    key = CHECK_KEY[name]
    if name == 'second_mode':
        return abs(found[name][key] / truth[name][key] - 1)
    if key == 'amplitude':
        return abs(found[name][-1]['amplitude'] / truth[name][0]['amplitude'] - 1)
    if key not in truth:        # a mismatch of another parameter than the stiffness (damping)
        key = next(iter(truth))
    return abs(found.get(key, math.nan) / truth[key] - 1)


def score_scene(scene: dict[str, Any], report: dict[str, Any], wall: float = 0.0,
                n_sims: int = 0, gains: dict[str, tuple] | None = None) -> dict[str, Any]:
    """
    Compare a report with the scene's truth.

    ``gains``: the held-out check's gain test per effect it judged, 'name@axis' -> (gain
    [noise floors], z, beyond noise); each is marked true or spurious by the scene's truth.
    An effect with a value the record does not determine (``not_determined``) does not count
    as found, nor as a false alarm: it is listed under ``not_determined``.
    """
    names = nominal_names()
    hidden = {(n, names[a]): p for n, a, p in scene['truth']}
    found = {(e['name'], e['axis']): e['parameters'] for e in report['effects']
             if e['name'] not in SENSOR_EFFECTS and not e.get('not_determined')}
    loose = sorted(f'{e["name"]}@{e["axis"]}' for e in report['effects']
                   if e.get('not_determined'))
    sensor = {(e['name'], e['axis']): e['parameters'] for e in report['effects']
              if e['name'] in SENSOR_EFFECTS}
    has_sensor = bool(scene['scene'].get('velocity_from_encoder'))
    sensor_hidden = {(n, a) for n in SENSOR_EFFECTS for a in names} if has_sensor else set()
    hits = [k for k in hidden if k in found]
    perr = {f'{k[0]}@{k[1]}': param_error(k[0], hidden[k], found[k]) for k in hits}
    mode_ok = mode_first = mode_named = None
    if scene['mode']:
        ax = scene['mode'][0]
        fm = second_mode_hz(scene, ax)
        mode_named = ('second_mode', names[ax]) in found

        def near(b: list[float]) -> bool:
            return b[0] <= fm * 1.1 and b[1] >= fm * 0.9
        on_axis = [u['signature'] for u in report['unexplained'] if u['axis'] == names[ax]]
        mode_ok = any(near(b) for sig in on_axis for b in sig.get('bands_hz', []))
        mode_first = any(near(sig['band_hz']) for sig in on_axis if 'band_hz' in sig)
    return {'kind': scene['kind'], 'hidden': sorted(f'{n}@{a}' for n, a in hidden),
            'found': sorted(f'{n}@{a}' for n, a in found), 'not_determined': loose,
            'hits': len(hits), 'n_hidden': len(hidden),
            'false_alarms': len([k for k in found if k not in hidden]),
            'n_found': len(found), 'param_errors': perr, 'mode_named': mode_named,
            'mode_unexplained': mode_ok, 'mode_band_first': mode_first,
            'sensor_hidden': sorted(f'{n}@{a}' for n, a in sensor_hidden),
            'sensor_found': sorted(f'{n}@{a}' for n, a in sensor),
            'sensor_missed': len(sensor_hidden - set(sensor)),
            'sensor_false': len(set(sensor) - sensor_hidden),
            'unexplained': report['unexplained'], 'wall_s': round(wall, 1), 'n_sims': n_sims,
            'parameters': {f'{n}@{a}': p for (n, a), p in found.items()},
            'gain_tests': {k: [*v, tuple(k.split('@')) in hidden]
                           for k, v in (gains or {}).items()},
            'sensor_resolution_error': {
                a: abs(p['encoder_resolution'] / scene['scene']['encoder_resolution'][
                    names.index(a)] - 1)
                for (n, a), p in sensor.items()
                if n == 'quantisation' and has_sensor}}


@contextmanager
def scene_search(bag: Path) -> Iterator[Any]:
    """
    Yield the diagnosis' search state on a scene's bag against MODEL (its evaluator ``ev``).

    The start of the experiments route, as ``diagnose`` builds it: for figures about chosen
    models (the true one, a named one) in the diagnosis' own noise floors.
    """
    from frf_ident.app.diagnose import at_record_rate, load_records
    from frf_ident.core.diagnosis.experiments.pipeline import start
    from frf_ident.io.model_file import load_model
    _model, robot, ctrl = load_model(MODEL)
    rec, _others = load_records(bag, [], robot, MODEL, None, lambda _m: None)
    robot = at_record_rate(robot, rec, MODEL, bag, lambda _m: None)
    s = start(rec, robot, ctrl, jobs=1)
    try:
        yield s
    finally:
        s.ev.close()


def with_effects(robot: Any, effects: list[tuple[str, int, dict[str, Any]]]) -> Any:
    """Return ``robot`` with a scene's ``truth`` entries (name, axis, parameters) applied."""
    from frf_ident.core.diagnosis.common import apply_effect, Effect
    names = [a.name for a in robot.axes]
    for name, axis, params in effects:
        robot = apply_effect(robot, Effect(name, names[axis], 1.0, params, '', axis))
    return robot
