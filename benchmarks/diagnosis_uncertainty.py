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
Check the diagnosed values against their standard errors on scenes of the independent plant.

Section ``diagnosis_uncertainty`` of ``make bench``: scenes of the reference plant
(test/plants/reference.py) with two effects on one axis that trade against each other
(backlash with viscous friction, Coulomb with viscous friction, a stiffening gear with a
joint-damping mismatch), identified and diagnosed end to end as in :mod:`benchmarks.diagnosis`.
Every value a report names is compared with the plant's: within 2 of its standard errors, or
labelled not determined (both rates), and never more than 3x off without the label. Then one
scene under NOISE_SEEDS noise realisations: the reported standard error against the spread of
the values.

``python -m benchmarks.diagnosis_uncertainty N [SEED [KIND]]`` runs N pair scenes (kinds
cycled, or all of KIND) from SEED and prints one JSON line per scene, then the rates;
``python -m benchmarks.diagnosis_uncertainty mc N [SEED]`` the Monte Carlo of :data:`MC_SCENE`
over noise seeds SEED .. SEED + N - 1.
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path
import sys
import tempfile
from typing import Any

from benchmarks.diagnosis_scene_run import run_scene
from benchmarks.diagnosis_scenes import draw_effect, MODEL, NOISE
import numpy as np

#: the pair kinds: two effects on one axis that trade against each other
PAIRS = {'backlash_viscous': ('backlash', 'viscous_friction'),
         'coulomb_viscous': ('coulomb_friction', 'viscous_friction'),
         'stiffening_damping': ('stiffness_nonlinearity', 'damping')}
#: the scene of the Monte Carlo: Coulomb and viscous friction on joint_2 (fixed values)
MC_SCENE = {'axes': {'1': {'coulomb_friction': 12.0, 'viscous_friction': 60.0}},
            'velocity_noise': NOISE}
MC_TRUTH = [('coulomb_friction', 1, {'coulomb_friction': 12.0}),
            ('viscous_friction', 1, {'viscous_friction': 60.0})]
#: noise realisations of the Monte Carlo
NOISE_SEEDS = 20


def nominal_axes() -> list[dict[str, Any]]:
    """Return the axes of the nominal model file (plain dicts, model-file keys)."""
    from frf_ident.io.model_file import load_model
    return load_model(MODEL)[0]['axes']


def draw_pair(rng: np.random.Generator, kind: str) -> dict[str, Any]:
    """
    Draw a scene with the two effects of ``kind`` on one random axis.

    Sizes as the sweep of :mod:`benchmarks.diagnosis` draws them; a joint-damping mismatch
    1.3-2.5 times the nominal damping, either way.
    """
    axes = nominal_axes()
    ax = int(rng.integers(3))
    truth = []
    for name in PAIRS[kind]:
        if name == 'damping':
            f = float(rng.uniform(1.3, 2.5)) ** (1 if rng.uniform() < 0.5 else -1)
            truth.append(('parameter_mismatch', ax, {'damping': float(axes[ax]['damping']) * f}))
        else:
            truth.append((name, ax, draw_effect(name, rng, axes[ax])))
    hidden: dict[str, Any] = {}
    for _, _, p in truth:
        hidden.update(p)
    return {'scene': {'axes': {str(ax): hidden}, 'velocity_noise': NOISE,
                      'seed': int(rng.integers(1e6))},
            'truth': truth, 'mode': None, 'kind': kind}


def pair_of(seed: int, kind: str | None = None) -> dict[str, Any]:
    """Return the pair scene of ``seed`` (kind cycled by the seed when None)."""
    kind = kind or list(PAIRS)[seed % len(PAIRS)]
    return draw_pair(np.random.default_rng(seed), kind)


def true_value(scene: dict[str, Any], axis: int, key: str) -> float:
    """Return the plant's value of a parameter (the scene's, else the nominal model's)."""
    a = dict(nominal_axes()[axis])
    a.update(scene['scene']['axes'].get(str(axis), {}))
    if key.endswith(' amplitude'):
        terms = a.get(key.split()[0]) or []
        return float(terms[0]['amplitude']) if terms else 0.0
    if key == 'stiffness_k2':
        return float(a.get('stiffness_k2') or a['stiffness'])
    return float(a.get(key) or 0.0)


