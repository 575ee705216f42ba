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
ROS 2 tests: run only where ROS 2 Jazzy is sourced (rclpy importable), else skipped.

Each test runs on a ROS_DOMAIN_ID of its own (test/conftest.py), which ``ros_env`` passes on.

``lockstep_run``: one short lockstep multisine run of the graph on rclpy, recorded by the
package's estimator and by ``ros2 bag record`` beside it, shared by test_ros_graph,
test_ros_bag_record and test_ros_bag_play (each started a graph for the same deterministic
run before; their modules share the xdist group ``ros_lockstep_run``, so the run happens once).
"""
from dataclasses import dataclass
import importlib.util
import os
from pathlib import Path
import signal
import subprocess
import time
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
HAVE_ROS = importlib.util.find_spec('rclpy') is not None and bool(os.environ.get('ROS_DISTRO'))


def pytest_collection_modifyitems(config, items):
    skip = pytest.mark.skip(reason='ROS 2 Jazzy not sourced (source /opt/ros/jazzy/setup.bash)')
    for item in items:
        if Path(str(item.fspath)).parent == Path(__file__).parent:
            item.add_marker(pytest.mark.ros)
            if not HAVE_ROS:
                item.add_marker(skip)


@pytest.fixture
def ros_env():
    """Environment of the ROS processes a test starts: loopback, the test's domain, rclpy."""
    env = dict(os.environ)
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', RMW_IMPLEMENTATION='rmw_cyclonedds_cpp',
               CYCLONEDDS_URI=(ROOT / 'config' / 'cyclonedds-localhost.xml').as_uri(),
               ROS_DOMAIN_ID=os.environ['ROS_DOMAIN_ID'], FRF_IDENT_MIDDLEWARE='rclpy',
               PYTHONUNBUFFERED='1',
               PYTHONPATH=os.pathsep.join([str(ROOT)] + [
                   p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]))
    return env


#: what ``ros2 bag record`` records: the topics of docs/CONTRACT.md §3
RECORDED_TOPICS = ['/joint_states', '/velocity_controller/commands',
                   '/effort_controller/commands', '/frf/excitation', '/frf/experiment']


@dataclass
class LockstepRun:
    """The shared run: its graph, driver results, the package's bag, the recorder's bag."""

    graph: Any
    result: dict
    bag: Path
    recorded: Path
    recorder_rc: int
    recorder_log: str


def _wait_subscribed(proc, log, timeout_s=60.0):
    """Read the recorder's output until it subscribed to every topic."""
    want = set(RECORDED_TOPICS)
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


@pytest.fixture(scope='session')
def lockstep_run(tmp_path_factory, new_domain):
    """Run a 16 s lockstep multisine on rclpy, recorded by the estimator and ros2 bag record."""
    from frf_ident.app.graph import Graph
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    ms = MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=2.0, compensate=False,
                         return_s=2.0, settle_s=0.3)
    out = tmp_path_factory.mktemp('lockstep_run')
    g = Graph(out / 'graph', multisine=ms, domain_id=new_domain(), middleware='rclpy',
              params={'excitation_node': {'stale_s': 2.0}})
    g.start()
    recorded = out / 'recorded'
    log: list[str] = []
    recorder = subprocess.Popen(
        ['ros2', 'bag', 'record', '-s', 'mcap', '--qos-profile-overrides-path',
         str(ROOT / 'config' / 'rosbag2_qos.yaml'), '-o', str(recorded), *RECORDED_TOPICS],
        env=dict(g.env), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        start_new_session=True)
    try:
        _wait_subscribed(recorder, log)
        res = g.drive(multisine=True, iterations=0)
        time.sleep(1.0)           # the recorder's queue drains
        # the estimator's live estimate (a worker thread) takes seconds on a loaded PC, and a
        # node stopped before it ends leaves it out: test_ros_graph checks its frf.json
        deadline = time.monotonic() + 120.0
        while not (g.frf_dir / 'frf.json').is_file() and time.monotonic() < deadline:
            time.sleep(0.2)
    finally:
        os.killpg(recorder.pid, signal.SIGINT)
        try:
            log.append(recorder.communicate(timeout=60)[0])
        except subprocess.TimeoutExpired:
            os.killpg(recorder.pid, signal.SIGKILL)
            recorder.communicate()
        bag = g.stop()
    return LockstepRun(g, res, bag, recorded, recorder.returncode, ''.join(log))
