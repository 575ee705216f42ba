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
``identify --poses --one-bag``: all poses in one bag, and ``estimate`` keeps them apart.

Two poses with a short multisine, recorded once as one bag per pose and once as one bag: the
estimate of the one bag must give one folder per pose whose frf.json equals (to the last bit)
the estimate of that pose's own bag, and whose summary records the pose; the FRF map lists both
poses. Were the poses not kept apart, the estimate would average the two poses' segments and
the antiresonance of joint_1, which moves by 5 % between them, would differ.
"""
import csv
import json

from frf_ident.app.identify import ONE_BAG, POSE_INDEX, run_identify_poses
from frf_ident.cli import main
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.simulation.runner import IdentificationConfig
import numpy as np
import pytest

pytest.importorskip('pinocchio')

POSES = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.45]]


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    root = tmp_path_factory.mktemp('pose_bag')
    poses = root / 'poses.yaml'
    poses.write_text('poses:\n' + ''.join(f'  - {q}\n' for q in POSES))
    cfg = IdentificationConfig(MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=0.5,
                                               f_high=30.0, compensate=False), None)
    run_identify_poses(None, poses, cfg, root / 'per_pose', progress=lambda s: None)
    index = run_identify_poses(None, poses, cfg, root / 'one', one_bag=True,
                               progress=lambda s: None)
    return root, index


def test_one_bag_estimates_as_the_per_pose_bags(bags):
    root, index = bags
    assert [p['bag'] for p in index] == [ONE_BAG] * 2
    assert json.loads((root / 'one' / POSE_INDEX).read_text())['poses'][1]['t_range'][0] > \
        index[0]['t_range'][1]
    assert main(['estimate', str(root / 'one' / ONE_BAG), '--out', str(root / 'est_one'),
                 '--jobs', '1']) == 0
    assert main(['estimate', str(root / 'per_pose'), '--out', str(root / 'est_per'),
                 '--jobs', '1']) == 0
    for k, q in enumerate(POSES):
        name = f'pose_{k:02d}'
        one = json.loads((root / 'est_one' / name / 'frf.json').read_text())
        per = json.loads((root / 'est_per' / name / 'frf.json').read_text())
        for key in ('freq_hz', 'inputs', 'outputs'):
            assert one[key] == per[key], (name, key)
        a, b = (np.array(d['re']) + 1j * np.array(d['im']) for d in (one, per))
        # the same samples shifted by whole samples: equal to the rounding of the time stamps
        # (measured 8e-16 relative)
        assert np.abs(a - b).max() < 1e-12 * np.abs(b).max()
        summary = json.loads((root / 'est_one' / name / 'summary.json').read_text())
        assert summary['experiment']['pose_rad'] == q
    with open(root / 'est_one' / 'frf_map.csv') as fh:
        rows = list(csv.DictReader(fh))
    assert [float(r['pose_rad_joint_3']) for r in rows] == [q[2] for q in POSES]
    anti = [float(r['antiresonance_hz_joint_1']) for r in rows]
    assert abs(anti[1] / anti[0] - 1) > 0.02, anti


def test_t_range_is_refused_on_a_bag_of_poses(bags, tmp_path, capsys):
    root, _ = bags
    assert main(['estimate', str(root / 'one' / ONE_BAG), '--out', str(tmp_path / 'x'),
                 '--t-range', '0', '5']) == 2
    assert '--t-range' in capsys.readouterr().err