def value_checks(scene: dict[str, Any], report: dict[str, Any]) -> list[dict[str, Any]]:
    """
    Return one entry per value a report names, against the plant's value.

    Scalar parameters and the amplitudes of added terms; each with its standard error, the
    plant's value, whether it is labelled not determined, within 2 standard errors of the
    truth, and more than 3x off.
    """
    names = [a['name'] for a in nominal_axes()]
    out = []
    for e in report['effects']:
        ax = names.index(e['axis'])
        se = e.get('standard_error') or {}
        loose = {n['parameter'] for n in e.get('not_determined', [])}
        for key, v in e['parameters'].items():
            if isinstance(v, list):
                errs = se.get(key) or [None] * len(v)
                items = [(f'{key} amplitude', v[-1]['amplitude'],
                          (errs[-1] or {}).get('amplitude'))]
            elif isinstance(v, (int, float)) and v != 0:
                items = [(key, v, se.get(key))]
            else:
                items = []
            for k, x, s in items:
                t = true_value(scene, ax, k)
                ratio = max(abs(x / t), abs(t / x)) if x and t else math.inf
                out.append({'effect': e['name'], 'axis': e['axis'], 'parameter': k,
                            'value': float(x), 'se': s, 'truth': t,
                            'determined': k not in loose,
                            'within_2se': s is not None and abs(x - t) <= 2 * float(s),
                            'off_3x': ratio > 3.0})
    return out


def run_pair(scene: dict[str, Any], seed: int) -> dict[str, Any]:
    """Identify and diagnose a scene; return its score with the value checks."""
    with tempfile.TemporaryDirectory() as tmp:
        r = run_scene(scene, Path(tmp), keep_report=True)
    r['values'] = value_checks(scene, r.pop('report'))
    r['seed'] = seed
    return r


