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
The graph's speed with the live estimate on and off, in the same run (issue 52).

The lockstep graph as ``frf-ident demo`` runs it (plant with its PI, excitation, estimator
recording) runs the same multisine with the excitation node's ``live: true`` (the default:
an estimate after every whole MIMO period, published on /frf/live/* and recorded) and
``live: false``. The runs alternate off, on, off, on ... so a change of the machine's load
(it is shared) falls on both alike; the rows give each pair's steps/s and its ratio, and the
median of the pairs' ratios (goal: the live stream costs at most 10 %, a median >= 0.90).
On a shared machine steps/s follows the other users' load; the CPU time the three node
processes spend per 1000 steps (from /proc, during the run) does much less, so it is given
beside them: what the live stream costs in work.

Run: ``python -m benchmarks --markdown live_graph``.
"""
from __future__ import annotations

import os
from pathlib import Path
import statistics
import tempfile
from typing import Any

from frf_ident.app.graph import Graph
from frf_ident.core.excitation.multisine_procedure import MultisineConfig

#: the issue's goal: steps/s with the live stream at least this share of those without
GOAL = 0.90


def design() -> MultisineConfig:
    """Return the measured multisine: 2 realisations x 4 periods of 1.536 s on 3 axes."""
    return MultisineConfig(n_realisations=2, n_periods=4, resolution_hz=1.0, compensate=False,
                           return_s=2.0, settle_s=0.3)


def one_run(out: Path, live: bool) -> dict[str, Any]:
    """
    Run the graph once and return the excitation node's figures of its multisine.

    Parameters
    ----------
    out : Path
        Output folder of the graph (must not hold a bag).
    live : bool
        The excitation node's ``live`` parameter.

    Returns
    -------
    dict
        ``steps_per_s``, ``max_gap_ms``, ``experiment_time_s`` and ``cpu_ms_per_1000``
        (CPU time of the node processes during the run per 1000 steps).

    """
    g = Graph(out, multisine=design(), params={'excitation_node': {'live': live}})
    g.start()
    try:
        c0 = sum(_cpu_s(p.pid) for p in g.procs.values())
        reply = g.drive(multisine=True, iterations=0)['multisine']['reply']
        c1 = sum(_cpu_s(p.pid) for p in g.procs.values())
    finally:
        g.stop()
    out = {k: reply[k] for k in ('steps_per_s', 'max_gap_ms', 'experiment_time_s')}
    steps = reply['experiment_time_s'] * 1000.0                 # the graph runs at 1 kHz
    out['cpu_ms_per_1000'] = 1e6 * (c1 - c0) / steps
    return out


def _cpu_s(pid: int) -> float:
    """User + system CPU time [s] of a process (Linux /proc)."""
    with open(f'/proc/{pid}/stat') as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def rows(pairs: int = 5) -> list[tuple[str, str, str, str]]:
    """Run ``pairs`` off/on pairs of the graph; one row per pair and the medians."""
    off, on, cpu_off, cpu_on = [], [], [], []
    out = []
    with tempfile.TemporaryDirectory(prefix='frf_live_bench_') as tmp:
        for i in range(pairs):
            a = one_run(Path(tmp) / f'off{i}', False)
            b = one_run(Path(tmp) / f'on{i}', True)
            off.append(a['steps_per_s'])
            on.append(b['steps_per_s'])
            cpu_off.append(a['cpu_ms_per_1000'])
            cpu_on.append(b['cpu_ms_per_1000'])
            out.append((f'pair {i + 1}: live on vs off (steps/s; CPU ms per 1000 steps)',
                        f'{b["steps_per_s"]:,.0f}; {b["cpu_ms_per_1000"]:,.0f} ms',
                        f'{a["steps_per_s"]:,.0f}; {a["cpu_ms_per_1000"]:,.0f} ms',
                        f'{b["steps_per_s"] / a["steps_per_s"]:.2f}'))
    from frf_ident.core.excitation.multisine_procedure import multisine_procedure
    ratio = statistics.median(b / a for a, b in zip(off, on))
    sim = design()
    period = multisine_procedure(sim, 3, 1000.0)[1].period
    out.append((f'median of {pairs} pairs: lockstep graph with the estimator, multisine '
                f'{sim.n_realisations} x {sim.n_periods} periods of {period:.2f} s x 3 axes',
                f'live on {statistics.median(on):,.0f} steps/s',
                f'live off {statistics.median(off):,.0f} steps/s',
                f'{ratio:.2f} (goal >= {GOAL:.2f})'))
    c_on, c_off = statistics.median(cpu_on), statistics.median(cpu_off)
    out.append(('median CPU time of the node processes per 1000 steps',
                f'live on {c_on:,.0f} ms', f'live off {c_off:,.0f} ms',
                f'+{100 * (c_on / c_off - 1):.1f} %'))
    return out


def main() -> None:
    for r in rows():
        print(' | '.join(r))


if __name__ == '__main__':
    main()
