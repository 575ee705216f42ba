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
The mapping MJCF <-> our parameters checked by simulation, not assumed (docs/mujoco.md).

- ``frictionloss`` against our Coulomb friction (set-valued: a stuck motor stays at rest):
  sliding, MuJoCo's friction torque is Fc exactly; stuck, its soft constraint lets the joint
  creep at a velocity proportional to the torque, which ours does not.
- A second robot that is not the iiwa: the repository's urdf/kuka_kr300_axes123.urdf as an
  MJCF (frf_ident.io.mjcf.from_urdf); MuJoCo's M(q), g(q) and dg/dq read in our parameters
  against pinocchio's of the same URDF (an independent rigid-body engine).
"""
from pathlib import Path

from frf_ident.core.model.params import MjcfSource
from frf_ident.io.mjcf.drive_map import RIGID_MOTOR_SHARE
import numpy as np
import pytest

mujoco = pytest.importorskip('mujoco')
axis_values = pytest.importorskip('frf_ident.io.mjcf.linear').axis_values
load_robot = pytest.importorskip('frf_ident.io.mjcf.robot').load_robot

ROOT = Path(__file__).resolve().parents[2]


def _hinge(fc: float, j: float, integrator: str) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(
        f'<mujoco><option timestep="0.001" gravity="0 0 0" integrator="{integrator}"/>'
        f'<worldbody><body><joint name="a" axis="0 0 1" armature="{j}" frictionloss="{fc}"/>'
        '<inertial mass="1e-6" pos="0 0 0" diaginertia="1e-9 1e-9 1e-9"/></body></worldbody>'
        '<actuator><motor joint="a"/></actuator></mujoco>')


@pytest.mark.parametrize('integrator', ['implicitfast', 'Euler'])
def test_frictionloss_slides_at_fc_and_creeps_when_stuck(integrator):
    fc, j, t = 10.0, 1.0, 2.0
    m = _hinge(fc, j, integrator)
    creep = []
    for ratio in (0.25, 0.5, 0.9, 1.5, 3.0):
        d = mujoco.MjData(m)
        d.ctrl[0] = ratio * fc
        mujoco.mj_step(m, d, int(t / m.opt.timestep))
        ours = max(ratio * fc - fc, 0.0) / j * t      # Coulomb: stuck below Fc, else slides
        print(f'{integrator}: torque {ratio:.2f} Fc: MuJoCo velocity after {t:g} s '
              f'{d.qvel[0]:.5f} rad/s, Coulomb {ours:.5f} rad/s')
        if ratio > 1:
            assert d.qvel[0] == pytest.approx(ours, rel=1e-9)
        else:
            creep.append(d.qvel[0] / (ratio * fc))
            assert 0.0 < d.qvel[0] < 2e-3 * ratio * fc    # default solref, 1 kg m^2
    # stuck, the creep is viscous-like: velocity / torque the same at every torque below Fc
    assert np.ptp(creep) < 0.02 * np.mean(creep)
    print(f'{integrator}: creep {np.mean(creep):.3e} rad/s per N m (a damper of '
          f'{1 / np.mean(creep):.0f} N m s/rad; our plant: 0)')


def test_second_robot_kr300_from_urdf_matches_pinocchio(tmp_path):
    pytest.importorskip('pinocchio')
    from frf_ident.io.kinematics import load_kinematics
    from frf_ident.io.mjcf.from_urdf import mjcf_from_urdf
    urdf = ROOT / 'urdf' / 'kuka_kr300_axes123.urdf'
    xml = mjcf_from_urdf(urdf, tmp_path / 'kr300.xml', torque_limits=[2e4, 4e4, 1.5e4])
    names = ['joint_1', 'joint_2', 'joint_3']
    kin = load_kinematics(urdf, names)
    for q in ([0.3, -0.8, 0.5], [0.0, -1.2, 1.0], [-1.0, 0.2, -0.4]):
        robot = load_robot(MjcfSource(str(xml), None, dict(zip(names, q))), names)
        axes, link = axis_values(robot, 1000.0)
        side = kin.at(np.array(q))
        # a rigid joint's motor share moved from the link side (drive_map.rigid_split)
        total = link + np.diag([a['motor_inertia'] for a in axes])
        np.testing.assert_allclose(total, side.inertia, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(np.diag(link), (1 - RIGID_MOTOR_SHARE) *
                                   np.diag(side.inertia), rtol=1e-12)
        np.testing.assert_allclose([a['gravity_torque'] for a in axes], side.gravity,
                                   rtol=1e-9, atol=1e-6)
        grad = np.zeros((3, 3))
        for i, a in enumerate(axes):
            for term in a['gravity']:
                grad[i, names.index(term['joints'][0])] = term['amplitude']
        np.testing.assert_allclose(grad, side.gravity_gradient, rtol=1e-6, atol=1e-3)
    m = mujoco.MjModel.from_xml_path(str(xml))
    assert m.nu == 3 and list(m.actuator_ctrlrange[:, 1]) == [2e4, 4e4, 1.5e4]


def test_docs_show_the_mapping_table():
    """docs/mujoco.md holds MAPPING as mapping_table() renders it (one table, one place)."""
    from frf_ident.io.mjcf.drive_map import mapping_table
    assert mapping_table() in (ROOT / 'docs' / 'mujoco.md').read_text()


def test_series_pair_on_the_kr300_reads_back_its_drive_and_pinocchios_link_side(tmp_path):
    """Split joint_2 of the KR 300 into the hinge pair: our parameters of it read back."""
    pytest.importorskip('pinocchio')
    from frf_ident.io.kinematics import load_kinematics
    from frf_ident.io.mjcf.drive_map import JointDrive
    from frf_ident.io.mjcf.from_urdf import mjcf_from_urdf
    from frf_ident.io.mjcf.spec_edit import set_drive, split_elastic
    urdf = ROOT / 'urdf' / 'kuka_kr300_axes123.urdf'
    xml = mjcf_from_urdf(urdf, tmp_path / 'kr300.xml', torque_limits=[2e4, 4e4, 1.5e4])
    spec = split_elastic(mujoco.MjSpec.from_file(str(xml)), ['joint_2'])
    drive = JointDrive('joint_2', armature=30.0, damping=200.0, frictionloss=0.0,
                       stiffness=4e6, link_damping=3e3, torque_limit=4e4)
    set_drive(spec, drive)
    (tmp_path / 'kr300_flex.xml').write_text(spec.to_xml())
    names = ['joint_1', 'joint_2', 'joint_3']
    q = [0.3, -0.8, 0.5]
    robot = load_robot(MjcfSource(str(tmp_path / 'kr300_flex.xml'), None, dict(zip(names, q))),
                       names)
    assert list(robot.elastic) == [False, True, False]
    axes, link = axis_values(robot, 1000.0)
    a2 = axes[1]
    assert a2['motor_inertia'] == pytest.approx(30.0, rel=1e-6)
    assert (a2['stiffness'], a2['damping'], a2['viscous_friction']) == (4e6, 3e3, 200.0)
    side = load_kinematics(urdf, names).at(np.array(q))
    rigid = np.diag([a['motor_inertia'] if i != 1 else 0.0 for i, a in enumerate(axes)])
    np.testing.assert_allclose(link + rigid, side.inertia, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose([a['gravity_torque'] for a in axes], side.gravity, rtol=1e-6)
