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
``frf-ident identify --poses``: the demo robot's resonances move with the pose as its URDF says.

The demo robot's URDF (urdf/robot_3axis_demo.urdf) must reproduce model_3axis.yaml's link
inertia at the home pose. At 9 poses (the forearm swung by up to +-0.45 rad, the upper arm
tilted a little: an unbalanced upper arm soon needs more torque than joint_2 has) each axis'
resonance and antiresonance in the FRF map of ``frf-ident estimate`` over the simulated
multisine bags (one per pose) must follow the
analytic value of that pose within 1 % (measured: 0.48 % at most, joint_1's antiresonance;
a link side frozen at the home pose misses that one by 6 %). The analytic value is computed
here, independently of the simulation and of frf_ident's analytic FRFs: the 6-DOF linear
equations of the motor and link sides with M(q) and the gravity gradient from pinocchio,
solved on a 0.002 Hz grid.
"""
import csv
import json

from frf_ident.app.identify import POSE_INDEX, run_identify_poses
from frf_ident.bag import read_recording
from frf_ident.cli import main
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.simulation.runner import IdentificationConfig
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.model_file import load_model
import numpy as np
import pytest

pin = pytest.importorskip('pinocchio')
pytestmark = pytest.mark.xdist_group('test_identify_poses')

#: q1 does not change the link side (vertical axis); q2 and q3 do; gravity bounds q2 * q3
POSES = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.45], [0.0, 0.0, -0.45], [0.0, 0.03, 0.2],
         [0.0, -0.03, -0.2], [1.0, 0.03, 0.45], [0.0, 0.03, 0.3], [0.0, -0.03, -0.45],
         [0.0, -0.03, -0.3]]


def _urdf_model():
    from frf_ident.io.share import share_dir
    m = pin.buildModelFromUrdf(str(share_dir() / 'urdf' / 'robot_3axis_demo.urdf'))
    return m, m.createData()


def analytic_modes(robot, q, freq_hz):
    """Accelerance peak and dip of each axis of the linear plant at pose q, on freq_hz."""
    m, d = _urdf_model()
    mass = pin.crba(m, d, np.asarray(q, float))
    mass = np.triu(mass) + np.triu(mass, 1).T
    kg = pin.computeGeneralizedGravityDerivatives(m, d, np.asarray(q, float))
    jm = np.diag([a.motor_inertia for a in robot.axes])
    k = np.diag([a.stiffness for a in robot.axes])
    dd = np.diag([a.damping for a in robot.axes])
    bv = np.diag([a.viscous_friction for a in robot.axes])
    n = robot.n_axes
    res, anti = np.zeros(n), np.zeros(n)
    acc = np.zeros((n, freq_hz.size))
    for c, f in enumerate(freq_hz):
        s = 2j * np.pi * f
        z = np.block([[jm * s**2 + (bv + dd) * s + k, -(dd * s + k)],
                      [-(dd * s + k), mass * s**2 + dd * s + k + kg]])
        p = s * np.linalg.inv(z)[:n, :n]             # torque -> motor velocity
        acc[:, c] = np.abs(s * np.diag(p))
    for i in range(n):
        kk = int(np.argmax(acc[i]))
        res[i] = freq_hz[kk]
        anti[i] = freq_hz[int(np.argmin(acc[i, :kk]))]
    return res, anti


def test_urdf_home_pose_is_the_model_file():
    m, d = _urdf_model()
    _, robot, _ = load_model(None)
    mass = pin.crba(m, d, np.zeros(3))
    mass = np.triu(mass) + np.triu(mass, 1).T
    np.testing.assert_allclose(mass, robot.link_inertia_matrix(), rtol=1e-3, atol=0.01)
    g = pin.computeGeneralizedGravity(m, d, np.zeros(3))
    assert abs(g[1] - robot.axes[1].gravity_torque) < 0.01 * robot.axes[1].gravity_torque


@pytest.fixture(scope='module')
def pose_bags(tmp_path_factory):
    root = tmp_path_factory.mktemp('poses')
    poses = root / 'poses.yaml'
    poses.write_text('poses:\n' + ''.join(f'  - {q}\n' for q in POSES))
    cfg = IdentificationConfig(MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=0.25,
                                               compensate=False), None)
    run_identify_poses(None, poses, cfg, root / 'bags', progress=lambda s: None)
    return root / 'bags'


def test_each_axis_resonance_follows_the_pose(pose_bags, tmp_path):
    """The estimate campaign's FRF map (frf_map.csv) against the analytic modes per pose."""
    _, robot, _ = load_model(None)
    index = json.loads((pose_bags / POSE_INDEX).read_text())['poses']
    assert [p['pose_rad'] for p in index] == POSES
    rec, _ = read_recording(pose_bags / index[1]['bag'])
    assert all(s.info['pose_rad'] == POSES[1] for s in rec.segments)
    assert main(['estimate', str(pose_bags), '--out', str(tmp_path / 'map'), '--jobs', '1']) == 0
    with open(tmp_path / 'map' / 'frf_map.csv') as fh:
        rows = list(csv.DictReader(fh))
    assert [r['bag'] for r in rows] == [p['bag'] for p in index]
    joints = robot.joint_names
    assert [[float(r[f'pose_rad_{j}']) for j in joints] for r in rows] == POSES
    got = np.array([[float(r[f'{w}_hz_{j}']) for w in ('resonance', 'antiresonance')
                     for j in joints] for r in rows])
    grid = np.arange(2.0, 40.0, 0.002)
    want = np.array([np.r_[analytic_modes(robot, q, grid)] for q in POSES])
    rel = np.abs(got / want - 1)
    assert rel.max() < 0.01, (rel.round(4), got.round(3), want.round(3))
    # the pose moves joint_1's antiresonance (link inertia 149..168 kg m^2) by 6 %: a link
    # side frozen at the home pose would miss it by more than four times the tolerance (the
    # resonances move 1 % at most: the motor inertia dominates them)
    assert np.abs(got[:, 3] / want[0, 3] - 1).max() > 0.04


def test_a_pose_gravity_cannot_hold_is_refused_before_anything_runs(tmp_path):
    poses = tmp_path / 'p.yaml'
    poses.write_text('poses:\n  - [0.0, 0.0, 0.0]\n  - [0.0, -0.5, 0.0]\n')
    cfg = IdentificationConfig(MultisineConfig(n_realisations=1, n_periods=2), None)
    with pytest.raises(FrfIdentInputError, match=r'poses\[1\] needs .* joint_2'):
        run_identify_poses(None, poses, cfg, tmp_path / 'out', progress=lambda s: None)
    assert not (tmp_path / 'out').exists()
