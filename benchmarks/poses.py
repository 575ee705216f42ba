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
The simulated pose campaign end to end (section ``poses``).

``identify --poses`` at 9 poses of the demo robot (short multisines: 1 realisation, 2
periods, 0.25 Hz, all poses in one bag with ``--one-bag``), ``estimate`` of that bag (one
folder per pose), ``fit --physical --band 2 30 --delay 0.0005`` over the estimates (the
two-mass model misses the sampled plant above 30 Hz, and the zero-order hold is half a
sample of delay) and the global pose model, all serially in this process. Rows: each
held-out pose's FRF predicted by the pose model fitted to the other 8 (median and 95th
percentile of |dB| over lines and axes, median over the poses) beside the nearest pose's
measured FRF and the pose-independent mean model, and the wall time of each stage.
"""
from __future__ import annotations

from pathlib import Path
import tempfile
import time

__all__ = ['POSES', 'rows']

#: the 9 poses of test/app/test_identify_poses.py [rad]
POSES = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.45], [0.0, 0.0, -0.45], [0.0, 0.03, 0.2],
         [0.0, -0.03, -0.2], [1.0, 0.03, 0.45], [0.0, 0.03, 0.3], [0.0, -0.03, -0.45],
         [0.0, -0.03, -0.3]]


def rows() -> list[tuple[str, str, str, str]]:
    import json

    from frf_ident.cli import main
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        poses = root / 'poses.yaml'
        poses.write_text('poses:\n' + ''.join(f'  - {q}\n' for q in POSES))
        steps = [('identify --poses --one-bag', ['identify', '--poses', str(poses), '--one-bag',
                                                 '--procedures', 'multisine', '--realisations',
                                                 '1', '--periods', '2', '--resolution', '0.25',
                                                 '--no-compensation', '--out',
                                                 str(root / 'bags')]),
                 ('estimate (9 poses of one bag)', ['estimate', str(root / 'bags' / 'all_poses'),
                                                    '--out', str(root / 'est'), '--jobs', '1']),
                 ('fit --physical + pose model', ['fit', str(root / 'est'), '--physical',
                                                  '--no-figure', '--band', '2', '30',
                                                  '--delay', '0.0005', '--out',
                                                  str(root / 'fit'), '--jobs', '1'])]
        times = []
        for name, argv in steps:
            t0 = time.perf_counter()
            status = main(['-q'] + argv)
            times.append((name, time.perf_counter() - t0, status))
        med = json.loads((root / 'fit' / 'pose_model.json').read_text())['validation'][
            'median_db']
    out = [('poses: held-out FRF, median |dB| (pose model vs nearest pose)',
            f'{med["model_db"]:.2f} dB', f'{med["nearest_db"]:.2f} dB',
            f'mean model {med["mean_db"]:.2f} dB'),
           ('poses: held-out FRF, 95th percentile |dB| (pose model vs nearest pose)',
            f'{med["model_p95_db"]:.2f} dB', f'{med["nearest_p95_db"]:.2f} dB',
            f'mean model {med["mean_p95_db"]:.2f} dB')]
    out += [(f'poses: {name} wall time (exit {status})', f'{t:.1f} s', '', '')
            for name, t, status in times]
    return out
