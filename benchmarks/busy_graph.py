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
The lockstep graph on a busy PC: multisine + 3 chirp iterations with the default watchdog.

Issue 44: at load 4-12 the wall-time watchdog (0.5 s) aborted 3 of 4 lockstep multisine runs
although nothing was lost. Two busy-loop processes hold both cores (on top of whatever else
runs) while the graph (plant with its PI, excitation, estimator) runs a short multisine and
3 chirp-iteration steps with the shipped watchdog settings (``stale_s`` in simulation time,
``plant_silent_s`` 10 s wall). Rows: wall time and steps/s of each run, and its longest wall
gap between joint states beside the old wall-time limit (a gap above it aborted the run
before).

Run: ``python -m benchmarks busy_graph``.
"""
from __future__ import annotations

import os
from pathlib import Path
import subprocess
import sys
import tempfile
import time

from frf_ident.app.excitation_settings import SessionSettings
from frf_ident.app.graph import Graph
from frf_ident.core.excitation.chirp_iteration import ChirpConfig
from frf_ident.core.excitation.multisine_procedure import MultisineConfig

#: the wall-time staleness limit of the lockstep watchdog before issue 44 [s]
OLD_WALL_LIMIT_S = 0.5
BUSY = 'while True:\n    pass\n'


def _busy_loops(n: int) -> list[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, '-c', BUSY]) for _ in range(n)]


def rows(n_busy: int = 2, iterations: int = 3) -> list[tuple[str, str, str, str]]:
    """Run the graph while ``n_busy`` busy loops spin; one row per run and the totals."""
    ms = MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=1.0, compensate=False,
                         return_s=2.0, settle_s=0.3)
    # a tolerance of 0.001 dB is never met: all the steps run
    chirp = ChirpConfig(duration=6.0, max_iterations=iterations, tolerance_db=1e-3)
    busy = _busy_loops(n_busy)
    load = os.getloadavg()[0]
    out: list[tuple[str, str, str, str]] = []
    try:
        with tempfile.TemporaryDirectory(prefix='frf_busy_') as tmp:
            g = Graph(Path(tmp), multisine=ms, chirp=chirp)
            t0 = time.monotonic()
            g.start()
            try:
                res = g.drive(multisine=True, iterations=iterations)
            finally:
                g.stop()
            wall = time.monotonic() - t0
    finally:
        for p in busy:
            p.kill()
            p.wait()
    runs = [('multisine', res['multisine'])] + [
        (f'chirp iteration {i + 1}', r) for i, r in enumerate(res['iterations'])]
    for name, r in runs:
        rep = r['reply']
        gap = rep['max_gap_ms'] / 1e3
        out.append((f'{name}: steps/s ({n_busy} busy loops)',
                    f'{rep["steps_per_s"]:.0f} ({rep["experiment_time_s"]:.1f} s sim)',
                    f'gap {gap:.2f} s wall', f'{gap / OLD_WALL_LIMIT_S:.2f} x old limit'))
    done = sum(1 for _n, r in runs if r['success'])
    out.append((f'runs completed (load {load:.1f} at start)', f'{done} of {len(runs)}',
                f'{1 + iterations} started', f'{wall:.0f} s wall incl. start'))
    default = SessionSettings()
    out.append(('watchdog (lockstep)', f'stale_s {default.stale_s} s sim',
                f'was {OLD_WALL_LIMIT_S} s wall', f'+ {default.plant_silent_s:g} s wall'))
    return out
