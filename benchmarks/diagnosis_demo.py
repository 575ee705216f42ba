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
Demo diagnosis wall time (section ``diagnosis_demo``): ``frf-ident diagnose`` of the demo bag.

The bag is `make demo`'s (OUT/demo/graph/bag, OUT from the environment as in the Makefile,
default out; or the path in FRF_DEMO_BAG). It is diagnosed twice in this run against the
nominal model config/model_3axis.yaml: one process simulating one model after the other
(``--jobs 1``, the path before the parallel simulations) and the default (candidates of a
round, a refit's starting simplex and the axes' FRF-shape candidates on 2 processes). Each row
gives the wall time beside the simulation count and the CPU time (this process and its
workers: what a quiet machine's wall time is bounded by), and whether both found the same
effects (names, axes, values to 4 digits) and metrics. Goal (issue 41): <= 30 s on 2 cores.

The machine's speed moves while it runs (a virtual machine: the same code took 27.0 s and
32.7 s within the hour, a single simulation 46 and 63 ms), so one row measures it in the same
run: one closed-loop simulation of the nominal model on the demo bag, best of 3, before and
after the diagnoses, and the 2-process wall time in units of it.

Issue 40 item 5 (stage 0, the frequency-domain physical fit that names a linear parameter
mismatch before the simulation search): the demo bag diagnosed a third time without it
(``fd_fit=False``, ``--no-fd-fit``), and a scene of the reference plant with one axis' stiffness
off (``python -m benchmarks.diagnosis 1 MISMATCH_SEED mismatch --every``) identified once and
diagnosed with and without it: wall time, simulations, the effects and the stiffness found.
"""
from __future__ import annotations

import os
from pathlib import Path
import resource
import tempfile
import time

__all__ = ['MISMATCH_SEED', 'demo_bag', 'rows']

#: the mismatch scene of the before/after rows: joint_3 15 % stiffer than the nominal model,
#: joint_2 with a Coulomb friction
MISMATCH_SEED = 2026

ROOT = Path(__file__).resolve().parent.parent


def demo_bag() -> Path:
    """Return where `make demo` wrote its bag (FRF_DEMO_BAG overrides)."""
    env = os.environ.get('FRF_DEMO_BAG')
    if env:
        return Path(env)
    return ROOT / os.environ.get('OUT', 'out') / 'demo' / 'graph' / 'bag'


def _effects(report: dict) -> list[tuple]:
    """Return the effects as (name, axis, parameters to 4 significant digits)."""
    def r4(v):
        if isinstance(v, float):
            return float(f'{v:.4g}')
        if isinstance(v, list):
            return [r4(x) for x in v]
        if isinstance(v, dict):
            return {k: r4(x) for k, x in v.items()}
        return v
    return sorted((e['name'], e['axis'], repr(r4(e['parameters']))) for e in report['effects'])


def _cpu_s() -> float:
    """Return the CPU seconds of this process and its finished children (user + system)."""
    return sum(u.ru_utime + u.ru_stime for u in (resource.getrusage(resource.RUSAGE_SELF),
                                                 resource.getrusage(resource.RUSAGE_CHILDREN)))


def rows() -> list[tuple[str, str, str, str]]:
    from frf_ident.app.diagnose import diagnose
    bag = demo_bag()
    if not bag.exists():
        return [('demo diagnose', f'no demo bag at {bag}', 'run `make demo` first', '-')]
    model = ROOT / 'config' / 'model_3axis.yaml'
    runs = {}
    speed = [_simulation_ms(bag, model)]
    with tempfile.TemporaryDirectory() as tmp:
        for jobs, fd in ((1, True), (2, True), (2, False)):
            t0, c0 = time.perf_counter(), _cpu_s()
            res = diagnose(bag, model, Path(tmp) / f'jobs{jobs}{fd}', jobs=jobs, fd_fit=fd)
            runs[jobs if fd else 'no_fd'] = (
                time.perf_counter() - t0, res.result.n_sims, _effects(res.report()),
                res.report()['metrics'], _cpu_s() - c0)
    speed.append(_simulation_ms(bag, model))
    (t1, n1, e1, m1, c1), (t2, n2, e2, m2, c2) = runs[1], runs[2]
    t0, n0, e0, m0, _ = runs['no_fd']
    load = os.getloadavg()[0]
    same = 'same effects' if e1 == e2 and m1 == m2 else 'EFFECTS OR METRICS DIFFER'
    return [('demo diagnose, 1 process (the serial path)',
             f'{t1:.1f} s, {n1} simulations, CPU {c1:.0f} s', f'{len(e1)} effects, held-out FRF '
             f'{m1["extended"]["frf_error_db"]:.3g} dB', f'load {load:.1f} on '
             f'{os.cpu_count()} cores'),
            ('demo diagnose, simulations on 2 processes (goal <= 30 s)',
             f'{t2:.1f} s, {n2} simulations, CPU {c2:.0f} s', f'1 process {t1:.1f} s; {same}',
             f'{t1 / t2:.2f}x'),
            ('demo diagnose with stage 0 (FD fit) vs without (--no-fd-fit), 2 processes',
             f'{t2:.1f} s, {n2} simulations: {_names(e2)}',
             f'without: {t0:.1f} s, {n0} simulations: {_names(e0)}',
             'same effects' if e0 == e2 and m0 == m2 else (
                 'same effects, other values' if _names(e0) == _names(e2)
                 else 'EFFECTS DIFFER')),
            ('machine speed: one simulation of the nominal model on the demo bag, best of 3, '
             'before / after the diagnoses', f'{speed[0]:.0f} / {speed[1]:.0f} ms',
             f'2 processes: {1e3 * t2 / max(speed):.0f} to {1e3 * t2 / min(speed):.0f} '
             f'simulation times', '-')] + mismatch_rows()


def _simulation_ms(bag: Path, model: Path) -> float:
    """Return the best of 3 closed-loop simulations of the nominal model on the bag [ms]."""
    from frf_ident.app.diagnose import load_data
    from frf_ident.core.diagnosis.common import bridge_gaps, simulate_like
    from frf_ident.io.model_file import load_model
    rec = bridge_gaps(load_data(bag))[0]
    _, robot, ctrl = load_model(model)
    best = float('inf')
    for _ in range(3):
        t0 = time.perf_counter()
        simulate_like(rec, robot, ctrl)
        best = min(best, time.perf_counter() - t0)
    return 1e3 * best


def _names(effects: list[tuple]) -> str:
    """Return 'name@axis, ...' of :func:`_effects` entries."""
    return ', '.join(f'{n}@{a}' for n, a, _ in effects) or 'none'


def mismatch_rows() -> list[tuple[str, str, str, str]]:
    """Return the before/after of stage 0 on the mismatch scene MISMATCH_SEED."""
    from benchmarks.diagnosis_scene_run import diagnose_scene, identify_scene
    from benchmarks.diagnosis_scenes import scene_of
    scene = scene_of(MISMATCH_SEED, 0, 'mismatch')
    _, ax, truth = scene['truth'][0]
    with tempfile.TemporaryDirectory() as tmp:
        bag = identify_scene(scene, Path(tmp) / 'bag')
        runs = {fd: diagnose_scene(scene, bag, Path(tmp) / f'diag{fd}', fd_fit=fd)
                for fd in (True, False)}

    def told(r: dict) -> str:
        found = {k: v for k, v in r['parameters'].items() if k.startswith('parameter_mismatch')}
        k = next(iter(found.values()), {}).get('stiffness')
        return (f'{r["wall_s"]:.1f} s, {r["n_sims"]} simulations, stiffness '
                + (f'{k:.4g} N m/rad' if k else 'not named')
                + f', {r["hits"]}/{r["n_hidden"]} hidden found, {r["false_alarms"]} false')
    return [(f'mismatch scene {MISMATCH_SEED}: stiffness of axis index {ax} '
             f'{truth["stiffness"]:.4g} '
             f'N m/rad; with stage 0 vs without', told(runs[True]),
             'without: ' + told(runs[False]),
             f'{runs[False]["wall_s"] / max(runs[True]["wall_s"], 1e-9):.2f}x')]
