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
"""Reading bags recorded by real robots: jitter, drops, gaps, duplicates, missing interfaces."""
from __future__ import annotations

from pathlib import Path

from bag_synth import JOINTS, truth, write_robot_bag
from frf_ident.bag import read_recording
from frf_ident.bag.timing import MAX_GAP_SAMPLES
from frf_ident.errors import BagError
import numpy as np
import pytest


def test_jitter_and_drops_resampled(tmp_path: Path) -> None:
    info = write_robot_bag(tmp_path / 'robot', jitter=0.01, drop=0.005)
    rec, rep = read_recording(tmp_path / 'robot', joints=JOINTS)
    assert rep.resampled and rep.grid == 'resampled'
    js = rep.topics['/joint_states']
    assert js.stamp_source == 'header'
    assert 0.005 < js.jitter < 0.012  # uniform +-1 %: std of intervals = 0.82 % of dt
    assert js.missing_samples == int((~info['keep']).sum()) and js.gaps > 0
    assert js.longest_gap_samples <= MAX_GAP_SAMPLES
    assert js.header_log_offset_mean_s == pytest.approx(300e-6, rel=0.05)
    assert rep.dt_s == pytest.approx(1e-3, rel=1e-5)
    assert rec.t.size == info['keep'].size  # dropped samples are back on the grid
    assert rec.joint_names == JOINTS
    default, _ = read_recording(tmp_path / 'robot')  # default: order of the first message
    assert sorted(default.joint_names) == JOINTS
    j = [default.joint_names.index(n) for n in JOINTS]
    np.testing.assert_array_equal(default.velocity[:, j], rec.velocity)
    # linear interpolation error bound: amplitude * (w * gap)^2 / 8 with gap <= 2 dt here
    pos, vel, eff = truth(rec.t)
    np.testing.assert_allclose(rec.position, pos, atol=1e-5)
    np.testing.assert_allclose(rec.velocity, vel, atol=2e-4)
    np.testing.assert_allclose(rec.effort, eff, atol=6e-4)
    assert rec.reference is None and rec.excitation is None
    assert any('jitter' in line for line in rep.summary())


def test_gap_too_large_is_refused(tmp_path: Path) -> None:
    write_robot_bag(tmp_path / 'gap', seconds=5.0, drop=0.0, gap=(2.3, 120))
    with pytest.raises(BagError) as exc:
        read_recording(tmp_path / 'gap', gaps='refuse')
    msg = str(exc.value)
    assert '\n' not in msg
    assert 'gap of 0.120 s (120 samples) at t=102.29' in msg
    assert '/joint_states' in msg and 'exceeds 3 samples' in msg
    # reading around the gap works
    rec, rep = read_recording(tmp_path / 'gap', t_range=(100.0, 102.25), gaps='refuse')
    assert rec.t[-1] <= 102.25 and not rep.topics['/joint_states'].gaps


def test_too_much_jitter_is_refused(tmp_path: Path) -> None:
    write_robot_bag(tmp_path / 'jit', seconds=2.0, jitter=0.08, drop=0.0)
    with pytest.raises(BagError, match=r'stamp jitter of \d+\.\d % of dt .* exceeds 5 %'):
        read_recording(tmp_path / 'jit')


