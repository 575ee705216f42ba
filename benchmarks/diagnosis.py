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
Run the diagnosis sweep over random scenes of the independent plant.

Diagnosis sweep (``make bench``, section ``diagnosis``): random 3-axis scenes of the
independent reference plant (test/plants/reference.py, not FlexibleJointPlant) with 0-4 hidden
effects at realistic sizes, identified end to end through ``identify --plant`` (a bag) and
diagnosed through ``diagnose`` against the nominal model config/model_3axis.yaml.

Reports recall of hidden (effect, axis) pairs, false alarms among the reported effects, clean
scenes without effects, parameters within 20 %, and second modes named on their axis (or, not
named, reported as ``unexplained`` there with a band containing the mode; issue 57 and
benchmarks/second_mode.py).

``python -m benchmarks.diagnosis N [SEED [KIND [--every]]]`` runs N scenes (seeds SEED,
SEED + 1, ...; default 2026; only those of KIND, e.g. second_mode, when given; all N drawn as
KIND with ``--every`` and for kind ``mismatch``, which is not in the cycle: one axis' stiffness
5-20 % off the nominal model next to 1-2 drawn effects) and prints one JSON line per scene,
then the aggregate. With FRF_DIAG_LOG=1 every
scene's diagnosis log (each candidate's misfit before and after, refits, held-out checks) goes
to stderr: ``FRF_DIAG_LOG=1 python -m benchmarks.diagnosis 1 SEED`` shows scene SEED drawn as
kind ``random`` (the kind the tests draw for it when SEED % 8 < 3); ``1 SEED KIND --every``
draws it as KIND (a CI scene of any kind).
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path
import sys
import tempfile
import time
from typing import Any, TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from frf_ident.core.diagnosis import DiagnosisResult
    from frf_ident.core.model.params import RobotParams
    from frf_ident.core.recording import Recording

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / 'config' / 'model_3axis.yaml'
PLANT = 'plants.reference:ReferencePlant'
NOISE = 2e-5                      # velocity noise of the "real" robot [rad/s]
KINDS = ('random', 'random', 'random', 'two_on_one_axis', 'weak_axis_small', 'second_mode',
         'clean', 'gravity')
# the characteristic parameter of each effect, compared within 20 %
CHECK_KEY = {'coulomb_friction': 'coulomb_friction', 'viscous_friction': 'viscous_friction',
             'stiffness_nonlinearity': 'stiffness_k2', 'backlash': 'backlash',
             'torque_ripple': 'amplitude', 'time_delay': 'time_delay', 'gravity': 'amplitude',
             'parameter_mismatch': 'stiffness', 'second_mode': 'frequency_hz'}
# gravity, a parameter mismatch and a second mode: scene kinds of their own
DRAWN = tuple(k for k in CHECK_KEY if k not in ('gravity', 'parameter_mismatch', 'second_mode'))
# drawn only when asked for by name (not in the cycle, so the README sweeps keep their scenes):
# 'sensor' is the nominal plant read by a realistic sensor, 'sensor_two' the same with two
# small effects on two axes (issue 55); 'link_mode', 'link_mode_beside' a second mode (57)
EXTRA_KINDS = ('mismatch', 'sensor', 'sensor_two', 'link_mode', 'link_mode_beside')
#: the sensor effects the diagnosis names (issue 55), scored apart from the plant's
SENSOR_EFFECTS = ('velocity_from_encoder', 'quantisation')
#: [rad] the encoder steps of a realistic sensor are drawn log-uniformly between these
ENCODER_RANGE = (1e-6, 1e-5)
# issue 57: a second link-side mode, 10-25 % of the link's inertia, tuned to 15-45 Hz (with
# the link held), damping ratio 0.005-0.08 (log-uniform: as many light as heavy modes)
LINK_MODE_RATIO = (0.10, 0.25)
LINK_MODE_HZ = (15.0, 45.0)
LINK_MODE_DAMPING = (0.005, 0.08)


def _nominal() -> dict[str, Any]:
    from frf_ident.io.model_file import load_model
    return load_model(MODEL)[0]


def draw_effect(name: str, rng: np.random.Generator, axis: dict[str, Any],
                small: bool = False) -> dict[str, Any]:
    """
    Draw a random realistic change of one axis.

    Random realistic change of one axis for effect ``name`` (model-file keys); ``small``
    draws from the low end of the range (near the noise floor).
    """
    hi = 0.3 if small else 1.0

    def u(a, b):
        return float(a + (b - a) * rng.uniform(0.0, hi))
    if name == 'coulomb_friction':
        return {'coulomb_friction': u(4.0, 25.0)}
    if name == 'viscous_friction':
        return {'viscous_friction': axis['viscous_friction'] + u(20.0, 80.0)}
    if name == 'stiffness_nonlinearity':
        return {'stiffness_k2': axis['stiffness'] * u(1.3, 1.8),
                'stiffness_breakpoint': u(1.5e-4, 4e-4)}
    if name == 'backlash':
        return {'backlash': u(2e-5, 8e-5)}
    if name == 'torque_ripple':
        return {'torque_ripple': [{'amplitude': u(2.0, 8.0),
                                   'spatial_frequency': float(rng.uniform(60, 1500)),
                                   'phase': float(rng.uniform(-3, 3))}]}
    if name == 'time_delay':
        return {'time_delay': u(1e-3, 4e-3)}
    raise ValueError(f'{name=} is not one of {DRAWN}')


