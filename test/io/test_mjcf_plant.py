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
MuJoCo as the plant: the project's closed-loop multisine pipeline against MuJoCo's own truth.

The shared iiwa 14 (MuJoCo_iiwa14) with series elasticity on joints 2 and 4
(test/plants/mujoco_iiwa.py, written there without frf_ident.io.mjcf), identified on joints 1,
2 and 4, the other four held at the home pose; the truth is the discrete FRF of
mjd_transitionFD's A, B at rest, computed in test/plants/mujoco_iiwa.py.
"""
from frf_ident.core.estimation.described import multisine_frf
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.core.simulation.runner import IdentificationConfig, run_identification
from frf_ident.io.model_file import load_plant
import numpy as np
from plants.mujoco_iiwa import AXES, elastic_xml, HELD, home, KI, KP, truth_frf
import pytest

mujoco = pytest.importorskip('mujoco')

pytestmark = pytest.mark.xdist_group('mujoco_iiwa')


def _model(xml_path, noise=None):
    pose = home()
    return {'frf_ident_model': 1, 'sample_rate': 1000.0, 'mjcf': str(xml_path),
            'pose': {a: pose[a] for a in AXES},
            'axes': [{'name': a, 'velocity_noise': 0.0 if noise is None else float(s)}
                     for a, s in zip(AXES, noise if noise is not None else [0] * 3)],
            'simulation': {'seed': 4},
            'controller': {'kind': 'pi_velocity', 'kp': KP, 'ki': KI}}


def _identify(model, ms):
    plant = load_plant('mujoco', model)
    ctrl = PIVelocity(KP, KI, plant.torque_limit, plant.dt, plant.hold.copy())
    return run_identification(plant, ctrl, IdentificationConfig(ms, None))


@pytest.fixture(scope='module')
def iiwa_record(tmp_path_factory):
    """Run the multisine at 40 dB SNR: velocity noise 1 % of the excited velocity rms."""
    path = tmp_path_factory.mktemp('iiwa') / 'iiwa_elastic.xml'
    path.write_text(elastic_xml())
    cfg = {'position_bound_deg': 1.0, 'f_low': 1.0, 'f_high': 60.0}
    quiet = _identify(_model(path), MultisineConfig(n_realisations=1, n_periods=2, **cfg))
    segs = [s for s in quiet.segments if s.info['design'] == 'multisine']
    y = np.concatenate([quiet.velocity[quiet.slice(s.t_start, s.t_end)]
                        - s.info['constant_velocity'] for s in segs])
    rms = np.sqrt(np.mean((y - y.mean(axis=0)) ** 2, axis=0))
    ms = MultisineConfig(n_realisations=4, n_periods=4, **cfg)
    rec = _identify(_model(path, rms / 100.0), ms)
    return rec, rms


def test_estimated_frf_is_mujocos_linearisation_at_40db(iiwa_record):
    rec, rms = iiwa_record
    frf, _ = multisine_frf(rec, method='reference')
    truth = truth_frf(elastic_xml(HELD), frf.freq_hz, home())
    for i, name in enumerate(AXES):
        est, tru = frf.response[i, i], truth[i, i]
        db = 20 * np.log10(np.abs(est / tru))
        deg = np.degrees(np.angle(est / tru))
        print(f'{name}: velocity rms {rms[i]:.2e} rad/s, {frf.freq_hz.size} lines '
              f'{frf.freq_hz[0]:.2f}-{frf.freq_hz[-1]:.1f} Hz: median |error| '
              f'{np.median(np.abs(db)):.4f} dB, {np.median(np.abs(deg)):.4f} deg; '
              f'95th percentile {np.percentile(np.abs(db), 95):.3f} dB, '
              f'{np.percentile(np.abs(deg), 95):.3f} deg')
        assert np.median(np.abs(db)) <= 0.1
        assert np.median(np.abs(deg)) <= 1.0
    # the baseline of the same record: the plain Y U^+ estimate (no reference), and a truth
    # without the elasticity, which the comparison must tell apart
    plain, _ = multisine_frf(rec, method='plain')
    rigid = truth_frf(elastic_xml(HELD, elastic={}), frf.freq_hz, home())
    for i, name in enumerate(AXES):
        e_plain = np.median(np.abs(20 * np.log10(np.abs(plain.response[i, i] / truth[i, i]))))
        e_rigid = np.median(np.abs(20 * np.log10(np.abs(frf.response[i, i] / rigid[i, i]))))
        print(f'{name}: plain Y U^+ median {e_plain:.4f} dB; against the rigid iiwa '
              f'{e_rigid:.2f} dB')
        if i > 0:
            assert e_rigid > 1.0


def test_compiled_loop_is_the_python_loop_with_pivelocity(tmp_path):
    """The compiled kernel runs the samples of mj_step in Python with PIVelocity.step."""
    path = tmp_path / 'iiwa.xml'
    path.write_text(elastic_xml())
    plant = load_plant('mujoco', _model(path))
    n = 2000
    r = 0.02 * np.random.default_rng(1).standard_normal((n, 3))
    ctrl = PIVelocity(KP, KI, plant.torque_limit, plant.dt, plant.hold.copy())
    res = plant.simulate(reference=r, controller=ctrl)
    plant.reset()
    pi = PIVelocity(KP, KI, plant.torque_limit, plant.dt, plant.hold.copy())
    m, d, rb = plant.robot.model, plant.data, plant.robot
    v = np.empty((n, 3))
    for k in range(n):
        v[k] = d.qvel[rb.vadr]
        d.ctrl[rb.actuator] = pi.step(r[k], v[k])
        mujoco.mj_step(m, d)
    # to rounding: numba may order the PI's floating-point operations differently
    np.testing.assert_allclose(res.velocity, v, rtol=0, atol=1e-13)
    np.testing.assert_allclose(ctrl.integral, pi.integral, rtol=1e-12)


def test_held_joint_is_welded_where_the_pose_puts_it():
    """Locking a joint at 0.7 rad keeps every body where the full model puts it, and M."""
    from frf_ident.core.model.params import MjcfSource
    from frf_ident.io.mjcf.robot import load_robot
    pose = {'joint1': 0.3, 'joint2': 0.785398, 'joint3': 0.7, 'joint4': -1.5708,
            'joint5': -0.4, 'joint6': 0.9, 'joint7': 0.2}
    from plants.mujoco_iiwa import SHARED_IIWA
    robot = load_robot(MjcfSource(str(SHARED_IIWA), None, pose), ['joint2', 'joint4'])
    full = mujoco.MjModel.from_xml_path(str(SHARED_IIWA))
    df = mujoco.MjData(full)
    df.qpos[:] = [pose[f'joint{i + 1}'] for i in range(7)]
    mujoco.mj_forward(full, df)
    d = mujoco.MjData(robot.model)
    d.qpos[:] = [pose['joint2'], pose['joint4']]
    mujoco.mj_forward(robot.model, d)
    # the flange where the full model puts it (the welded bodies are fused into their parents)
    np.testing.assert_allclose(d.site('attachment_site').xpos,
                               df.site('attachment_site').xpos, atol=1e-12)
    np.testing.assert_allclose(d.site('attachment_site').xmat,
                               df.site('attachment_site').xmat, atol=1e-12)
    mf, ml = np.zeros((7, 7)), np.zeros((2, 2))
    mujoco.mj_fullM(full, df, mf)
    mujoco.mj_fullM(robot.model, d, ml)
    np.testing.assert_allclose(ml, mf[np.ix_([1, 3], [1, 3])], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(d.qfrc_bias, df.qfrc_bias[[1, 3]], rtol=1e-12, atol=1e-12)
