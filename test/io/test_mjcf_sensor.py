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
The sensor an MJCF in MuJoCo already has: no ``velocity_from_encoder`` against it.

MuJoCo's semi-implicit step updates q_(k+1) = q_k + h v_(k+1), so an MJCF stepped once per
sample (the shared iiwa 14: implicitfast, 1 ms, sampled at 1 kHz) outputs as velocity exactly
the backward difference of its positions. A record of it (here: the iiwa simulated by MuJoCo,
velocity noise added as a filtered encoder velocity would have) shows the sensor effect of
issue 55, and so does the nominal MJCF's own simulation: the model lacks nothing
(frf_ident.core.diagnosis.sensor.model_sensor). Truth the code did not produce: MuJoCo's
output, the difference checked here on it.
"""
from frf_ident.core.diagnosis.sensor import (model_sensor, read_sensor, sensor_effects,
                                             with_lacking_sensor, with_sensor)
from frf_ident.core.recording import Recording, Segment
import numpy as np
from plants.mujoco_iiwa import SHARED_IIWA
import pytest
import yaml

pytest.importorskip('mujoco')
MjcfModels = pytest.importorskip('frf_ident.io.mjcf.candidate').MjcfModels

pytestmark = pytest.mark.xdist_group('mujoco_iiwa')

FS = 1000.0
#: [rad/s] as test/app/test_diagnose_mjcf.py's scene
VELOCITY_NOISE = 5e-4


def _nominal(tmp_path):
    """Return the shared iiwa's joint2 and joint4 as a model file naming the MJCF."""
    from frf_ident.io.model_file import load_model
    if not SHARED_IIWA.is_file():
        pytest.skip('shared data not present')
    d = {'frf_ident_model': 1, 'sample_rate': FS, 'mjcf': str(SHARED_IIWA), 'pose': 'home',
         'axes': [{'name': 'joint2'}, {'name': 'joint4'}],
         'controller': {'kind': 'pi_velocity', 'kp': [150.0, 50.0], 'ki': [1500.0, 500.0]}}
    (tmp_path / 'm.yaml').write_text(yaml.safe_dump(d))
    return load_model(tmp_path / 'm.yaml')[1:]


def _excitation(n_axes: int, T: float = 4.0, seed: int = 3) -> Recording:
    """Return a record template: sines as velocity reference, one multisine segment."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(T * FS)) / FS
    w = 2 * np.pi * rng.uniform(1.0, 20.0, (5, n_axes))
    ref = (0.05 * np.sin(t[:, None, None] * w + rng.uniform(0, 6, w.shape))).sum(axis=1)
    z = np.zeros((t.size, n_axes))
    names = [f'a{i}' for i in range(n_axes)]
    return Recording(t, names, z, z, z, ref, z.copy(),
                     [Segment(0.0, T, {'design': 'multisine', 'realisation': 0})])


def test_a_difference_the_mjcf_itself_outputs_is_no_sensor_effect(tmp_path):
    robot, ctrl = _nominal(tmp_path)
    mj = MjcfModels(robot)
    template = _excitation(robot.n_axes)
    template = Recording(template.t, robot.joint_names, template.position, template.velocity,
                         template.effort, template.reference, template.excitation,
                         template.segments)
    sim = mj(template, robot, ctrl)
    rng = np.random.default_rng(7)
    rec = Recording(sim.t, sim.joint_names, sim.position,
                    sim.velocity + VELOCITY_NOISE * rng.standard_normal(sim.velocity.shape),
                    sim.effort, sim.reference, sim.excitation, sim.segments)
    back = np.diff(sim.position, axis=0) * FS
    dev = np.abs(sim.velocity[1:] - back).max(axis=0)
    print(f'MuJoCo: max |v_k - (q_k - q_(k-1)) / h| {dev} rad/s for max |v| '
          f'{np.abs(sim.velocity).max(axis=0)} rad/s')
    assert np.all(dev < 1e-9 * np.abs(sim.velocity).max(axis=0))
    reading = read_sensor(rec, robot.joint_names)
    assert all(s.differenced for s in reading), reading          # the record shows it ...
    # ... so the record alone names it on every axis (the false alarm before the model's
    # own output was read)
    assert {e.axis for e in sensor_effects(reading, robot)
            if e.name == 'velocity_from_encoder'} == set(robot.joint_names)
    shown = model_sensor(rec, robot, ctrl, mj)
    print('record:', reading, '\nnominal MJCF:', shown)
    assert all(s.differenced for s in shown), shown              # ... and so does the MJCF
    assert [e for e in sensor_effects(reading, robot, shown=shown)
            if e.name == 'velocity_from_encoder'] == []
    assert not with_sensor(robot, reading, shown).velocity_from_encoder
    # the experiments route searches against the nominal as it is
    assert with_lacking_sensor(rec, robot, mj(rec, robot, ctrl)) is robot


def _time_series(tmp_path, T: float = 8.0):
    """Return the nominal MJCF, its controller and its own simulation as a plain time series."""
    robot, ctrl = _nominal(tmp_path)
    mj = MjcfModels(robot)
    template = _excitation(robot.n_axes, T=T)
    template = Recording(template.t, robot.joint_names, template.position, template.velocity,
                         template.effort, template.reference, template.excitation,
                         template.segments)
    sim = mj(template, robot, ctrl)
    rng = np.random.default_rng(11)
    noisy = sim.velocity + VELOCITY_NOISE * rng.standard_normal(sim.velocity.shape)
    # what a robot's log holds: the joint states, no reference, no experiments
    return robot, ctrl, mj, Recording(sim.t, sim.joint_names, sim.position, noisy, sim.effort,
                                      None, None, [])


def test_the_time_series_route_reads_the_mjcfs_own_output_too(tmp_path):
    """
    The time series of the nominal MJCF itself: no velocity_from_encoder on either route.

    Without experiments the nominal model is simulated following the record's velocity (its
    reference unknown): MuJoCo's output is the backward difference, as the record's is.
    """
    robot, ctrl, mj, rec = _time_series(tmp_path)
    reading = read_sensor(rec, robot.joint_names)
    assert all(s.differenced for s in reading), reading
    shown = model_sensor(rec, robot, ctrl, mj)
    print('record:', reading, '\nnominal MJCF on the time series:', shown)
    assert shown is not None and all(s.differenced for s in shown), shown
    assert [e for e in sensor_effects(reading, robot, shown=shown)
            if e.name == 'velocity_from_encoder'] == []


def test_time_series_diagnosis_of_the_nominal_mjcf_names_no_sensor(tmp_path):
    from frf_ident.core.diagnosis.pipeline import diagnose
    robot, ctrl, mj, rec = _time_series(tmp_path)
    res = diagnose(rec, robot, ctrl, simulator=mj, jobs=1)
    assert res.mode == 'timeseries'
    names = [(e.name, e.axis) for e in res.result.effects]
    print('effects:', names)
    assert not [n for n in names if n[0] == 'velocity_from_encoder'], names
    assert not res.result.extended.velocity_from_encoder