def draw_scene(rng: np.random.Generator, kind: str) -> dict[str, Any]:
    """
    Draw a random scene.

    A scene: {'scene': plug-in scene, 'truth': [(effect, axis index, params)], 'mode':
    (axis, Hz) or None, 'kind'}.
    """
    model = _nominal()
    axes = model['axes']
    truth: list[tuple[str, int, dict[str, Any]]] = []
    mode = None

    def add_random(k: int) -> None:
        used = {(t[0], t[1]) for t in truth}
        while len(truth) < k:
            name, ax = str(rng.choice(DRAWN)), int(rng.integers(3))
            if (name, ax) in used or (name == 'backlash' and any(
                    t[0] == 'stiffness_nonlinearity' and t[1] == ax for t in truth)):
                continue
            used.add((name, ax))
            truth.append((name, ax, draw_effect(name, rng, axes[ax])))
    if kind == 'random':
        add_random(int(rng.integers(1, 5)))
    elif kind == 'two_on_one_axis':
        ax = int(rng.integers(3))
        a, b = rng.choice(['coulomb_friction', 'torque_ripple', 'time_delay',
                           'stiffness_nonlinearity'], 2, replace=False)
        truth = [(str(a), ax, draw_effect(str(a), rng, axes[ax])),
                 (str(b), ax, draw_effect(str(b), rng, axes[ax]))]
    elif kind == 'weak_axis_small':
        truth = [('coulomb_friction', 1, draw_effect('coulomb_friction', rng, axes[1])),
                 ('coulomb_friction', 2, draw_effect('coulomb_friction', rng, axes[2],
                                                     small=True))]
    elif kind == 'gravity':
        # an axis the nominal model loads with a constant (its value at the operating point)
        # carries a link's weight G sin(q + phi) instead: the constant within 10 %, the
        # configuration dependence hidden (G from 1.2 to 4 times the load, either slope)
        ax = int(rng.choice([i for i, a in enumerate(axes) if a.get('gravity_torque')]))
        load = float(axes[ax]['gravity_torque']) * float(rng.uniform(0.9, 1.1))
        amp = abs(load) * float(rng.uniform(1.2, 4.0))
        phase = math.asin(load / amp)
        if rng.uniform() < 0.5:
            phase = math.pi - phase
        truth = [('gravity', ax, {'gravity': [{'amplitude': amp, 'phase': phase}],
                                  'gravity_torque': 0.0})]
        add_random(1 + int(rng.integers(0, 3)))      # and 0-2 other effects anywhere
    elif kind == 'mismatch':
        # as on every real robot, the nominal model's linear parameters are off: one axis'
        # stiffness 5-20 % either way, next to 1-2 drawn effects anywhere
        ax = int(rng.integers(3))
        scale = float(rng.uniform(1.05, 1.2)) ** (1 if rng.uniform() < 0.5 else -1)
        truth = [('parameter_mismatch', ax, {'stiffness': float(axes[ax]['stiffness']) * scale})]
        add_random(2 + int(rng.integers(0, 2)))      # the mismatch and 1-2 others
    elif kind == 'sensor_two':
        # two small effects of different kinds on two different axes
        ax = [int(a) for a in rng.choice(3, 2, replace=False)]
        names = [str(n) for n in rng.choice(DRAWN, 2, replace=False)]
        truth = [(n, a, draw_effect(n, rng, axes[a], small=True)) for n, a in zip(names, ax)]
    elif kind == 'second_mode':
        ax = int(rng.integers(3))
        mode = (ax, float(rng.uniform(18.0, 30.0)))
    elif kind in ('link_mode', 'link_mode_beside'):
        return _link_mode_scene(rng, kind, axes)
    sc: dict[str, Any] = {'axes': {}, 'velocity_noise': NOISE, 'seed': int(rng.integers(1e6))}
    if kind in ('sensor', 'sensor_two'):
        # every axis read by an encoder, its velocity the difference of two readings
        lo, hi = np.log(ENCODER_RANGE)
        sc['encoder_resolution'] = [float(np.exp(rng.uniform(lo, hi))) for _ in axes]
        sc['velocity_from_encoder'] = True
    for name, ax, ch in truth:
        sc['axes'].setdefault(str(ax), {}).update(ch)
    if mode:
        em = {'frequency_hz': mode[1], 'mass_ratio': float(rng.uniform(0.3, 0.5)),
              'damping_ratio': float(rng.uniform(0.01, 0.03))}
        sc['extra_mode'] = {str(mode[0]): em}
        # the mode in the model file's terms (docs/model_file.md): the inertia on the spring
        truth.append(('second_mode', mode[0], {'second_mode': {
            'frequency_hz': em['frequency_hz'], 'damping_ratio': em['damping_ratio'],
            'inertia': em['mass_ratio'] * axes[mode[0]]['link_inertia']}}))
    return {'scene': sc, 'truth': truth, 'mode': mode, 'kind': kind}


def _link_mode_scene(rng: np.random.Generator, kind: str, axes: list[dict[str, Any]]
                     ) -> dict[str, Any]:
    """
    Draw a scene with a second link-side mode (issue 57) on a random axis.

    ``link_mode_beside`` adds one drawn effect on another axis. The truth lists the mode as
    the effect ``second_mode`` with the model-file keys (docs/model_file.md): the reference
    plant takes ``mass_ratio`` of the link inertia onto the spring, the model file names that
    inertia.
    """
    ax = int(rng.integers(3))
    ratio = float(rng.uniform(*LINK_MODE_RATIO))
    hz = float(rng.uniform(*LINK_MODE_HZ))
    zeta = float(math.exp(rng.uniform(*np.log(LINK_MODE_DAMPING))))
    truth: list[tuple[str, int, dict[str, Any]]] = [
        ('second_mode', ax, {'second_mode': {'frequency_hz': hz, 'damping_ratio': zeta,
                                             'inertia': ratio * axes[ax]['link_inertia']}})]
    if kind == 'link_mode_beside':
        other = int(rng.choice([i for i in range(3) if i != ax]))
        name = str(rng.choice(DRAWN))
        truth.append((name, other, draw_effect(name, rng, axes[other])))
    sc: dict[str, Any] = {'axes': {}, 'velocity_noise': NOISE, 'seed': int(rng.integers(1e6))}
    for name, i, ch in truth[1:]:
        sc['axes'].setdefault(str(i), {}).update(ch)
    sc['extra_mode'] = {str(ax): {'frequency_hz': hz, 'mass_ratio': ratio,
                                  'damping_ratio': zeta}}
    return {'scene': sc, 'truth': truth, 'mode': (ax, hz), 'kind': kind}


