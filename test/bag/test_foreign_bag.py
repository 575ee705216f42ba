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
"""Bags that did not come from frf_ident: only /joint_states, robot-like timing."""
from frf_ident.bag import read_recording
from frf_ident.cli import main
from frf_ident.core.estimation.described import estimate_recording
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.core.model.schema import default_model_dict, robot_from_dict
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.controller import controller_from_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
import numpy as np
import pytest
from scipy.interpolate import CubicSpline

# module fixtures shared by the tests here: they run on one worker (make test, pytest-xdist)
pytestmark = pytest.mark.xdist_group('test_foreign_bag')

FS = 1000.0


@pytest.fixture(scope='module')
def clean_run():
    """3-axis closed loop, odd multisine velocity reference on joint_2, 6 periods."""
    d = default_model_dict()
    rob = robot_from_dict(d)
    ctrl = controller_from_dict(d, rob)
    des = design_odd_multisine(2.0, 60.0, bound=0.01, resolution_hz=0.5, fs=FS)
    real = multisine_realisation(des, 1, np.random.default_rng(0), fs=FS)
    n = des.period_samples(FS)
    r = np.zeros((6 * n, 3))
    r[:, 1] = np.tile(real.evaluate(np.arange(n) / FS)[0][:, 0], 6)
    res = FlexibleJointPlant(rob).simulate(reference=r, controller=ctrl)
    return Recording(res.t, rob.joint_names, res.position, res.velocity, res.effort)


def _write_joint_states_bag(path, rec, rng, jitter=0.01, drop=0.005):
    """
    Write a jittered /joint_states-only bag with the rosbags writer.

    rosbags writer, /joint_states only, shuffled joint order; sample k is taken at
    k dt + U(+-jitter) dt (values interpolated there), 0.5 % of the messages dropped.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores
    ts = get_typestore(Stores.ROS2_JAZZY)
    JointState = ts.types['sensor_msgs/msg/JointState']
    Header = ts.types['std_msgs/msg/Header']
    Time = ts.types['builtin_interfaces/msg/Time']
    dt = 1.0 / FS
    t = rec.t + rng.uniform(-jitter, jitter, rec.t.size) * dt
    t[0] = rec.t[0]
    keep = rng.random(t.size) >= drop
    splines = {k: CubicSpline(rec.t, getattr(rec, k), axis=0)
               for k in ('position', 'velocity', 'effort')}
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection('/joint_states', JointState.__msgtype__, typestore=ts)
        for k in np.flatnonzero(keep):
            order = rng.permutation(3)
            ns = int(round((t[k] + 100.0) * 1e9))
            vals = {f: splines[f](t[k])[order] for f in splines}
            msg = JointState(header=Header(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9),
                                           frame_id=''),
                             name=[rec.joint_names[i] for i in order], **vals)
            w.write(conn, ns + 200_000, ts.serialize_cdr(msg, JointState.__msgtype__))
    return int((~keep).sum())


def test_jittered_dropped_joint_states_only_bag_within_005_db_and_half_a_degree(
        clean_run, tmp_path, capsys):
    clean = estimate_recording(clean_run)
    assert list(clean) == ['detected/joint_2']
    dropped = _write_joint_states_bag(tmp_path / 'robot', clean_run, np.random.default_rng(4))
    assert dropped > 0
    rec, timing = read_recording(tmp_path / 'robot')
    assert timing.resampled
    est = estimate_recording(rec)['detected/joint_2']
    ref = clean['detected/joint_2']
    common, i_est, i_ref = np.intersect1d(np.round(est.freq_hz, 6), np.round(ref.freq_hz, 6),
                                          return_indices=True)
    assert common.size >= 0.8 * ref.freq_hz.size   # resampling noise hides a few weak lines
    o_est, o_ref = est.outputs.index('dq_m/joint_2'), ref.outputs.index('dq_m/joint_2')
    ratio = est.response[o_est, 0, i_est] / ref.response[o_ref, 0, i_ref]   # driven channel
    err_db, err_deg = 20 * np.log10(np.abs(ratio)), np.degrees(np.angle(ratio))
    with capsys.disabled():      # shown by pytest -s (the README figure)
        print(f'{common.size} lines, max |error| {np.max(np.abs(err_db)):.4f} dB, '
              f'{np.max(np.abs(err_deg)):.3f} deg')
    # magnitude and phase: a one-sample shift between effort and velocity (3.6 deg per
    # 10 Hz at 1 kHz) keeps every magnitude
    assert np.max(np.abs(err_db)) <= 0.05 and np.max(np.abs(err_deg)) <= 0.5
    # the command line says what it detected
    assert main(['estimate', str(tmp_path / 'robot'), '--out', str(tmp_path / 'est')]) == 0
    out = capsys.readouterr().out
    assert 'detected: joint_2' in out and 'multisine' in out
