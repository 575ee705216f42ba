"""
Lockstep closed-loop speed of the node graph vs plain DDS ping-pong, in the same run.

``bench_lockstep()`` starts plant, controller and excitation node (and, for the second figure,
the estimator recording everything) as processes on a private loopback domain, runs a
multisine procedure in lockstep and reads the samples per wall second from the excitation
node; then it measures :func:`benchmarks.pingpong.dds_pingpong` (one
Float64MultiArray ping + one JointState pong between two processes = one lockstep step's
messages). Goal: graph >= 50 % of ping-pong.

Run: ``python -m benchmarks.graph``.
"""
from __future__ import annotations

import json
from pathlib import Path
import tempfile
from typing import Any, Optional

from frf_ident.app.graph import Graph


def _graph_rate(out: Path, nodes: tuple[str, ...], model: Optional[str],
                middleware: Optional[str] = None) -> dict[str, Any]:
    from frf_ident.core.excitation.procedures import MultisineConfig
    ms = MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=1.0, compensate=False)
    g = Graph(out, model=model, multisine=ms, nodes=nodes, middleware=middleware,
              params={'excitation_node': {'stale_s': 2.0}})
    g.start()
    try:
        res = g.drive(multisine=True, iterations=0)
    finally:
        g.stop()
    reply = res['multisine']['reply']
    return {'steps_per_s': reply['steps_per_s'], 'max_gap_ms': reply['max_gap_ms'],
            'samples': int(round(reply['experiment_time_s'] * 1000))}


def bench_lockstep(model: Optional[str] = None, n_pingpong: int = 3000) -> dict[str, Any]:
    """Measure the DDS graph: {'graph_steps_per_s', 'pingpong_per_s', 'ratio', ...}."""
    from benchmarks.pingpong import dds_pingpong
    with tempfile.TemporaryDirectory(prefix='frf_bench_') as tmp:
        bare = _graph_rate(Path(tmp) / 'bare', ('plant_node', 'controller_node',
                                                'excitation_node'), model)
        full = _graph_rate(Path(tmp) / 'full', ('plant_node', 'controller_node',
                                                'excitation_node', 'estimator_node'), model)
    pp = dds_pingpong(n_pingpong)
    return {'graph_steps_per_s': bare['steps_per_s'],
            'graph_max_gap_ms': bare['max_gap_ms'],
            'graph_with_recorder_steps_per_s': full['steps_per_s'],
            'graph_with_recorder_max_gap_ms': full['max_gap_ms'],
            'pingpong_per_s': pp,
            'ratio': bare['steps_per_s'] / pp,
            'ratio_with_recorder': full['steps_per_s'] / pp,
            'goal_ratio': 0.5}


def bench_backends(model: Optional[str] = None, n_pingpong: int = 3000) -> list[dict]:
    """
    Measure per backend (rclpy when importable, DDS always) graph and ping-pong rates.

    Both are measured back to back in the same run.
    """
    import importlib.util
    from benchmarks.pingpong import pingpong
    backends = (['rclpy'] if importlib.util.find_spec('rclpy') else []) + ['dds']
    rows = []
    for be in backends:
        with tempfile.TemporaryDirectory(prefix='frf_bench_') as tmp:
            bare = _graph_rate(Path(tmp) / 'bare', ('plant_node', 'controller_node',
                                                    'excitation_node'), model, be)
            full = _graph_rate(Path(tmp) / 'full', ('plant_node', 'controller_node',
                                                    'excitation_node', 'estimator_node'),
                               model, be)
        pp = pingpong(be, n_pingpong)
        rows.append({'backend': be, 'graph_steps_per_s': bare['steps_per_s'],
                     'graph_with_recorder_steps_per_s': full['steps_per_s'],
                     'pingpong_per_s': pp, 'ratio': bare['steps_per_s'] / pp,
                     'ratio_with_recorder': full['steps_per_s'] / pp})
    return rows


def rows() -> list[tuple[str, str, str, str]]:
    """``make bench`` rows: per backend, graph samples/s beside that backend's ping-pong."""
    out = []
    for r in bench_backends():
        be, pp = r['backend'], r['pingpong_per_s']
        out.append((f'{be} graph lockstep (plant, controller, excitation)',
                    f"{r['graph_steps_per_s']:,.0f} samples/s", f'{be} ping-pong {pp:,.0f}/s',
                    f"{100 * r['ratio']:.0f} %"))
        out.append((f'{be} graph ... with the estimator recording',
                    f"{r['graph_with_recorder_steps_per_s']:,.0f} samples/s",
                    f'{be} ping-pong {pp:,.0f}/s', f"{100 * r['ratio_with_recorder']:.0f} %"))
    return out


def main() -> None:
    print(json.dumps(bench_backends(), indent=1))


if __name__ == '__main__':
    main()