def identification_config():
    """Short experiments (the demo's design, fewer realisations): a scene in about a minute."""
    from frf_ident.core.excitation.chirp_iteration import ChirpConfig
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    from frf_ident.core.simulation.runner import IdentificationConfig
    return IdentificationConfig(MultisineConfig(n_realisations=3, n_periods=2,
                                                resolution_hz=0.5),
                                ChirpConfig(duration=10.0, max_iterations=3))


def _diagnosis_log() -> None:
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
    _diagnosis_log()
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
    names = _nominal_names()
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


def second_mode_hz(scene: dict[str, Any], ax: int) -> float:
    """
    Return the frequency of the resonance that the extra link-side mode adds.

    Frequency [Hz] of the resonance the extra link-side mode adds to axis ``ax`` (motor,
    rigid link part and the mode's mass as a free 3-mass chain, the highest of its two
    modes): what the measured FRF shows, not the spring's link-held tuning.
    """
    a = _nominal()['axes'][ax]
    em = scene['scene']['extra_mode'][str(ax)]
    me = em['mass_ratio'] * a['link_inertia']
    ke = me * (2 * math.pi * em['frequency_hz']) ** 2
    m = np.diag([a['motor_inertia'], a['link_inertia'] - me, me])
    k1 = a['stiffness']
    k = np.array([[k1, -k1, 0.0], [-k1, k1 + ke, -ke], [0.0, -ke, ke]])
    w2 = np.sort(np.real(np.linalg.eigvals(np.linalg.solve(m, k))))
    return float(math.sqrt(max(w2[-1], 0.0)) / (2 * math.pi))


def _nominal_names() -> list[str]:
    return [a['name'] for a in _nominal()['axes']]


def scene_of(seed: int, k: int, kind: str | None = None) -> dict[str, Any]:
    """
    Return scene number ``k`` of the sweep that starts at ``seed``.

    Drawn as ``kind``, or as the cycle's kind when None.
    """
    return draw_scene(np.random.default_rng(seed + k), kind or KINDS[k % len(KINDS)])


def _run_numbered(seed: int, k: int, kind: str | None = None) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as tmp:
        r = run_scene(scene_of(seed, k, kind), Path(tmp))
    r['seed'] = seed + k
    return r


def sweep(n: int = 42, seed: int = 2026, verbose: bool = True, jobs: int | None = None,
          kind: str | None = None, every: bool = False) -> dict[str, Any]:
    """
    Run ``n`` scenes (kinds cycled, sizes drawn) and aggregate.

    Scenes run in ``jobs`` processes (default: one per CPU); the result does not depend on it.
    With ``kind`` only the scenes of that kind among the ``n`` run; all ``n``, drawn as that
    kind, with ``every`` or for a kind of EXTRA_KINDS.
    """
    from concurrent.futures import ProcessPoolExecutor
    jobs = jobs or os.cpu_count() or 1
    every = every or kind in EXTRA_KINDS
    ks = [k for k in range(n) if kind is None or every or KINDS[k % len(KINDS)] == kind]
    runs = []
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        for r in pool.map(_run_numbered, [seed] * len(ks), ks, [kind] * len(ks)):
            runs.append(r)
            if verbose:
                print(json.dumps(r, default=float), flush=True)
    return aggregate(runs)


