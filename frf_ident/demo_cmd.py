"""`frf-ident demo --out DIR`: the node graph on the simulated robot, then estimate (+ diagnose).

Thin orchestration: :func:`frf_ident.nodes.graph.run_graph` (separate processes over DDS on
loopback), :func:`frf_ident.commands.estimate_bag`, and ``frf_ident.diagnose`` when present.
"""
from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from frf_ident.cli import command
from frf_ident.commands import subcommand
from frf_ident.errors import FrfIdentInputError

_CONFIG = Path(__file__).resolve().parents[1] / 'config'


@subcommand('demo', 'the main job: node graph on the simulated robot, estimation, diagnosis')
def _demo_args(p: argparse.ArgumentParser) -> None:
    p.add_argument('--out', type=Path, required=True, help='output directory')
    p.add_argument('--model', type=Path, help='nominal model for diagnosis (default '
                                              'config/model_3axis.yaml)')
    p.add_argument('--robot', type=Path, help='the simulated "real" robot (default '
                                              'config/robot_3axis_demo.yaml if present)')
    p.add_argument('--realisations', type=int, default=4)
    p.add_argument('--periods', type=int, default=3)
    p.add_argument('--resolution', type=float, default=0.5)
    p.add_argument('--chirp-duration', type=float, default=10.0)
    p.add_argument('--max-iterations', type=int, default=3)


@command('demo')
def _demo(args: argparse.Namespace) -> int:
    from frf_ident.commands import estimate_bag
    from frf_ident.core.procedures import ChirpConfig, MultisineConfig
    from frf_ident.nodes.graph import run_graph
    model = args.model or _CONFIG / 'model_3axis.yaml'
    robot = args.robot or (_CONFIG / 'robot_3axis_demo.yaml'
                           if (_CONFIG / 'robot_3axis_demo.yaml').is_file() else model)
    for p in (model, robot):
        if not Path(p).is_file():
            raise FrfIdentInputError(f'{p}: model file not found')
    out = Path(args.out)
    if (out / 'graph' / 'bag').exists():
        raise FrfIdentInputError(f'{out / "graph" / "bag"}: exists; choose a new --out')
    ms = MultisineConfig(n_realisations=args.realisations, n_periods=args.periods,
                         resolution_hz=args.resolution)
    ch = ChirpConfig(duration=args.chirp_duration, max_iterations=args.max_iterations)
    print(f'demo: robot {robot}, nominal model {model}', flush=True)
    bag, results = run_graph(out / 'graph', robot=robot, multisine=ms, chirp=ch,
                             log=lambda m: print(m, flush=True))
    print(f'demo: bag {bag}', flush=True)
    estimate_bag(bag, out / 'estimate')
    try:
        diagnose = importlib.import_module('frf_ident.diagnose')
    except ImportError:
        print('demo: frf_ident.diagnose not available; diagnosis skipped', flush=True)
        return 0
    entry = getattr(diagnose, 'main', None)
    if entry is not None:
        return int(entry([str(bag), '--model', str(model), '--out',
                          str(out / 'diagnosis')]) or 0)
    fn = getattr(diagnose, 'diagnose', None)
    if fn is None:
        print('demo: frf_ident.diagnose has no entry point; diagnosis skipped', flush=True)
        return 0
    fn(Path(bag), Path(model), out / 'diagnosis')
    print(f'demo: diagnosis in {out / "diagnosis"}', flush=True)
    return 0
