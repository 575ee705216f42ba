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
Fitted parameters written as MJCF (and URDF): MuJoCo loads them and linearises them back.

Standalone: MuJoCo's linearisation of the written MJCF against the analytic FRF of the same
parameters (frf_ident.core.simulation.analytic, exact zero-order hold). With an MJCF base: the
``fit --physical`` of an FRF measured on the elastic iiwa 14 (test/plants/mujoco_iiwa.py), its
model.xml linearised by MuJoCo at the pose against the fitted model's own FRF and the truth's.
"""
from dataclasses import replace
import json

from frf_ident.core.model.params import MjcfSource
from frf_ident.core.model.schema import default_robot
from frf_ident.core.simulation.analytic import robot_frf_sampled
import numpy as np
from plants.mujoco_iiwa import elastic_xml, HELD, home, SHARED_IIWA, truth_frf
import pytest

mujoco = pytest.importorskip('mujoco')
write_mjcf = pytest.importorskip('frf_ident.io.mjcf.export').write_mjcf
transition = pytest.importorskip('frf_ident.io.mjcf.linear').transition
load_robot = pytest.importorskip('frf_ident.io.mjcf.robot').load_robot

pytestmark = pytest.mark.xdist_group('mujoco_iiwa')


def _db(a, b):
    return np.abs(20 * np.log10(np.abs(a / b)))


def test_standalone_mjcf_linearises_to_our_frf(tmp_path):
    """The default 3-axis robot (coupling left out) written and linearised by MuJoCo."""
    rob = replace(default_robot(), link_coupling=None).with_axes(gravity_torque=0.0)
    exp = write_mjcf(rob, tmp_path / 'model.xml')
    m = mujoco.MjModel.from_xml_path(str(exp.path))
    assert m.nu == 3 and m.nv == 6
    lin = transition(load_robot(MjcfSource(str(exp.path)), rob.joint_names), rob.dt)
    f = np.linspace(0.5, 100.0, 400)
    mj, ours = lin.frf(f), robot_frf_sampled(rob, f)
    for i, a in enumerate(rob.axes):
        e = _db(mj[i, i], ours[i, i])
        deg = np.abs(np.degrees(np.angle(mj[i, i] / ours[i, i])))
        print(f'{a.name}: MuJoCo (implicitfast, 1 ms) vs exact zero-order hold: median '
              f'{np.median(e):.3f} dB / {np.median(deg):.3f} deg, max {e.max():.3f} dB')
        assert np.median(e) < 0.1 and e.max() < 0.3 and np.median(deg) < 0.5
    assert np.abs(mj[0, 1]).max() < 1e-9          # independent axes


def test_what_mjcf_cannot_hold_is_reported(tmp_path):
    rob = default_robot()
    axes = list(rob.axes)
    axes[1] = replace(axes[1], backlash=1e-3, torque_ripple=[{'amplitude': 2.0,
                                                              'spatial_frequency': 6.0}],
                      stiffness_k2=4e5, stiffness_breakpoint=2e-3, coulomb_friction=12.0,
                      time_delay=0.002)
    exp = write_mjcf(replace(rob, axes=axes), tmp_path / 'model.xml')
    text = '\n'.join(exp.lines())
    print(text)
    for key in ('backlash', 'torque_ripple', 'stiffness_k2', 'link_coupling', 'gravity'):
        assert key in text
    m = mujoco.MjModel.from_xml_path(str(exp.path))
    j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, 'joint_2')
    assert m.dof_frictionloss[m.jnt_dofadr[j]] == 12.0
    a = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, 'joint_2_motor')
    assert m.actuator_delay[a] == pytest.approx(0.002)


def test_drive_urdf_is_read_by_pinocchio(tmp_path):
    pin = pytest.importorskip('pinocchio')
    from frf_ident.io.urdf_drive import write_drive_urdf
    rob = default_robot()
    model = pin.buildModelFromUrdf(str(write_drive_urdf(rob, tmp_path / 'model.urdf')))
    np.testing.assert_allclose(model.damping, [a.viscous_friction for a in rob.axes])
    np.testing.assert_allclose(model.effortLimit, rob.torque_limits())
    assert 'motor_inertia' in (tmp_path / 'model.urdf').read_text()


@pytest.fixture(scope='module')
def fitted(tmp_path_factory):
    """Identify (MuJoCo, joints 2 and 4), estimate, fit --physical on the plain iiwa."""
    from frf_ident.app.estimate import estimate_bag
    from frf_ident.app.fit import fit_frf
    from frf_ident.app.identify import run_identify
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    from frf_ident.core.simulation.runner import IdentificationConfig
    import yaml
    tmp = tmp_path_factory.mktemp('fit')
    (tmp / 'truth.xml').write_text(elastic_xml())
    pose = home()
    common = {'frf_ident_model': 1, 'sample_rate': 1000.0,
              'axes': [{'name': 'joint2'}, {'name': 'joint4'}],
              'controller': {'kind': 'pi_velocity', 'kp': [150.0, 50.0], 'ki': [1500.0, 500.0]}}
    (tmp / 'truth.yaml').write_text(yaml.safe_dump(dict(
        common, mjcf='truth.xml', pose={'joint2': pose['joint2'], 'joint4': pose['joint4']})))
    (tmp / 'nominal.yaml').write_text(yaml.safe_dump(dict(common, mjcf=str(SHARED_IIWA),
                                                          pose='home')))
    cfg = IdentificationConfig(MultisineConfig(n_realisations=2, n_periods=3, f_low=1.0,
                                               position_bound_deg=1.0), None)
    run_identify(tmp / 'truth.yaml', 'mujoco', cfg, tmp / 'bag')
    estimate_bag(tmp / 'bag', tmp / 'est')
    fit_frf(tmp / 'est', tmp / 'fit', physical=True, delay_s=0.0005, model=tmp / 'nominal.yaml',
            figure=False)
    return tmp


def test_fit_physical_writes_an_mjcf_that_linearises_to_the_fit(fitted):
    from frf_ident.io.model_file import load_model
    xml = fitted / 'fit' / 'model.xml'
    m = mujoco.MjModel.from_xml_path(str(xml))
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(m.njnt)]
    assert 'joint2_link' in names and 'joint4_link' in names and 'joint1_link' not in names
    pose = home()
    robot = load_robot(MjcfSource(str(xml), None, pose), ['joint2', 'joint4'])
    frf = json.loads((fitted / 'est' / 'frf.json').read_text())
    f = np.asarray(frf['freq_hz'])
    exported = transition(robot, 1e-3).frf(f)
    _, fit_robot, _ = load_model(fitted / 'fit' / 'model.yaml')
    fit_model = robot_frf_sampled(fit_robot, f)
    truth = truth_frf(elastic_xml(HELD + ['joint1']), f, pose, axes=['joint2', 'joint4'])
    nominal = truth_frf(elastic_xml(HELD + ['joint1'], elastic={}), f, pose,
                        axes=['joint2', 'joint4'])
    for i, name in enumerate(['joint2', 'joint4']):
        e_fit = np.median(_db(exported[i, i], fit_model[i, i]))
        e_truth = np.median(_db(exported[i, i], truth[i, i]))
        e_nom = np.median(_db(nominal[i, i], truth[i, i]))
        print(f'{name}: model.xml linearised vs the fitted model {e_fit:.3f} dB, vs the truth '
              f'{e_truth:.3f} dB (the nominal rigid MJCF vs the truth {e_nom:.2f} dB), median '
              f'over {f.size} lines')
        assert e_fit < 0.5 and e_truth < 0.5 and e_nom > 3.0
