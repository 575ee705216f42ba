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
A model file naming an MJCF: what it reads, and what it refuses with one line.

Refused (exit 2 from the CLI): drive keys on an axis (the MJCF holds them), a link_coupling, an
unknown keyframe or pose joint, an axis that is not an actuated hinge, a sample period the
MJCF's time step does not divide, a pose without mjcf, ``--plant mujoco`` without an MJCF.
"""
from frf_ident.cli import main
from frf_ident.errors import MjcfError, ModelFileError
from frf_ident.io.model_file import load_model, load_plant
import pytest
import yaml

pytest.importorskip('mujoco')


def _write(tmp_path, **changes):
    from plants.mujoco_iiwa import SHARED_IIWA
    d = {'frf_ident_model': 1, 'sample_rate': 1000.0, 'mjcf': str(SHARED_IIWA), 'pose': 'home',
         'axes': [{'name': 'joint2'}, {'name': 'joint4', 'velocity_noise': 1e-4}],
         'controller': {'kind': 'pi_velocity', 'kp': [150.0, 50.0], 'ki': [1500.0, 500.0]}}
    d.update(changes)
    p = tmp_path / 'm.yaml'
    p.write_text(yaml.safe_dump(d))
    return p


def test_mjcf_model_reads_the_mjcf_at_the_pose(tmp_path):
    d, robot, ctrl = load_model(_write(tmp_path))
    assert robot.mjcf is not None and robot.joint_names == ['joint2', 'joint4']
    assert robot.axes[1].velocity_noise == 1e-4
    assert robot.torque_limits().tolist() == [320.0, 176.0]
    # the PI starts with the pose's holding torque, which MuJoCo's plant needs there
    plant = load_plant('mujoco', d)
    assert ctrl.integral == pytest.approx(plant.hold, rel=1e-6)
    assert d['pose']['joint2'] == pytest.approx(0.785398)


@pytest.mark.parametrize('changes, words', [
    ({'axes': [{'name': 'joint2', 'motor_inertia': 1.0}]}, ['axes[0]', 'motor_inertia']),
    ({'link_coupling': [[0, 1], [1, 0]]}, ['link_coupling']),
    ({'pose': 'nowhere'}, ["keyframe 'nowhere'"]),
    ({'pose': {'joint9': 0.1}}, ['pose.joint9']),
    ({'axes': [{'name': 'joint8'}]}, ["axis 'joint8'"]),
    ({'sample_rate': 300.0}, ['timestep 0.001', '300']),
])
def test_mjcf_model_refusals_name_the_field(tmp_path, changes, words):
    with pytest.raises(ModelFileError) as err:
        load_model(_write(tmp_path, **changes))
    msg = str(err.value)
    print(msg)
    assert '\n' not in msg and 'm.yaml' in msg
    for w in words:
        assert w in msg


def test_pose_without_mjcf_and_plant_mujoco_without_mjcf_are_refused(tmp_path, capsys):
    p = tmp_path / 'plain.yaml'
    p.write_text(yaml.safe_dump({'frf_ident_model': 1, 'pose': 'home', 'axes': [{}],
                                 'controller': {'kp': [1.0], 'ki': [1.0]}}))
    with pytest.raises(ModelFileError, match='pose: only a model with mjcf'):
        load_model(p)
    rc = main(['identify', '--plant', 'mujoco', '--out', str(tmp_path / 'bag')])
    assert rc == 2
    assert 'names no mjcf' in capsys.readouterr().err
    with pytest.raises(MjcfError, match='not found'):
        load_plant('mujoco:' + str(tmp_path / 'missing.xml'), load_model(None)[0])