def test_missing_interface_duplicates_and_reordering(tmp_path: Path) -> None:
    """ros2_control style: effort interface absent; one duplicated and one late message."""
    def extra(w, store):  # noqa: ANN001
        conn = w.connections[0]
        js = store.types['sensor_msgs/msg/JointState']
        hdr, tm_ = store.types['std_msgs/msg/Header'], store.types['builtin_interfaces/msg/Time']
        p, v, _ = truth(np.array([100.5]))
        # a duplicate of the sample at t=100.5 s... stamped exactly on it
        sec, nsec = divmod(info_stamp[0], 10**9)
        msg = js(header=hdr(stamp=tm_(sec=sec, nanosec=nsec), frame_id=''), name=list(JOINTS),
                 position=p[0], velocity=v[0], effort=np.empty(0))
        w.write(conn, info_stamp[0] + 10**9, store.serialize_cdr(msg, msg.__msgtype__))

    info_stamp = [int(round(100.5 * 1e9))]
    write_robot_bag(tmp_path / 'rc', seconds=2.0, jitter=0.0, drop=0.0, effort=False,
                    extra=extra)
    rec, rep = read_recording(tmp_path / 'rc', joints=JOINTS)
    js = rep.topics['/joint_states']
    assert js.duplicates == 1 and js.non_monotonic == 1
    assert np.all(np.isnan(rec.effort))
    pos, vel, _ = truth(rec.t)
    np.testing.assert_allclose(rec.velocity, vel, atol=1e-9)
    assert rec.t.size == 2000


def test_header_stamps_unset_use_log_time(tmp_path: Path) -> None:
    from frf_ident.bag.topics import QOS_DEFAULT
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores

    store = get_typestore(Stores.ROS2_JAZZY)
    js = store.types['sensor_msgs/msg/JointState']
    with Writer(tmp_path / 'log', version=9, storage_plugin=StoragePlugin.MCAP) as w:
        c = w.add_connection('/joint_states', js.__msgtype__, typestore=store,
                             offered_qos_profiles=[QOS_DEFAULT])
        for k in range(500):
            m = js(header=store.types['std_msgs/msg/Header'](
                stamp=store.types['builtin_interfaces/msg/Time'](sec=0, nanosec=0),
                frame_id=''), name=['a'], position=np.array([k * 1.0]),
                velocity=np.array([1.0]), effort=np.array([0.0]))
            w.write(c, 10**9 + k * 2_000_000, store.serialize_cdr(m, js.__msgtype__))
    rec, rep = read_recording(tmp_path / 'log')
    assert rep.topics['/joint_states'].stamp_source == 'log'
    assert rep.dt_s == pytest.approx(2e-3)
    assert any('header stamps are unset' in w for w in rep.warnings)
    np.testing.assert_array_equal(rec.position[:, 0], np.arange(500.0))


