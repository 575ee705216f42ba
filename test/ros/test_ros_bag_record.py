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
topics of a lockstep multisine run beside the estimator node. Issue 44 found three faults on
this path: the idle plant's re-sent stamp-0 joint states made the reader fall back to log
time and refuse ("stamp jitter of 18.7 % of dt"); with the default QoS the recorder lost
31-41 % of /joint_states; and the raw joint states (effort of state k = torque of sample
k-1) gave phase = true + 360 f dt (21.6 deg at 60 Hz) without a warning. Here: no joint
state lost, and the multisine FRF of both bags agrees within 0.01 dB and 0.1 deg.
"""
import os
from pathlib import Path
import signal
import subprocess
import time

from frf_ident.app.graph import Graph
from frf_ident.core.excitation.procedures import MultisineConfig
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
TOPICS = ['/joint_states', '/velocity_controller/commands', '/effort_controller/commands',
          '/frf/excitation', '/frf/experiment']
MS = MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=2.0, compensate=False,
                     return_s=2.0, settle_s=0.3)


def _wait_subscribed(proc, log, timeout_s=60.0):
    """Read the recorder's output until it subscribed to every topic."""
    want = set(TOPICS)
    deadline = time.monotonic() + timeout_s
    while want and time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        log.append(line)
        for t in list(want):
            if f"Subscribed to topic '{t}'" in line:
                want.discard(t)
    assert not want, f'ros2 bag record did not subscribe to {sorted(want)}: {"".join(log)}'


def _estimate(bag):
    from frf_ident.bag import read_recording
    from frf_ident.core.estimation.described import estimate_recording
    rec, timing = read_recording(bag)
    return rec, timing, estimate_recording(rec)['multisine']


def test_ros2_bag_record_of_a_lockstep_run_equals_the_package_bag(tmp_path, ros_env):
    g = Graph(tmp_path / 'graph', multisine=MS, domain_id=int(ros_env['ROS_DOMAIN_ID']),
              middleware='rclpy')
    g.start()
    rec_bag = tmp_path / 'recorded'
    log: list[str] = []
    recorder = subprocess.Popen(
        ['ros2', 'bag', 'record', '-s', 'mcap', '--qos-profile-overrides-path',
         str(ROOT / 'config' / 'rosbag2_qos.yaml'), '-o', str(rec_bag), *TOPICS],
        env=dict(g.env), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        start_new_session=True)
    try:
        _wait_subscribed(recorder, log)
        res = g.drive(multisine=True, iterations=0)
        assert res['multisine']['success'], res
        time.sleep(1.0)           # the recorder's queue drains
    finally:
        os.killpg(recorder.pid, signal.SIGINT)
        try:
            log.append(recorder.communicate(timeout=60)[0])
        except subprocess.TimeoutExpired:
            os.killpg(recorder.pid, signal.SIGKILL)
            recorder.communicate()
        bag = g.stop()
    assert recorder.returncode == 0, ''.join(log)[-2000:]
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
