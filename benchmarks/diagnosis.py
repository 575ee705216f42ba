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

The scenes are drawn in benchmarks/diagnosis_scenes.py, each run and scored in
benchmarks/diagnosis_scene_run.py; this module sweeps and aggregates them. The KUKA KR300
rows of section ``diagnosis_real`` are in benchmarks/diagnosis_kuka.py,
benchmarks/diagnosis_kuka_baseline.py and benchmarks/diagnosis_kuka_synthetic.py.
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path
import sys
import tempfile
import time
from typing import Any

from benchmarks.diagnosis_scene_run import run_scene
from benchmarks.diagnosis_scenes import EXTRA_KINDS, KINDS, MODEL, scene_of
import numpy as np

ROOT = Path(__file__).resolve().parents[1]


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


if __name__ == '__main__':
    args = [a for a in sys.argv[1:] if a != '--every']
    print(json.dumps({k: v for k, v in sweep(int(args[0]) if args else 42,
                                             int(args[1]) if len(args) > 1 else 2026,
                                             kind=args[2] if len(args) > 2 else None,
                                             every='--every' in sys.argv[1:]
                                             ).items() if k != 'runs'}, default=float))