def aggregate(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Recall, false alarms, clean scenes, parameter accuracy (per effect too), second modes."""
    hid = sum(r['n_hidden'] for r in runs)
    fnd = sum(r['n_found'] for r in runs)
    clean = [r for r in runs if r['kind'] == 'clean']
    perr = [v for r in runs for v in r['param_errors'].values()]
    named = [bool(r.get('mode_named')) for r in runs if r.get('mode_named') is not None]
    modes = [r['mode_unexplained'] for r in runs
             if r['mode_unexplained'] is not None and not r.get('mode_named')]
    firsts = [r['mode_band_first'] for r in runs
              if r.get('mode_band_first') is not None and not r.get('mode_named')]
    per: dict[str, list[int]] = {}
    for r in runs:
        for h in r['hidden']:
            per.setdefault(h.split('@')[0], []).append(int(h in r['found']))
    errs: dict[str, list[float]] = {}
    for r in runs:
        for k, e in r['param_errors'].items():
            errs.setdefault(k.split('@')[0], []).append(float(e))
    return {'n': len(runs), 'recall': sum(r['hits'] for r in runs) / max(hid, 1),
            'false_alarm_share': sum(r['false_alarms'] for r in runs) / max(fnd, 1),
            'clean_empty': sum(r['n_found'] == 0 for r in clean) / max(len(clean), 1),
            'param_within_20': float(np.mean([e < 0.2 for e in perr])) if perr else math.nan,
            'mode_named': sum(named) / len(named) if named else math.nan,
            'mode_unexplained': sum(modes) / max(len(modes), 1) if modes else math.nan,
            'mode_band_first': sum(firsts) / len(firsts) if firsts else math.nan,
            'unexplained_entries': sum(len(r['unexplained']) for r in runs),
            'bands_listed': sum(len(u['signature'].get('bands_hz', []))
                                for r in runs for u in r['unexplained']),
            'per_effect': {k: f'{sum(v)}/{len(v)}' for k, v in per.items()},
            'param_error_per_effect': {k: {'median': float(np.median(v)), 'max': float(max(v))}
                                       for k, v in errs.items()},
            # the counts behind the shares, as README quotes them
            'counts': {'found': f'{sum(r["hits"] for r in runs)}/{hid}',
                       'false_alarms': f'{sum(r["false_alarms"] for r in runs)}/{fnd}',
                       'clean_empty': f'{sum(r["n_found"] == 0 for r in clean)}/{len(clean)}',
                       'param_within_20': f'{sum(e < 0.2 for e in perr)}/{len(perr)}'},
            'simulations': sum(r['n_sims'] for r in runs),
            'median_wall_s': float(np.median([r['wall_s'] for r in runs])), 'runs': runs}


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def bench_rows() -> list[tuple[str, str, str, str]]:
    """
    Return the rows of ``make bench``.

    Rows of ``make bench``: the sweep, then diagnose wall time on the demo bag if present
    (out/demo/graph/bag of ``make demo``).
    """
    n = int(os.environ.get('FRF_BENCH_SCENES', '42'))
    r = sweep(n, verbose=False)
    rows = [(f'diagnosis sweep: recall of hidden pairs ({r["n"]} scenes)',
             f'{100 * r["recall"]:.0f} %', 'goal >= 90 %', ''),
            ('... false alarms among reported effects', f'{100 * r["false_alarm_share"]:.0f} %',
             'goal <= 5 %', ''),
            ('... clean scenes without effects', f'{100 * r["clean_empty"]:.0f} %',
             'goal >= 95 %', ''),
            ('... parameters within 20 %', f'{100 * r["param_within_20"]:.0f} %', 'goal >= 90 %',
             ''),
            ('... second mode named on its axis', f'{100 * r["mode_named"]:.0f} %',
             'not named: unexplained with its band '
             f'{100 * r["mode_unexplained"]:.0f} %', '')]
    pe = r['param_error_per_effect']
    rows += [(f'  {k}: found / parameter error median, max', v,
              f'{100 * pe[k]["median"]:.1f} %, {100 * pe[k]["max"]:.1f} %' if k in pe else '',
              '') for k, v in r['per_effect'].items()]
    bag = ROOT / 'out' / 'demo' / 'graph' / 'bag'
    if bag.exists():
        from frf_ident.app.diagnose import diagnose
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            res = diagnose(bag, MODEL, Path(tmp), progress=lambda _m: None)
            wall = time.perf_counter() - t0
        rows.append(('diagnose on the demo bag: wall time', f'{wall:.0f} s',
                     f'{res["result"].n_sims} simulations', 'goal < 120 s'))
        ev = res.result.detail.evaluator
        robot = res.result.extended
        t_loss = min(_timed(lambda: ev.loss(robot, 0)) for _ in range(3))
        rows.append(('... one candidate evaluation (simulate + estimate)', f'{t_loss:.2f} s',
                     '', ''))
    return rows


KUKA = ROOT.parent / 'shared' / 'data' / 'KUKA_KR300_Weigand2021' / 'recorded_FF_A_2020-10-21.mat'


def kuka_halves_rows() -> list[tuple[str, str, str, str]]:
    """
    Return the rows comparing the KUKA KR300 diagnosis of the two halves of trajectory A.

    Each half (5 s) is diagnosed on its own against config/model_kuka_kr300_axes123.yaml; rows:
    the effects each half names, every gravity term found in both halves (amplitude ratio,
    phase difference) and, as independent truth, the correlation of each half's fitted
    gravity torque of axis 3 with the authors' rigid-body gravity torque stored in the file
    (``tau_g_all``) over the whole trajectory. Empty when the data are not present.
    """
    if not KUKA.is_file():
        return []
    from frf_ident.app.diagnose import diagnose, load_data
    from frf_ident.bag import write_recording
    from frf_ident.core.recording import Recording
    from frf_ident.io.model_file import load_model
    from scipy.io import loadmat
    cfg = ROOT / 'config'
    rec = load_data(KUKA, cfg / 'map_kuka_kr300.yaml')
    tau_g = np.asarray(loadmat(KUKA, squeeze_me=True)['tau_g_all'])[:3].T
    n = rec.t.size // 2
    fits, errs, names, corr, unphysical = [], [], [], [], []
    # on an axis moving one way only the constant is load + Coulomb friction forward and
    # load - Coulomb backward: a different parameter in each half, per axis and direction
    consts: dict[str, dict[str, float]] = {}
    cross = []
    with tempfile.TemporaryDirectory() as tmp:
        bags = []
        for k, sl in enumerate((slice(0, n), slice(n, None), slice(0, None))):
            part = Recording(rec.t[sl] - rec.t[sl][0], rec.joint_names, rec.position[sl],
                             rec.velocity[sl], rec.effort[sl], meta=dict(rec.meta))
            bags.append(write_recording(part, Path(tmp) / f'half{k}'))
        for k, bag in enumerate(bags):
            # each half's extended model predicts the other half (data not used for fitting)
            res = diagnose(bag, cfg / 'model_kuka_kr300_axes123.yaml', Path(tmp) / f'd{k}',
                           validate=[bags[1 - k]] if k < 2 else [], progress=lambda _m: None)
            if k < 2:
                cross.append(res.report()['metrics']['validation_records'][0])
            one_way = _one_way(res.report())
            est = _estimates(res.report())
            fit = {key: v for key, (v, _) in est.items()}
            err = {key: se for key, (_, se) in est.items()}
            for e in res.report()['effects']:
                if 'gravity_torque' in e['parameters'] and e['axis'] in one_way:
                    consts.setdefault(e['axis'], {})[one_way[e['axis']]] = float(
                        e['parameters']['gravity_torque'])
            fits.append(fit)
            errs.append(err)
            if k < 2:
                names.append(sorted(f'{e["name"]}@{e["axis"]}'
                                    for e in res.report()['effects']))
                unphysical.append(', '.join(
                    f'{r["name"]}@{r["axis"]} {r["fitted_value"]:.3g}'
                    for r in res.report().get('rejected', []) if 'fitted_value' in r)
                    or 'none')
            robot = load_model(Path(tmp) / f'd{k}' / 'extended_model.yaml')[1]
            g3 = robot.gravity_load(rec.position[:, :3])[:, 2]
            corr.append(float(np.corrcoef(g3, tau_g[:, 2])[0, 1]) if np.std(g3) > 0
                        else math.nan)
    rows = [('KUKA A halves: effects of the first half', ', '.join(names[0]), '', ''),
            ('... of the second half', ', '.join(names[1]), '', '')]
    both = sorted(set(fits[0]) & set(fits[1]))
    z = {}
    for key in both:
        a, b = fits[0][key], fits[1][key]
        sa, sb = errs[0].get(key), errs[1].get(key)
        if sa is not None and sb is not None and (sa or sb):
            z[key] = abs(a - b) / math.hypot(sa, sb)
        rows.append((f'... {key[0]} {key[1]} (standard error)',
                     f'{a:.3g} ({sa:.2g}) / {b:.3g} ({sb:.2g})' if key in z else
                     f'{a:.3g} / {b:.3g}',
                     (f'ratio {b / a:.2f}' if a else '')
                     + (f', difference {z[key]:.1f} combined SE' if key in z else ''),
                     'goal within 20 %'))
    agree = sum(abs(fits[1][k] / fits[0][k] - 1) <= 0.2 for k in both if fits[0][k])
    rows.append(('... parameters of both halves within 20 %', f'{agree}/{len(both)}',
                 f'named in one half only: {len(set(fits[0]) ^ set(fits[1]))}', ''))
    # the record's own uncertainty (block-robust standard errors of each half) against the
    # other half: a difference beyond it is no noise, the model lacks a term there
    rows.append(('... differences within 2 combined standard errors',
                 f'{sum(v <= 2.0 for v in z.values())}/{len(z)}',
                 'relative standard error of each half: ' + ', '.join(
                     f'{100 * errs[0][k] / abs(fits[0][k]):.0f}/'
                     f'{100 * errs[1][k] / abs(fits[1][k]):.0f} %' for k in z),
                 'beyond 2: more than noise'))
    # the two one-way constants of an axis that goes out in one half and back in the other
    # hold Coulomb friction and load separately: (forward - backward) / 2 and their mean
    for ax, c in sorted(consts.items()):
        if len(c) < 2:
            continue
        full = fits[2].get((ax, 'coulomb_friction'))
        fc = (c['forward'] - c['backward']) / 2
        rows.append((f'... {ax} Coulomb from the two one-way constants',
                     f'{fc:.3g} (load {(c["forward"] + c["backward"]) / 2:+.3g})',
                     f'whole record {full:.3g}' if full else 'whole record: none',
                     f'ratio {fc / full:.2f}' if full else ''))
    for k, v in enumerate(cross):
        per = ' '.join(f'{v["baseline"]["per_axis"][a]["time_nrmse"]:.2f}->'
                       f'{v["extended"]["per_axis"][a]["time_nrmse"]:.2f}'
                       for a in v['baseline']['per_axis'])
        rows.append((f'... model of the {("first", "second")[k]} half on the '
                     f'{("second", "first")[k]}: time NRMSE nominal -> extended',
                     f'{v["baseline"]["time_nrmse"]:.3f} -> {v["extended"]["time_nrmse"]:.3f}',
                     f'axes 1-3: {per}', 'held out: the other half'))
    rows.append(('... fitted outside the physical range, dropped (each half)',
                 ' / '.join(unphysical), '', ''))
    rows.append(("... axis-3 gravity vs the authors' tau_g (r, each half)",
                 ' / '.join(f'{c:.3f}' for c in corr[:2]), f'whole record {corr[2]:.3f}', ''))
    # what the authors' rigid-body gravity depends on: sinusoids of the model's joint sets
    # leave part of it, the wrist's pitch (record joint 5) the rest
    shares = []
    for extra in ((), (4,)):
        cols = [np.ones(rec.t.size)]
        for js in [(1,), (1, 2)] + ([(1, 2) + extra] if extra else []):
            arg = rec.position[:, list(js)].sum(axis=1)
            cols += [np.sin(arg), np.cos(arg)]
        X = np.column_stack(cols)
        res = [tau_g[:, i] - X @ np.linalg.lstsq(X, tau_g[:, i], rcond=None)[0] for i in (1, 2)]
        shares.append(' / '.join(f'{100 * np.std(r) / np.std(tau_g[:, i]):.1f}'
                                 for r, i in zip(res, (1, 2))))
    rows.append(("... authors' tau_g of axes 2 / 3 left by sinusoids of q2, q2 + q3 [% of RMS]",
                 shares[0], f'adding q2 + q3 + q5 (the wrist): {shares[1]}',
                 'the 3-axis model cannot hold the wrist load'))
    # why the halves cannot agree: the trajectory goes out and back, so within a half an axis
    # whose velocity keeps one sign cannot tell Coulomb friction from a constant load, and
    # its gravity curve is seen over one sweep of its angle only
    share = []
    for sl in (slice(0, n), slice(n, None)):
        v = rec.velocity[sl, :3]
        moving = np.abs(v) > math.radians(1.0)
        share.append(' '.join(f'{100 * np.mean(v[moving[:, i], i] > 0):.0f}'
                              for i in range(3)))
    rows.append(('... share of moving samples with positive velocity, axes 1-3 [%]',
                 ' / '.join(share), 'one-signed: Coulomb = constant offset in that half', ''))
    return rows


#: directory with the authors' other trajectories, B.mat and C.mat (not in ../shared/data:
#: JonasWeigand/Robot_Identification, commit 9e403c07, data/recorded_trajectories/
#: "2020-10-21 10s FF {B,C} 08ms"/data.mat, MIT), e.g. KUKA_BC=<dir with B.mat and C.mat>
KUKA_BC_ENV = 'KUKA_BC'


def kuka_trajectories_rows() -> list[tuple[str, str, str, str]]:
    """
    Return the rows of the KUKA diagnosis of trajectories A, B and C, each on the others.

    Each whole trajectory is diagnosed against config/model_kuka_kr300_axes123.yaml with the
    other two as ``--validate`` records (experiments not used for fitting). Rows: each fit's
    held-out NRMSE and its nominal -> extended NRMSE on the other two, and per parameter the
    three fits (standard error) with how many of B and C lie within 20 % of A. Empty unless
    the environment variable KUKA_BC names a directory holding B.mat and C.mat.
    """
    if not os.environ.get(KUKA_BC_ENV):
        return []
    bc = Path(os.environ[KUKA_BC_ENV])
    paths = {'A': KUKA, 'B': bc / 'B.mat', 'C': bc / 'C.mat'}
    if not all(p.is_file() for p in paths.values()):
        return []
    from frf_ident.app.diagnose import diagnose
    cfg = ROOT / 'config'
    est, rows, slopes = {}, [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for x, p in paths.items():
            others = [q for y, q in paths.items() if y != x]
            res = diagnose(p, cfg / 'model_kuka_kr300_axes123.yaml', Path(tmp) / x,
                           map_path=cfg / 'map_kuka_kr300.yaml', validate=others,
                           progress=lambda _m: None)
            rep = res.report()
            est[x] = _estimates(rep)
            slopes[x] = _slopes_by_direction(res.recording, res.result.extended)
            m = rep['metrics']
            rows.append((f'KUKA trajectory {x} fitted: held-out NRMSE nominal -> extended',
                         f'{m["baseline"]["time_nrmse"]:.3f} -> {m["extended"]["time_nrmse"]:.3f}',
                         '; '.join(f'on {y}: {v["baseline"]["time_nrmse"]:.3f} -> '
                                   f'{v["extended"]["time_nrmse"]:.3f}'
                                   for y, v in zip([y for y in paths if y != x],
                                                   m['validation_records'])),
                         'other experiments, not used for fitting'))
    rows += _direction_rows(paths, slopes)
    keys = sorted(set().union(*(set(e) for e in est.values())))
    agree = named = 0
    for k in keys:
        cells = [f'{est[x][k][0]:.3g} ({est[x][k][1]:.2g})'
                 if k in est[x] and est[x][k][1] is not None else
                 (f'{est[x][k][0]:.3g}' if k in est[x] else '-') for x in 'ABC']
        near = [abs(est[x][k][0] / est['A'][k][0] - 1) <= 0.2 for x in 'BC'
                if k in est['A'] and k in est[x] and est['A'][k][0]]
        agree, named = agree + sum(near), named + len(near)
        rows.append((f'... {k[0]} {k[1]}: A / B / C (standard error)', ' / '.join(cells),
                     f'B, C within 20 % of A: {sum(near)}/{len(near)}', ''))
    rows.append(('... parameters of B and C within 20 % of A', f'{agree}/{named}', '', ''))
    return rows


def kuka_baseline_rows() -> list[tuple[str, str, str, str]]:
    """
    Return per axis and pooled the NRMSE of nominal / least squares / extended on B and C.

    KUKA trajectory A diagnosed with B and C as ``--validate`` records (issue #41), with the
    gravity the diagnosis fits per axis and, beside it, with the gravity of
    urdf/kuka_kr300_axes123.urdf (``--urdf``: base parameters fitted jointly): the extended
    model as fitted on A (after its gravity and ripple terms were kept or dropped on B and C)
    beside the 4-parameter least-squares baseline fitted on the same data, on A's held-out
    blocks and on B and C; per axis what became of its position-dependent terms and whether
    its effects were kept; the standard errors against the spread between A, B and C. Empty
    unless KUKA_BC names a directory holding B.mat and C.mat.
    """
    bc = Path(os.environ.get(KUKA_BC_ENV, '') or '/nonexistent')
    others = [bc / 'B.mat', bc / 'C.mat']
    if not all(p.is_file() for p in others):
        return []
    from frf_ident.app.diagnose import diagnose
    cfg = ROOT / 'config'
    rows = []
    for label, urdf in (('', None), (' --urdf', ROOT / 'urdf' / 'kuka_kr300_axes123.urdf')):
        with tempfile.TemporaryDirectory() as tmp:
            res = diagnose(KUKA, cfg / 'model_kuka_kr300_axes123.yaml', Path(tmp) / 'A',
                           map_path=cfg / 'map_kuka_kr300.yaml', validate=others, urdf=urdf,
                           progress=lambda _m: None)
        rows += _baseline_rows(res.report()['metrics'], others, label)
    return rows


def _baseline_rows(m: dict[str, Any], others: list[Path], label: str
                   ) -> list[tuple[str, str, str, str]]:
    """Return the rows of :func:`kuka_baseline_rows` of one report's metrics."""
    from frf_ident.core.diagnosis.thresholds import LS_BASELINE_MARGIN
    ls, rows = m['least_squares'], []
    names = {str(others[0]): 'B', str(others[1]): 'C'}
    for s in ls['held_out_as_fitted']:
        name = names.get(s['record'], 'A held out')
        t = s['time_nrmse']
        rows.append((f'KUKA A{label} fitted, on {name}: NRMSE nominal / LS / extended',
                     f'{t["nominal"]:.3f} / {t["least_squares"]:.3f} / {t["extended"]:.3f}',
                     'pooled over axes 1-3', ''))
        for ax, v in s['per_axis'].items():
            rows.append((f'... {ax}', f'{v["nominal"]:.3f} / {v["least_squares"]:.3f} / '
                                      f'{v["extended"]:.3f}', '',
                         'extended at or below LS' if v['extended'] <= v['least_squares']
                         else 'tie (within the 10 % margin)' if v['extended'] <= (
                             1 + LS_BASELINE_MARGIN) * v['least_squares']
                         else 'least squares wins'))
    for ax, v in m.get('position_terms_on_validate', {}).items():
        rows.append((f'KUKA A{label}: {ax} gravity/ripple on B / C, NRMSE with -> without',
                     ' / '.join(f'{a:.3f} -> {b:.3f}' for a, b in zip(v['with'], v['without'])),
                     'dropped: does not generalise' if v['dropped'] else 'kept', ''))
    for ax, v in ls['extended_vs_baseline'].items():
        rows.append((f'KUKA A{label}: {ax} extended vs baseline', v.split(';')[0][:26],
                     "effects replaced by the baseline's terms" if 'replaced' in v
                     else 'effects rejected' if 'rejected' in v else 'effects kept', ''))
    for s in ls['held_out']:
        name = names.get(s['record'], 'A held out')
        rows.append((f'KUKA A{label} after the baseline rule, on {name}: LS / extended',
                     ', '.join(f'{v["least_squares"]:.3f} / {v["extended"]:.3f}'
                               for v in s['per_axis'].values()),
                     f'pooled {s["time_nrmse"]["least_squares"]:.3f} / '
                     f'{s["time_nrmse"]["extended"]:.3f}',
                     'at or below LS (10 % margin) on every axis' if all(
                         v['extended'] <= (1 + LS_BASELINE_MARGIN) * v['least_squares']
                         for v in s['per_axis'].values()) else 'least squares wins on an axis'))
    se = m.get('standard_errors_across') or {}
    if se.get('rms_z') is not None:
        rows.append((f'KUKA A{label}: parameter differences A - B, A - C [combined standard '
                     f'errors], RMS', f'{se["rms_z"]:.2f}',
                     f'{len(se["pairs"])} pairs, chi-square p = {se["p_value"]:.2g}',
                     f'standard errors widened x{se["factor"]:.2g}' if se['factor'] > 1
                     else 'standard errors hold'))
    return rows


def _slopes_by_direction(rec: Recording, robot: RobotParams
                         ) -> dict[str, tuple[float, float, float]]:
    """
    Return per axis the viscous slope forward and backward that a record's residual shows.

    The residual of the extended model ``robot`` on ``rec`` (its joints the model's axes, as
    diagnose returns it; low-passed, moving rows) regressed on an offset, v and |v|: forward
    slope b + c_v + c_|v|, backward b + c_v - c_|v| (b the model's viscous friction), and the
    block-robust standard error of c_|v|, half their difference.
    """
    from frf_ident.core.diagnosis.regressors import model_residual, moving
    from frf_ident.core.diagnosis.residual import lowpass
    from frf_ident.core.diagnosis.selection import block_standard_errors
    from frf_ident.core.diagnosis.thresholds import FC_HZ
    f, _, v, _ = model_residual(rec, robot)
    rows = moving(v, rec.velocity, rec.fs, FC_HZ)
    out = {}
    for i, ax in enumerate(robot.axes):
        g = {k: lowpass(x, rec.fs, FC_HZ)[:, None] for k, x in (
            ('offset', np.ones(v.shape[0])), ('v', v[:, i]), ('abs', np.abs(v[:, i])))}
        y = lowpass(f[:, i], rec.fs, FC_HZ)
        X = np.column_stack(list(g.values()))[rows[:, i]]
        c = np.linalg.lstsq(X, y[rows[:, i]], rcond=None)[0]
        se = block_standard_errors(g, list(g), y, rows[:, i], rec.fs)['abs'][0]
        b = ax.viscous_friction + c[1]
        out[ax.name] = (b + c[2], b - c[2], float(se))
    return out


def _direction_rows(paths: dict[str, Path], slopes: dict[str, dict]
                    ) -> list[tuple[str, str, str, str]]:
    """Return per axis the rows of :func:`_slopes_by_direction` of each trajectory."""
    return [(f'... {ax} viscous slope forward / backward (half-difference SE): '
             + ' / '.join(paths), ' ; '.join(
                 '{:.3g} / {:.3g} ({:.2g})'.format(*slopes[x][ax]) for x in paths),
             'residual of each extended model on offset, v, |v|',
             'a one-way half measures one of them') for ax in slopes[next(iter(paths))]]


def _one_way(report: dict[str, Any]) -> dict[str, str]:
    """Return {axis: 'forward' or 'backward'} of the axes a report found moving one way only."""
    return {r['axis']: 'forward' if r['forward_share'] > 0.5 else 'backward'
            for r in report.get('rejected', []) if 'forward_share' in r}


def _estimates(report: dict[str, Any]) -> dict[tuple[str, str], tuple]:
    """
    Return {(axis, parameter): (value, standard error)} of a time-series report.

    One entry per scalar parameter and per gravity term (its amplitude); not the constant of
    an axis that moves one way only (load + the Coulomb friction of its direction, a different
    parameter in each half).
    """
    one_way = _one_way(report)
    out = {}
    for e in report['effects']:
        for key, val in e['parameters'].items():
            se = (e.get('standard_error') or {}).get(key)
            if key == 'gravity':
                for t, t_se in zip(val, se or [None] * len(val)):
                    out[e['axis'], 'gravity sin(' + ' + '.join(t['joints']) + ' + phi)'] = (
                        t['amplitude'], (t_se or {}).get('amplitude'))
            elif isinstance(val, (int, float)) and not (
                    key == 'gravity_torque' and e['axis'] in one_way):
                out[e['axis'], key] = (float(val), se)
    return out


def _report(res: DiagnosisResult) -> dict[str, Any]:
    """Return the effects and rejected candidates of a core result as report.json has them."""
    return {'effects': [e.to_dict() for e in res.effects],
            'rejected': [r.to_dict() for r in res.rejected]}


def kuka_synthetic_halves(runs: int = 20, seed: int = 0) -> dict[str, Any]:
    """
    Diagnose the halves of KUKA trajectory A on synthetic records of known truth.

    The truth is the whole record's extended model: its torque for the recorded motion
    (inverse dynamics) plus white noise at the level the record itself has
    (:func:`noise_level` of its residual), ``runs`` realisations; each half diagnosed on its
    own as in :func:`kuka_halves_rows`. Returns 'truth', 'sigma', 'real' (the real record's
    halves), 'est' ({parameter: per half the list of (value, standard error)}), 'named_both'
    and 'agree' ({parameter: records naming it in both halves, and of these the ones
    within 20 %}). Needs the KUKA data (:data:`KUKA`).
    """
    from frf_ident.app.diagnose import load_data
    from frf_ident.core.diagnosis.prediction import noise_level
    from frf_ident.core.diagnosis.regressors import model_residual
    from frf_ident.core.diagnosis.timeseries import diagnose_timeseries
    from frf_ident.core.recording import Recording
    from frf_ident.io.model_file import load_model
    robot = load_model(ROOT / 'config' / 'model_kuka_kr300_axes123.yaml')[1]
    full = load_data(KUKA, ROOT / 'config' / 'map_kuka_kr300.yaml')
    # the model's axes are the record's first joints (as diagnose maps them)
    rec = full.select_joints(full.joint_names[:robot.n_axes])
    whole = diagnose_timeseries(rec, robot)
    truth = _estimates(_report(whole))
    f = model_residual(rec, whole.extended)[0]
    sigma = np.sqrt(noise_level(f, rec.fs) * rec.fs / 2)
    n = rec.t.size // 2

    def halves(effort):
        out = []
        for sl in (slice(0, n), slice(n, None)):
            part = Recording(rec.t[sl] - rec.t[sl][0], rec.joint_names, rec.position[sl],
                             rec.velocity[sl], effort[sl])
            res = diagnose_timeseries(part, robot)
            out.append(_estimates(_report(res)))
        return out
    real = halves(rec.effort)
    rng = np.random.default_rng(seed)
    est: dict[tuple, list[list[tuple]]] = {}
    # per parameter: records whose two halves both name it, and of these the ones within 20 %
    named_both: dict[tuple, int] = {}
    agree_k: dict[tuple, int] = {}
    for _ in range(runs):
        u = rec.effort.copy()
        # the truth's torque for the recorded motion (between samples, as the residual)
        u[:-1] = rec.effort[:-1] - f + sigma * rng.standard_normal(f.shape)
        h = halves(u)
        for k in set(h[0]) & set(h[1]):
            named_both[k] = named_both.get(k, 0) + 1
            agree_k[k] = agree_k.get(k, 0) + int(
                bool(h[0][k][0]) and abs(h[1][k][0] / h[0][k][0] - 1) <= 0.2)
        for j in (0, 1):
            for k, x in h[j].items():
                est.setdefault(k, [[], []])[j].append(x)
    return {'truth': truth, 'sigma': sigma, 'real': real, 'est': est,
            'named_both': named_both, 'agree': agree_k}


def kuka_synthetic_halves_rows(runs: int = 20, seed: int = 0) -> list[tuple[str, str, str, str]]:
    """
    Return the rows of the KUKA halves repeated on synthetic records of known truth.

    What can the halves of trajectory A determine at all? The whole record's extended model is
    taken as the truth: its torque for the recorded motion (inverse dynamics) plus white noise
    at the level the record itself has (:func:`noise_level` of its residual), ``runs``
    realisations. Each half is diagnosed on its own as in :func:`kuka_halves_rows`. Rows: the
    share of parameters named in both halves that agree within 20 % (the goal), and per
    parameter the mean and Monte-Carlo spread of each half's estimate against the truth, the
    records whose halves agree within 20 % (of those naming it in both), the mean reported
    standard error against that spread, and the real record's halves. A real
    difference far outside the synthetic spread is no noise: the model lacks a term there.
    """
    if not KUKA.is_file():
        return []
    syn = kuka_synthetic_halves(runs, seed)
    truth, sigma, real, est = syn['truth'], syn['sigma'], syn['real'], syn['est']
    named_both, agree_k = syn['named_both'], syn['agree']
    real_both = set(real[0]) & set(real[1])
    real_agree = sum(abs(real[1][k][0] / real[0][k][0] - 1) <= 0.2 for k in real_both)
    agree, pairs = sum(agree_k.values()), sum(named_both.values())
    rows = [("KUKA A halves on synthetic records (the whole record's extended model as truth, "
             f'white noise {", ".join(f"{s:.2f}" for s in sigma)} N m as measured), '
             f'{runs} records: parameters of both halves within 20 %',
             f'{agree}/{pairs} ({100 * agree / max(pairs, 1):.0f} %)',
             f'real record {real_agree}/{len(real_both)}',
             'what the halves can determine under noise alone')]
    for k in sorted(est, key=lambda k: (k[0], k[1])):
        cells, ratio = [], []
        for j in (0, 1):
            x = np.array([v for v, _ in est[k][j]], float)
            se = np.array([s if s is not None else math.nan for _, s in est[k][j]], float)
            if x.size < 2:
                cells.append(f'named {x.size}/{runs}')
                continue
            sd = float(np.std(x, ddof=1))
            cells.append(f'{x.mean():.3g} +- {sd:.2g} ({x.size}/{runs})')
            if np.isfinite(se).any() and sd > 0:
                ratio.append(f'{np.nanmean(se) / sd:.1f}')
        rr = ' / '.join(f'{real[j][k][0]:.3g}' if k in real[j] else '-' for j in (0, 1))
        rows.append((f'... {k[0]} {k[1]}: each half, mean +- spread (named)',
                     ' / '.join(cells),
                     f'truth {truth[k][0]:.3g}; real halves {rr}' if k in truth else
                     f'truth: none; real halves {rr}',
                     '; '.join(x for x in (
                         f'halves within 20 % {agree_k[k]}/{named_both[k]}'
                         if k in named_both else '',
                         f'reported SE / spread {" / ".join(ratio)}' if ratio else '') if x)))
    return rows


if __name__ == '__main__':
    args = [a for a in sys.argv[1:] if a != '--every']
    print(json.dumps({k: v for k, v in sweep(int(args[0]) if args else 42,
                                             int(args[1]) if len(args) > 1 else 2026,
                                             kind=args[2] if len(args) > 2 else None,
                                             every='--every' in sys.argv[1:]
                                             ).items() if k != 'runs'}, default=float))
