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
Filters on the measured velocity in front of the PI (issue #51): simulation, node and file.

The torques of a closed-loop run are recomputed from the recorded reference and velocity
with scipy.signal.sosfilt and the PI recursion written out here (truth the kernel did not
produce); PIVelocity.step (what the controller node runs) gives the same; pass-through
sections leave the PI's torques bit for bit; the model file carries the sections and refuses
unusable ones, naming the field.
"""
import copy

from frf_ident.core.loop.notch import design_lowpass, design_notch
from frf_ident.core.model.schema import PASS_SECTION, robot_from_dict, robot_to_dict
from frf_ident.core.simulation.controller import controller_from_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.errors import ModelFileError
from frf_ident.io.model_file import load_model
import numpy as np
import pytest
from scipy import signal

ROOT = __import__('pathlib').Path(__file__).resolve().parents[3]
MODEL = ROOT / 'config' / 'model_3axis_resonant.yaml'


def _model(filters):
    d, _, _ = load_model(MODEL)
    d = copy.deepcopy(d)
    for a in d['axes']:
        a['velocity_noise'] = 0.0
    d['controller']['filters'] = filters
    return d


def _run(d, n=3000, seed=0):
    rob = robot_from_dict(d)
    ctrl = controller_from_dict(d, rob)
    r = np.cumsum(np.random.default_rng(seed).standard_normal((n, 3)), axis=0) * 1e-3
    res = FlexibleJointPlant(rob).simulate(reference=r, controller=ctrl.copy())
    return rob, ctrl, r, res


def test_the_kernel_runs_the_sections_and_the_pi_as_written_out():
    n1 = design_notch(36.4, 36.8, 0.011, 0.5, 1000.0)
    lp = design_lowpass(15.0, 1000.0)
    d = _model({'joint_1': [n1.sos.tolist(), lp.sos.tolist()], 'joint_3': [lp.sos.tolist()]})
    rob, ctrl, r, res = _run(d)
    hold = rob.gravity_load(np.zeros(3))
    dt = rob.dt
    u = np.empty_like(r)
    for i in range(3):
        sos = [s for s in ctrl.sos[i] if not np.array_equal(s, PASS_SECTION)]
        y = signal.sosfilt(np.array(sos), res.velocity[:, i]) if sos else res.velocity[:, i]
        e = r[:, i] - y
        integ = hold[i] + ctrl.ki[i] * dt * np.cumsum(e)       # no saturation in this run
        u[:, i] = ctrl.kp[i] * e + integ
    assert np.all(np.abs(u) < 0.9 * rob.torque_limits())     # no saturation: linear PI
    np.testing.assert_allclose(res.effort, u, rtol=1e-9, atol=1e-7)
    # the controller node's step on the same measurements gives the same torques
    node = ctrl.copy()
    stepped = np.array([node.step(r[k], res.velocity[k]) for k in range(r.shape[0])])
    np.testing.assert_allclose(stepped, res.effort, rtol=1e-12, atol=1e-9)


def test_pass_through_sections_leave_the_pi_bit_for_bit():
    _, _, _, plain = _run(_model(None))
    _, _, _, passed = _run(_model({'joint_2': [list(PASS_SECTION), list(PASS_SECTION)]}))
    assert np.array_equal(plain.effort, passed.effort)
    assert np.array_equal(plain.velocity, passed.velocity)


def test_the_model_file_round_trip_and_refusals():
    n1 = design_notch(36.4, 36.8, 0.011, 0.5, 1000.0)
    d = _model({'joint_2': [n1.sos.tolist()]})
    rob = robot_from_dict(d)
    ctrl = controller_from_dict(d, rob)
    back = robot_to_dict(rob, ctrl)['controller']['filters']
    assert list(back) == ['joint_2'] and np.allclose(back['joint_2'], [n1.sos])
    bad = [({'joint_9': [n1.sos.tolist()]}, r'controller\.filters\.joint_9: no axis'),
           ({'joint_1': [[1, 0, 0, 1, -2.1, 1.2]]}, r'joint_1: section 0: unstable'),
           ({'joint_1': [[1, 0, 0, 2, 0, 0]]}, r'a0 must be 1'),
           ({'joint_1': [[0.5, 0, 0, 1, 0, 0]]}, r'DC gain 0\.5'),
           ({'joint_1': [[1, 0, 0, 1, 0]]}, r'rows of 6 numbers'),
           ({'joint_1': 'notch'}, r'joint_1: expected a list'),
           ('notch', r'controller\.filters: expected a mapping')]
    for spec, match in bad:
        d = _model(spec)
        with pytest.raises(ModelFileError, match=match):
            controller_from_dict(d, robot_from_dict(d))


def test_the_mujoco_plant_runs_the_sections_too(tmp_path):
    """The MuJoCo closed loop (frf_ident/io/mjcf/loop.py): filtered torques as written out."""
    pytest.importorskip('mujoco')
    from frf_ident.core.simulation.controller import PIVelocity
    from frf_ident.io.model_file import load_plant
    from plants.mujoco_iiwa import AXES, elastic_xml, home, KI, KP
    path = tmp_path / 'iiwa.xml'
    path.write_text(elastic_xml())
    pose = home()
    model = {'frf_ident_model': 1, 'sample_rate': 1000.0, 'mjcf': str(path),
             'pose': {a: pose[a] for a in AXES}, 'axes': [{'name': a} for a in AXES],
             'controller': {'kind': 'pi_velocity', 'kp': KP, 'ki': KI}}
    lp = design_lowpass(15.0, 1000.0).sos
    sos = np.array([[PASS_SECTION], [lp], [PASS_SECTION]], dtype=float)
    r = np.cumsum(np.random.default_rng(0).standard_normal((1500, 3)), axis=0) * 2e-4
    runs = []
    for s in (sos, np.zeros((3, 0, 6))):
        plant = load_plant('mujoco', model)
        ctrl = PIVelocity(KP, KI, plant.torque_limit, plant.dt, plant.hold.copy(), sos=s)
        runs.append((plant.simulate(reference=r, controller=ctrl), plant))
    (res, plant), (plain, _) = runs
    assert np.all(np.abs(res.effort) < 0.9 * plant.torque_limit)
    e = r[:, 1] - signal.sosfilt(lp.reshape(1, 6), res.velocity[:, 1])
    u = KP[1] * e + plant.hold[1] + KI[1] * plant.dt * np.cumsum(e)
    np.testing.assert_allclose(res.effort[:, 1], u, rtol=1e-9, atol=1e-7)
    assert not np.allclose(res.effort[:, 1], plain.effort[:, 1])
