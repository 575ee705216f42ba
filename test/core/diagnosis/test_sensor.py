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
The sensor read from the record (issue 55 item 1).

Truth the code did not produce: records of the independent reference plant
(test/plants/reference.py, whose encoder and differenced velocity are written there) under a
PD loop written here, with each sensor on and off; and the real records, whose sensors are
known from their sources (EMPS: encoder positions, velocity the central difference of the
import map; KUKA: the drive's own filtered velocity).
"""
from pathlib import Path

from frf_ident.core.diagnosis.common import simulate_like
from frf_ident.core.diagnosis.sensor import (model_sensor, read_sensor, sensor_effects,
                                             with_lacking_sensor, with_sensor)
from frf_ident.core.model.schema import robot_from_dict
from frf_ident.core.recording import Recording
import numpy as np
from plants import reference
import pytest

ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT.parent / 'shared' / 'data'
FS = 1000.0
MODEL = {'frf_ident_model': 1, 'sample_rate': FS, 'axes': [
    {'name': f'joint_{k + 1}', 'motor_inertia': 0.5, 'link_inertia': 1.0, 'stiffness': 3e5,
     'damping': 50.0, 'viscous_friction': 0.5, 'torque_limit': 1e4} for k in range(2)],
    'controller': {'kind': 'pi_velocity', 'kp': [50.0, 50.0], 'ki': [0.0, 0.0]}}


def _record(sensor: dict, seed: int = 2, T: float = 3.0) -> Recording:
    """Return the reference plant following slow sines under a PD loop, read by ``sensor``."""
    rng = np.random.default_rng(seed)
    reference.SCENE = {'velocity_noise': 2e-5, 'seed': seed, **sensor}
    try:
        plant = reference.ReferencePlant(MODEL)
    finally:
        reference.SCENE = {}
    t = np.arange(int(T * FS)) / FS
    w = 2 * np.pi * rng.uniform(0.3, 2.0, (3, 2))
    qr = (0.3 * np.sin(t[:, None, None] * w)).sum(axis=1)
    vr = (0.3 * w * np.cos(t[:, None, None] * w)).sum(axis=1)
    q, v, e = np.zeros((t.size, 2)), np.zeros((t.size, 2)), np.zeros((t.size, 2))
    qk, vk = np.zeros(2), np.zeros(2)
    for k in range(t.size):
        u = 2000.0 * (qr[k] - qk) + 80.0 * (vr[k] - vk)
        q[k], v[k], e[k] = qk, vk, u
        qk, vk, _ = plant.step(u)
    return Recording(t, ['joint_1', 'joint_2'], q, v, e)


@pytest.mark.parametrize('res', [1e-6, 1e-5])
def test_a_differenced_encoder_is_read_with_its_step(res):
    rec = _record({'encoder_resolution': [res, 2 * res], 'velocity_from_encoder': True})
    got = read_sensor(rec)
    for s, r in zip(got, (res, 2 * res)):
        assert s.resolution == pytest.approx(r, rel=1e-6), s
        assert s.differenced, s
        # the quantisation floor on a differenced velocity: r / (dt sqrt 6)
        assert s.velocity_floor == pytest.approx(r * FS / np.sqrt(6), rel=1e-6)
    robot = robot_from_dict(MODEL)
    names = sorted((e.name, e.axis) for e in sensor_effects(got, robot))
    assert names == sorted((n, a) for a in ('joint_1', 'joint_2')
                           for n in ('quantisation', 'velocity_from_encoder'))
    ext = with_sensor(robot, got)
    assert ext.velocity_from_encoder and ext.axes[1].encoder_resolution == pytest.approx(2 * res)
    # a model that has the sensor lacks nothing
    assert sensor_effects(got, ext) == []


def test_a_true_velocity_or_an_ideal_encoder_is_no_sensor_effect():
    plain = read_sensor(_record({}))
    assert all(s.resolution is None and not s.differenced for s in plain), plain
    fine = read_sensor(_record({'velocity_from_encoder': True}))
    assert all(s.resolution is None and s.differenced for s in fine), fine
    coarse = read_sensor(_record({'encoder_resolution': 1e-5}))
    assert all(s.resolution is not None and not s.differenced for s in coarse), coarse


@pytest.mark.parametrize('data, map_name, step, differenced', [
    ('EMPS/DATA_EMPS.mat', 'map_emps.yaml', 5e-8, False),
    ('KUKA_KR300_Weigand2021/recorded_FF_A_2020-10-21.mat', 'map_kuka_kr300.yaml', None, False)])
def test_the_real_records_sensors(data, map_name, step, differenced):
    """EMPS: positions in steps of 5e-8 m, velocity central; KUKA: neither (filtered)."""
    if not (DATA / data).is_file():
        pytest.skip('shared data not present')
    from frf_ident.app.diagnose import load_data
    rec = load_data(DATA / data, ROOT / 'config' / map_name)
    for s in read_sensor(rec)[:3]:
        print(s)
        assert (s.resolution is None) == (step is None), s
        if step is not None:
            assert s.resolution == pytest.approx(step, rel=1e-6)
        assert s.differenced == differenced, s


def test_our_plant_outputs_the_true_velocity_so_a_differenced_record_names_the_sensor():
    """Our plant's own simulation is read as the record's: its velocity is no difference."""
    from frf_ident.core.recording import Segment
    from frf_ident.core.simulation.controller import controller_from_dict
    base = _record({'velocity_from_encoder': True})
    vr = np.gradient(base.position, base.t, axis=0)       # what the loop followed, about
    rec = Recording(base.t, base.joint_names, base.position, base.velocity, base.effort, vr,
                    np.zeros_like(vr), [Segment(0.0, base.t[-1] + 1 / FS,
                                                {'design': 'multisine', 'realisation': 0})])
    robot = robot_from_dict(MODEL)
    shown = model_sensor(rec, robot, controller_from_dict(MODEL, robot))
    print(shown)
    assert shown is not None and not any(s.differenced for s in shown), shown
    named = [e.axis for e in sensor_effects(read_sensor(rec), robot, shown=shown)
             if e.name == 'velocity_from_encoder']
    assert named == ['joint_1', 'joint_2']
    assert with_sensor(robot, read_sensor(rec), shown).velocity_from_encoder
    ctrl = controller_from_dict(MODEL, robot)
    assert with_lacking_sensor(rec, robot, simulate_like(rec, robot, ctrl)).velocity_from_encoder
    # a time series (no reference, no experiments): the model follows its measured velocity,
    # its output is still no difference, so the sensor is still named (issue 50)
    shown = model_sensor(base, robot, ctrl)
    assert shown is not None and not any(s.differenced for s in shown), shown
    assert [e.axis for e in sensor_effects(read_sensor(base), robot, shown=shown)
            if e.name == 'velocity_from_encoder'] == ['joint_1', 'joint_2']
    # a record whose velocity is no difference: nothing the model could lack, no simulation
    assert model_sensor(_record({}), robot, ctrl) is None