def rates(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """
    Return the shares the issue asks for over the values of ``runs``.

    Beside them the share of the scenes' true effects named (not labelled not determined):
    a value never named is in no share of the values.
    """
    vals = [v for r in runs for v in r['values']]
    det = [v for v in vals if v['determined']]
    ok = [v['within_2se'] or not v['determined'] for v in vals]
    named = sum(len(set(r['hidden']) & set(r['found'])) for r in runs)
    return {'values': len(vals), 'refused': sum('refused' in r for r in runs),
            'true_effects_named': f'{named}/{sum(len(r["hidden"]) for r in runs)}',
            'within_2se_of_determined': f'{sum(v["within_2se"] for v in det)}/{len(det)}',
            'not_determined': f'{len(vals) - len(det)}/{len(vals)}',
            'within_2se_or_not_determined': float(np.mean(ok)) if ok else math.nan,
            'off_3x_unlabelled': sum(v['off_3x'] for v in det)}


def _pair_run(seed: int, kind: str | None) -> dict[str, Any]:
    """
    Run the pair scene of ``seed`` (a process pool's task).

    A scene the tool refuses to identify (its drawn effects ask for more torque than the
    limits allow: the chirp iteration's safety check) is kept as refused, with the reason,
    not lost with the sweep.
    """
    from frf_ident.errors import FrfIdentError
    scene = pair_of(seed, kind)
    try:
        return run_pair(scene, seed)
    except FrfIdentError as err:
        names = [a['name'] for a in nominal_axes()]
        return {'seed': seed, 'kind': scene['kind'], 'found': [], 'values': [],
                'hidden': sorted(f'{n}@{names[a]}' for n, a, _ in scene['truth']),
                'refused': f'{type(err).__name__}: {err}'}


def _mc_run(seed: int) -> dict[str, Any]:
    """Run the Monte Carlo scene under noise seed ``seed`` (a process pool's task)."""
    scene = {'scene': dict(MC_SCENE, seed=seed), 'truth': MC_TRUTH, 'mode': None,
             'kind': 'monte_carlo'}
    return run_pair(scene, seed)


def _pool_map(fn, *args, jobs: int | None = None):
    """Yield ``fn`` over ``args`` in order, the scenes run side by side (one per core)."""
    from concurrent.futures import ProcessPoolExecutor
    with ProcessPoolExecutor(max_workers=jobs or os.cpu_count() or 1) as pool:
        yield from pool.map(fn, *args)


def _record(r: dict[str, Any]) -> dict[str, Any]:
    """Return what is printed and kept of a scene: its truth, what was named, the checks."""
    return {x: r[x] for x in ('seed', 'kind', 'hidden', 'found', 'values', 'refused') if x in r}


def _save_runs(runs: list[dict[str, Any]]) -> None:
    """Append every scene's checks to ``FRF_UNCERTAINTY_RUNS`` (JSON lines), when set."""
    path = os.environ.get('FRF_UNCERTAINTY_RUNS', '')
    if path:
        with open(path, 'a') as f:
            for r in runs:
                f.write(json.dumps(_record(r), default=float) + '\n')


def sweep(n: int, seed: int, kind: str | None = None, jobs: int | None = None
          ) -> dict[str, Any]:
    """
    Run ``n`` pair scenes from ``seed`` (kinds cycled, or all ``kind``); print each.

    The scenes run side by side, ``jobs`` at a time (default one per core). Returns the
    rates over all scenes and, under ``per_kind``, those of each kind run.
    """
    runs = []
    seeds = [seed + k for k in range(n)]
    for r in _pool_map(_pair_run, seeds, [kind] * n, jobs=jobs):
        print(json.dumps(_record(r), default=float), flush=True)
        runs.append(r)
    _save_runs(runs)
    kinds = [k for k in PAIRS if any(r['kind'] == k for r in runs)]
    return {'n': len(runs), **rates(runs),
            'per_kind': {k: {'n': sum(r['kind'] == k for r in runs),
                             **rates([r for r in runs if r['kind'] == k])} for k in kinds}}


def monte_carlo(n: int = NOISE_SEEDS, seed: int = 0) -> dict[str, Any]:
    """
    Diagnose :data:`MC_SCENE` under ``n`` noise seeds; the standard error against the spread.

    Per parameter named in every run: the mean of the values, their standard deviation, the
    RMS of the reported standard errors and its ratio to the standard deviation.
    """
    vals: dict[str, list[tuple[float, float]]] = {}
    for r in _pool_map(_mc_run, [seed + k for k in range(n)]):
        print(json.dumps({'seed': r['seed'], 'values': r['values']}, default=float),
              flush=True)
        for v in r['values']:
            if v['se'] is not None:
                vals.setdefault(f'{v["parameter"]}@{v["axis"]}', []).append((v['value'], v['se']))
    out = {}
    for key, xs in vals.items():
        if len(xs) < n:
            continue
        x, s = np.array(xs).T
        sd = float(np.std(x, ddof=1))
        rms = float(np.sqrt(np.mean(s ** 2)))
        out[key] = {'mean': float(x.mean()), 'spread': sd, 'rms_se': rms,
                    'ratio': rms / sd if sd > 0 else math.inf}
    return out


def rows() -> list[tuple[str, str, str, str]]:
    """
    Return the rows of section ``diagnosis_uncertainty``.

    FRF_BENCH_SCENES pair scenes (default 21, kinds cycled) from seed 5800, then the Monte
    Carlo of :data:`MC_SCENE` over NOISE_SEEDS noise seeds; the scenes side by side, one per
    core. ``FRF_UNCERTAINTY_RUNS=FILE`` appends every pair scene's checks there (JSON lines).
    """
    n = int(os.environ.get('FRF_BENCH_SCENES', '21'))
    runs = list(_pool_map(_pair_run, [5800 + k for k in range(n)], [None] * n))
    _save_runs(runs)
    r = rates(runs)
    vals = [v for run in runs for v in run['values']]
    near = sum(abs(v['value'] / v['truth'] - 1) <= 0.2 for v in vals if v['truth'])
    out = [(f'pair scenes ({n}, seeds 5800-{5800 + n - 1}): values within 2 standard errors '
            'of the truth, or labelled not determined',
            f'{100 * r["within_2se_or_not_determined"]:.0f} % of {r["values"]}',
            f'within 20 % of the truth: {near}/{len(vals)}', 'goal >= 90 %'),
           ('... within 2 standard errors, of the values determined',
            r['within_2se_of_determined'], '', ''),
           ('... labelled not determined', r['not_determined'], '', ''),
           ('true effects named (a value not named counts in no share above)',
            r['true_effects_named'], f'scenes refused by identify: {r["refused"]}', ''),
           ('... more than 3x off without the label', str(r['off_3x_unlabelled']), '',
            'goal 0')]
    for kind in PAIRS:
        sub = rates([x for x in runs if x['kind'] == kind])
        out.append((f'  {kind}: within 2 SE of the determined / not determined / effects '
                    'named', f'{sub["within_2se_of_determined"]} / {sub["not_determined"]} / '
                    f'{sub["true_effects_named"]}', '', ''))
    mc = monte_carlo()
    for key, m in mc.items():
        out.append((f'Monte Carlo, {NOISE_SEEDS} noise seeds of one scene: {key}, RMS '
                    'standard error / spread of the values', f'{m["ratio"]:.2f}',
                    f'spread {m["spread"]:.3g}, RMS standard error {m["rms_se"]:.3g}, mean '
                    f'{m["mean"]:.4g}', 'goal 0.7-1.3'))
    return out


def main(argv: list[str]) -> None:
    """Command line: N [SEED [KIND]] pair scenes, or mc N [SEED]."""
    if os.environ.get('FRF_DIAG_LOG'):
        sys.stderr.write('diagnosis trace on stderr\n')
    if argv and argv[0] == 'mc':
        n = int(argv[1]) if len(argv) > 1 else NOISE_SEEDS
        print(json.dumps(monte_carlo(n, int(argv[2]) if len(argv) > 2 else 0), default=float))
        return
    n = int(argv[0]) if argv else 3
    seed = int(argv[1]) if len(argv) > 1 else 5800
    print(json.dumps(sweep(n, seed, argv[2] if len(argv) > 2 else None), default=float))


if __name__ == '__main__':
    main(sys.argv[1:])
