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
The URDF adapter and the linearised link side against pinocchio at displaced poses.

robot_at_pose must give the model the pose's inertia matrix and a gravity load that matches
pinocchio's g(q0 + dq) to second order in dq over the +-4 deg an experiment travels; the
poses file and URDF are refused with one line naming what is wrong.
"""
from frf_ident.core.model.operating_point import robot_at_pose
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.kinematics import load_kinematics, read_poses
from frf_ident.io.model_file import load_model
import numpy as np
import pytest

pin = pytest.importorskip('pinocchio')


def test_linearised_gravity_matches_pinocchio_near_the_pose():
    _, robot, _ = load_model(None)
    kin = load_kinematics(None, robot.joint_names)
    q0 = np.array([0.3, 0.02, -0.35])
    side = kin.at(q0)
    lin = robot_at_pose(robot, side.inertia, side.gravity, side.gravity_gradient)
    np.testing.assert_allclose(lin.link_inertia_matrix(), side.inertia, rtol=1e-12)
    rng = np.random.default_rng(3)
    for dq in rng.uniform(-np.deg2rad(4), np.deg2rad(4), size=(5, 3)):
        truth = kin.at(q0 + dq).gravity
        err = np.abs(lin.gravity_load(dq) - truth).max()
        # second order: half the largest curvature of g (about m g c of the upper arm and
        # forearm, < 1000 N m/rad^2) times |dq|^2; the first-order term is ~60 N m at 4 deg
        assert err < 500.0 * np.sum(dq ** 2), (dq, err)
    # and not by accident: the constant load alone misses by first order
    dq = np.deg2rad([0.0, 4.0, 4.0])
    assert np.abs(side.gravity - kin.at(q0 + dq).gravity).max() > 10.0


def test_poses_file_and_urdf_refused_in_one_line(tmp_path):
    p = tmp_path / 'p.yaml'
    p.write_text('poses:\n  - [0.0, 0.1]\n')
    with pytest.raises(FrfIdentInputError, match=r'poses\[0\] = \[0.0, 0.1\]; expected 3'):
        read_poses(p, 3)
    p.write_text('poses: []\n')
    with pytest.raises(FrfIdentInputError, match='non-empty list'):
        read_poses(p, 3)
    with pytest.raises(FrfIdentInputError, match=r'do not match the model axes'):
        load_kinematics(None, ['joint_1', 'joint_2', 'elbow'])
    bad = tmp_path / 'bad.urdf'
    bad.write_text('<robot name="x"><link name="a"/><joint name="j"/></robot>')
    with pytest.raises(FrfIdentInputError, match='bad.urdf'):
        load_kinematics(bad, ['j'])


def test_inertia_regressor_and_fitted_urdf_reproduce_crba(tmp_path):
    """Y(q) pi is pinocchio's CRBA at any pose, for the URDF's pi and for other parameters."""
    _, robot, _ = load_model(None)
    kin = load_kinematics(None, robot.joint_names)
    rng = np.random.default_rng(5)
    pi = kin.parameters()
    other = pi * rng.uniform(0.8, 1.2, pi.size)          # masses stay positive
    changed = kin.with_parameters(other)
    urdf = changed.write_urdf(tmp_path / 'fitted.urdf', comment='test')
    reread = load_kinematics(urdf, robot.joint_names)
    iu = np.triu_indices(3)
    for q in rng.uniform(-1.0, 1.0, size=(4, 3)):
        y = kin.inertia_regressor(q)
        np.testing.assert_allclose(y @ pi, kin.at(q).inertia[iu], rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(y @ other, changed.at(q).inertia[iu], rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(reread.at(q).inertia, changed.at(q).inertia, rtol=1e-7)
        np.testing.assert_allclose(reread.at(q).gravity, changed.at(q).gravity, rtol=1e-7,
                                   atol=1e-6)
    assert not np.allclose(changed.at([0, 0, 0.4]).inertia, kin.at([0, 0, 0.4]).inertia)
