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
``ros2 bag record`` of a lockstep run estimates like the package's own bag (issue 44).

The real recorder, with the shipped QoS override file (config/rosbag2_qos.yaml), records the
topics of a lockstep multisine run beside the estimator node (conftest's ``lockstep_run``).
Issue 44 found three faults on this path: the idle plant's re-sent stamp-0 joint states made
the reader fall back to log time and refuse ("stamp jitter of 18.7 % of dt"); with the default
QoS the recorder lost 31-41 % of /joint_states; and the raw joint states (effort of state k =
torque of sample k-1) gave phase = true + 360 f dt (21.6 deg at 60 Hz) without a warning. Here:
no joint state lost, and the multisine FRF of both bags agrees within 0.01 dB and 0.1 deg.
"""
import numpy as np
import pytest

# the run is conftest's lockstep_run, shared with test_ros_graph and test_ros_bag_play
pytestmark = pytest.mark.xdist_group('ros_lockstep_run')


def _estimate(bag):
    from frf_ident.bag import read_recording
    from frf_ident.core.estimation.described import estimate_recording
    rec, timing = read_recording(bag)
    return rec, timing, estimate_recording(rec)['multisine']


def test_ros2_bag_record_of_a_lockstep_run_equals_the_package_bag(lockstep_run):
    run = lockstep_run
    assert run.result['multisine']['success'], run.result
    rec_bag, bag = run.recorded, run.bag
    assert run.recorder_rc == 0, run.recorder_log[-2000:]
    assert (rec_bag / 'metadata.yaml').is_file()
    own, own_timing, est_own = _estimate(bag)
    got, got_timing, est_got = _estimate(rec_bag)
    js = got_timing.topics['/joint_states']
    assert js.missing_samples == 0 and js.gaps == 0, got_timing.summary()
    # the run's samples: every joint state of the package's bag is in the recorded one
    assert got.t.size >= own.t.size, (got.t.size, own.t.size)
    np.testing.assert_allclose(est_got.freq_hz, est_own.freq_hz)
    ratio = est_got.response / est_own.response
    db = np.max(np.abs(20 * np.log10(np.abs(ratio))))
    deg = np.max(np.abs(np.degrees(np.angle(ratio))))
    print(f'ros2 bag record vs package bag: {got.t.size} / {own.t.size} samples, max '
          f'{db:.4f} dB, {deg:.4f} deg over {est_own.freq_hz.size} lines up to '
          f'{est_own.freq_hz.max():.1f} Hz')
    assert db < 0.01 and deg < 0.1, (db, deg)