def test_idle_resent_sample_zero_keeps_header_stamps(tmp_path: Path) -> None:
    """
    ``ros2 bag record`` of a lockstep simulation: sample 0 re-sent while idle, then the run.

    The idle plant re-sends its stamp-0 joint state every 0.2 s wall; the reader took the
    several zero stamps for "header stamps unset", fell back to the (wall) log time and
    refused with "stamp jitter of 18.7 % of dt" (issue 44). The copies are one sample.
    """
    from frf_ident.bag.topics import QOS_DEFAULT
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores

    store = get_typestore(Stores.ROS2_JAZZY)
    js = store.types['sensor_msgs/msg/JointState']
    rng = np.random.default_rng(3)
    stamps = [0] * 6 + [k * 1_000_000 for k in range(1, 2000)]
    logs = np.cumsum(np.r_[[2e8] * 6, rng.uniform(1e4, 2e6, 1999)]).astype(np.int64)
    with Writer(tmp_path / 'rec', version=9, storage_plugin=StoragePlugin.MCAP) as w:
        c = w.add_connection('/joint_states', js.__msgtype__, typestore=store,
                             offered_qos_profiles=[QOS_DEFAULT])
        for ns, log in zip(stamps, logs):
            sec, nsec = divmod(ns, 10**9)
            m = js(header=store.types['std_msgs/msg/Header'](
                stamp=store.types['builtin_interfaces/msg/Time'](sec=sec, nanosec=nsec),
                frame_id=''), name=['a'], position=np.array([ns * 1e-6]),
                velocity=np.array([1.0]), effort=np.array([0.0]))
            w.write(c, int(log), store.serialize_cdr(m, js.__msgtype__))
    rec, rep = read_recording(tmp_path / 'rec')
    assert rep.topics['/joint_states'].stamp_source == 'header'
    assert rep.topics['/joint_states'].duplicates == 5
    np.testing.assert_allclose(rec.t, np.arange(2000) * 1e-3, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(rec.position[:, 0], np.arange(2000.0))


def test_zero_stamps_after_set_ones_count_as_unset() -> None:
    from frf_ident.bag.timing import valid_header_stamps
    assert valid_header_stamps(np.array([0, 0, 0, 1, 2, 3]))
    assert not valid_header_stamps(np.array([0, 1, 0, 2, 0, 3]))
    assert not valid_header_stamps(np.zeros(5, dtype=np.int64))


def test_slow_commands_are_zero_order_held(tmp_path: Path) -> None:
    """A ros2_control-style bag: 1 kHz joint states, velocity commands at 100 Hz (log time)."""
    f64 = None

    def extra(w, store):  # noqa: ANN001
        nonlocal f64
        f64 = store.types['std_msgs/msg/Float64MultiArray']
        lay = store.types['std_msgs/msg/MultiArrayLayout']
        c = w.add_connection('/velocity_controller/commands', f64.__msgtype__, typestore=store,
                             offered_qos_profiles=[QOS_DEFAULT])
        for i in range(100):  # 100.000 .. 100.990 s; value i on every joint
            m = f64(layout=lay(dim=[], data_offset=0), data=np.full(3, float(i)))
            raw = store.serialize_cdr(m, f64.__msgtype__)
            w.write(c, int(round((100.0 + 0.01 * i) * 1e9)), raw)

    from frf_ident.bag.topics import QOS_DEFAULT

    write_robot_bag(tmp_path / 'zoh', seconds=1.5, jitter=0.0, drop=0.0, extra=extra)
    rec, rep = read_recording(tmp_path / 'zoh')
    t_cmd = 100.0 + 0.01 * np.arange(100)
    idx = np.searchsorted(np.round(t_cmd * 1e9), np.round(rec.t * 1e9), side='right') - 1
    expect = np.where(rec.t - t_cmd[idx] <= 0.03 + 1e-9, idx, -1).astype(float)
    expect[expect < 0] = np.nan
    np.testing.assert_array_equal(rec.reference[:, 0], expect)
    assert np.isnan(rec.reference[-1, 0])  # held 30 ms (3 command periods), then NaN
    assert any('unequal rates' in w for w in rep.warnings)
    assert rep.topics['/velocity_controller/commands'].rate_hz == pytest.approx(100.0)


def test_long_gap_kept_as_missing_data(tmp_path: Path) -> None:
    """gaps='mark' (the default): the grid goes through the gap, its samples NaN, rest as usual."""
    write_robot_bag(tmp_path / 'gap', seconds=5.0, drop=0.0, gap=(2.3, 120))
    rec, rep = read_recording(tmp_path / 'gap')
    assert rec.t.size == 5000 and rep.resampled
    nan = np.flatnonzero(np.isnan(rec.velocity[:, 0]))
    np.testing.assert_array_equal(nan, np.arange(2300, 2420))
    assert np.all(np.isnan(rec.effort[nan]))
    assert not np.any(np.isnan(np.delete(rec.effort, nan, axis=0)))
    assert rep.missing == rec.meta['gaps'] == [[pytest.approx(102.3, abs=2e-5),
                                                pytest.approx(102.419, abs=2e-5)]]
    assert any('1 gaps longer than 3 samples kept as missing data (120 samples' in line
               for line in rep.summary())
    pos, vel, eff = truth(np.delete(rec.t, nan))
    np.testing.assert_allclose(np.delete(rec.velocity, nan, axis=0), vel, atol=2e-4)
    with pytest.raises(ValueError, match="gaps='skip'"):
        read_recording(tmp_path / 'gap', gaps='skip')
