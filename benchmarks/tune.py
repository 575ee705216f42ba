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
``frf-ident tune`` on a 3x3 FRF campaign of 9 poses (section ``tune``; goal < 5 s).

The campaign of test/plants/campaign.py: the exact sampled FRFs of the 3-axis robot of
config/model_3axis_resonant.yaml with heavier drives at 9 link inertia scales 0.5-2 (the
resonances move by 30-46 %), 237 lines 2-120 Hz, 1 % noise, written as 9 estimate folders.
Timed: ``run_tune`` as the command runs it (reading, mode fits, weights, search, checks with
50 draws of the nominal FRF, every file), and its fits, weights and search alone; wall and
CPU time of this process (on a shared machine the wall time also counts the others' load).
Beside it the simplest honest baseline: the PI ``loop --propose`` reads off the nominal FRF
for the bandwidth tune reached (frf_ident/core/loop/design.py, no filters, one pose): its
time, and both settings' worst margins over the 9 poses on the noise-free FRFs (python-control).
"""
from __future__ import annotations

from pathlib import Path
import sys
import tempfile
import time
import warnings

import numpy as np

__all__ = ['SCALES', 'rows']

#: the 9 poses' link inertia scales
SCALES = np.geomspace(0.5, 2.0, 9)


def _worst(settings, robots, dt):
    """Worst GM [dB], PM [deg], MM over poses and axes on the exact FRFs (python-control)."""
    import control
    from plants.campaign import FREQ_HZ, true_frf
    worst = np.array([np.inf, np.inf, np.inf])
    for rob in robots:
        p = true_frf(rob)
        for j, s in enumerate(settings):
            lo = p[j, j] * s.response(FREQ_HZ, dt)
            with warnings.catch_warnings():
                warnings.simplefilter('ignore')
                gm, pm, sm, *_ = control.stability_margins(
                    control.frd(lo, 2 * np.pi * FREQ_HZ), method='frd')
            gm = 20 * np.log10(gm) if np.isfinite(gm) else np.inf
            worst = np.minimum(worst, [gm, pm, sm])
    return worst


def rows() -> list[tuple[str, str, str, str]]:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'test'))
    from plants.campaign import pose_robot, resonances_hz, write_campaign  # noqa: I100
    from frf_ident.app.loop import propose_gains
    from frf_ident.app.tune import run_tune, tune_campaign
    from frf_ident.app.tune_inputs import read_campaign
    from frf_ident.core.loop.shaping import AxisSetting
    from frf_ident.core.loop.targets import TuneTargets
    import frf_ident.report.tune_figures  # noqa: F401 (matplotlib: not timed)
    robots = [pose_robot(s) for s in SCALES]
    modes = np.array([resonances_hz(r) for r in robots])
    spread = 100 * (modes.max(axis=0) / modes.min(axis=0) - 1)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        dirs = write_campaign(root / 'frfs', SCALES, rel_sd=0.01, seed=0)
        run_tune(dirs[:1], root / 'warm', rate=1000.0)            # numba and imports warm
        t0, c0 = time.perf_counter(), time.process_time()
        out = run_tune(dirs, root / 'tune', rate=1000.0)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        camp = read_campaign(dirs)
        t1, c1 = time.perf_counter(), time.process_time()
        tune_campaign(camp, TuneTargets(), 1000.0)
        search, search_cpu = time.perf_counter() - t1, time.process_time() - c1
        bw = min(a.result.worst_bandwidth_hz for a in out.axes)
        t2 = time.perf_counter()
        props = propose_gains(camp.frfs[camp.nominal], bw, 45.0)
        base_t = time.perf_counter() - t2
    names = [a.axis for a in out.axes]
    base = [AxisSetting(n, p.kp, p.ki) for n, p in zip(names, props)]
    tw, bwst = _worst(out.settings(), robots, 1e-3), _worst(base, robots, 1e-3)

    def m(x):
        return f'GM {x[0]:.1f} dB, PM {x[1]:.0f} deg, MM {x[2]:.2f}'
    return [('tune: 3x3 FRFs of 9 poses, wall (CPU) time, goal < 5 s',
             f'{wall:.2f} s ({cpu:.2f} s)', f'loop --propose, nominal: {1e3 * base_t:.1f} ms', ''),
            ('tune: of it the fits, weights and search', f'{search:.2f} s ({search_cpu:.2f} s)',
             '', ''),
            ('tune: worst true margins over the 9 poses (default targets)', m(tw),
             f'propose at {bw:.2f} Hz: {m(bwst)}', ''),
            ('tune: resonance spread over the poses per axis',
             ', '.join(f'{x:.0f} %' for x in spread), '', ''),
            ('tune: every target met at every pose (as tune judged it)', str(out.met), '', '')]
