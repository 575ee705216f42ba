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
Lockstep closed-loop speed of the node graph vs plain DDS ping-pong, in the same run.

``bench_backends()`` starts the node graph as processes on a private loopback domain, runs a
multisine procedure in lockstep and reads the samples per wall second from the excitation node;
then it measures :func:`benchmarks.pingpong.pingpong` of the same backend (one
Float64MultiArray ping + one JointState pong between two processes). Goals: >= 1,000 samples/s
under rclpy, the DDS graph >= 50 % of its ping-pong.

``free_running_gaps()`` runs the graph free-running on wall time, as on a robot, and reads the
longest gap between the joint states the excitation node saw in each run: what the default
``stale_samples`` (the watchdog's limit) must leave room for on this machine.

Run: ``python -m benchmarks.graph``.
"""
from __future__ import annotations

import json
from pathlib import Path
import tempfile
from typing import Any, Optional

from frf_ident.app.graph import Graph


def _graph_rate(out: Path, nodes: Optional[tuple[str, ...]], model: Optional[str],
                middleware: Optional[str] = None, lockstep: bool = True) -> dict[str, Any]:
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    ms = MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=1.0, compensate=False)
    # the watchdog out of the way: the run is measured, not judged
    params = {'excitation_node': {'stale_s': 2.0} if lockstep else {'stale_samples': 10 ** 6}}
    g = Graph(out, model=model, multisine=ms, nodes=nodes, middleware=middleware,
              lockstep=lockstep, params=params)
    g.start()
    try:
        res = g.drive(multisine=True, iterations=0)
    finally:
        g.stop()
    reply = res['multisine']['reply']
    return {'steps_per_s': reply['steps_per_s'], 'max_gap_ms': reply['max_gap_ms'],
            'samples': int(round(reply['experiment_time_s'] * 1000))}


def bench_backends(model: Optional[str] = None, n_pingpong: int = 3000) -> list[dict]:
    """
    Measure per backend (rclpy when importable, DDS always) graph and ping-pong rates.

    Graphs: the plant hosting the PI with the excitation node (the lockstep simulation as
    ``frf-ident demo`` and the launch file run it), the same with the estimator recording,
    and plant + controller_node + excitation (one plant -> controller -> plant round trip per
    sample). The ping-pong of the same backend is measured right after, in the same run.
    """
    import importlib.util
    from benchmarks.pingpong import pingpong
    backends = (['rclpy'] if importlib.util.find_spec('rclpy') else []) + ['dds']
    rows = []
    for be in backends:
        with tempfile.TemporaryDirectory(prefix='frf_bench_') as tmp:
            bare = _graph_rate(Path(tmp) / 'bare', ('plant_node', 'excitation_node'), model, be)
            full = _graph_rate(Path(tmp) / 'full', ('plant_node', 'excitation_node',
                                                    'estimator_node'), model, be)
            split = _graph_rate(Path(tmp) / 'split', ('plant_node', 'controller_node',
                                                      'excitation_node'), model, be)
        pp = pingpong(be, n_pingpong)
        rows.append({'backend': be, 'graph_steps_per_s': bare['steps_per_s'],
                     'graph_with_recorder_steps_per_s': full['steps_per_s'],
                     'graph_controller_node_steps_per_s': split['steps_per_s'],
                     'pingpong_per_s': pp, 'ratio': bare['steps_per_s'] / pp,
                     'ratio_with_recorder': full['steps_per_s'] / pp,
                     'ratio_controller_node': split['steps_per_s'] / pp})
    return rows


def free_running_gaps(runs: int = 3, middleware: Optional[str] = None) -> list[float]:
    """
    Return the longest joint-state gap [ms] the excitation node saw in each free-running run.

    Parameters
    ----------
    runs : int, optional
        How many multisine runs of the free-running graph (about 20 s each).
    middleware : str, optional
        The backend; default: the one the graph picks.

    Returns
    -------
    list of float

    """
    gaps = []
    for k in range(runs):
        with tempfile.TemporaryDirectory(prefix='frf_bench_') as tmp:
            gaps.append(_graph_rate(Path(tmp) / f'free{k}', None, None, middleware,
                                    lockstep=False)['max_gap_ms'])
    return gaps


def rows() -> list[tuple[str, str, str, str]]:
    """Return the ``make bench`` rows: per backend, graph samples/s beside its ping-pong."""
    out = []
    for r in bench_backends():
        be, pp = r['backend'], r['pingpong_per_s']
        base = f'{be} ping-pong {pp:,.0f}/s'
        for key, label in (('', 'lockstep graph (plant with PI, excitation)'),
                           ('_with_recorder', '... with the estimator recording'),
                           ('_controller_node', '... PI in controller_node (round trip)')):
            rate = r[f'graph{key}_steps_per_s']
            out.append((f'{be} {label}', f'{rate:,.0f} samples/s', base,
                        f'{100 * rate / pp:.0f} %'))
    from frf_ident.app.excitation_settings import SessionSettings
    limit = SessionSettings().stale_samples          # samples at the graph's 1 kHz: ms
    gaps = free_running_gaps()
    out.append(('free-running: longest joint-state gap per run', ' / '.join(
        f'{g:.1f}' for g in gaps) + ' ms', f'stale_samples default {limit} ms',
        f'{max(gaps) / limit:.2f} of the limit'))
    return out


def main() -> None:
    print(json.dumps(bench_backends(), indent=1))


if __name__ == '__main__':
    main()
