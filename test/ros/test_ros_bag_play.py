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
``ros2 bag play`` of the package's bag into an estimator_node estimates like the bag (issue 44).

Issue 44 found that replaying the package's bag into an estimator started with the package's
params file and ``--clock`` gave phase = true - 360 f dt (-21.6 deg at 60 Hz) without a word.
Here a short lockstep multisine run is recorded by the package, played with the real
``ros2 bag play`` into an estimator_node started with config/frf_ident.yaml (once with
``--clock`` and use_sim_time, once on wall time without ``--clock``, lockstep off as the
params file's rule demands), and the estimator's new bag is estimated beside the original:
magnitude within 0.01 dB and phase within 0.1 deg at every line up to the highest (61 Hz).
Both paths agree exactly, so a refusal would fail the test as well: never a silent phase
error, and no mismatch to refuse (test/bag/test_pairing.py covers the refusal of descriptors
that disagree).
"""
from pathlib import Path
import signal
import subprocess
import sys
import time

from frf_ident.middleware import READY
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


# the run is conftest's lockstep_run, shared with test_ros_graph and test_ros_bag_record
pytestmark = pytest.mark.xdist_group('ros_lockstep_run')


@pytest.fixture
def package_bag(lockstep_run):
    """Return the package's bag of a short lockstep multisine run (its estimator node)."""
    assert lockstep_run.result['multisine']['success'], lockstep_run.result
    return lockstep_run.bag


def _estimate(bag):
    from frf_ident.bag import read_recording
    from frf_ident.core.estimation.described import estimate_recording
    rec, _ = read_recording(bag)
    return rec, estimate_recording(rec)['multisine']


def _start_estimator(bag, env, clock):
    """estimator_node with the package's params file; on wall time without ``--clock``."""
    over = ['-p', f'estimator_node:bag:={bag}', '-p', 'estimator_node:estimate:=false']
    if not clock:
        over += ['-p', 'use_sim_time:=false', '-p', 'lockstep:=false',
                 '-p', 'estimator_node:use_sim_time:=false',
                 '-p', 'estimator_node:lockstep:=false']
    proc = subprocess.Popen(
        [sys.executable, '-m', 'frf_ident.nodes.estimator_node', '--ros-args', '--params-file',
         str(ROOT / 'config' / 'frf_ident.yaml'), *over],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    log = []
    deadline = time.monotonic() + 60.0
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        log.append(line)
        if line.startswith(READY):
            return proc, log
    proc.kill()
    raise AssertionError(f'estimator_node not ready: {"".join(log)}')


@pytest.mark.parametrize('clock', [True, False], ids=['clock', 'wall'])
def test_ros2_bag_play_into_the_estimator_equals_the_package_bag(tmp_path, ros_env, clock,
                                                                 package_bag):
    replayed = tmp_path / 'replayed'
    est, log = _start_estimator(replayed, ros_env, clock)
    try:
        time.sleep(1.0)       # discovery: the estimator's readers match the player's writers
        play = subprocess.run(['ros2', 'bag', 'play', str(package_bag),
                               '--disable-keyboard-controls',
                               *(['--clock', '100'] if clock else [])],
                              env=ros_env, capture_output=True, text=True, timeout=300)
        assert play.returncode == 0, play.stderr[-2000:]
        time.sleep(1.0)
    finally:
        est.send_signal(signal.SIGINT)
        try:
            log.append(est.communicate(timeout=60)[0])
        except subprocess.TimeoutExpired:
            est.kill()
            log.append(est.communicate()[0])
    assert est.returncode == 0, ''.join(log)[-2000:]
    own, est_own = _estimate(package_bag)
    got, est_got = _estimate(replayed)
    np.testing.assert_allclose(est_got.freq_hz, est_own.freq_hz)
    ratio = est_got.response / est_own.response
    db = np.max(np.abs(20 * np.log10(np.abs(ratio))))
    deg = np.max(np.abs(np.degrees(np.angle(ratio))))
    top = np.abs(np.degrees(np.angle(ratio[..., -1]))).max()
    print(f'ros2 bag play ({"--clock" if clock else "wall"}) vs package bag: '
          f'{got.t.size} / {own.t.size} samples, max {db:.1e} dB, {deg:.1e} deg '
          f'({top:.1e} deg at {est_own.freq_hz[-1]:.1f} Hz) over {est_own.freq_hz.size} lines')
    assert db < 0.01 and deg < 0.1, (db, deg)
