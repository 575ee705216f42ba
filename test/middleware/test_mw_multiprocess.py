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
"""Two processes over Cyclone DDS on loopback: topics, Trigger service, latched topic."""

import json
from pathlib import Path
import subprocess
import sys
import threading
import time

import pytest

PEER = Path(__file__).with_name('mw_peer.py')


@pytest.fixture
def peer(domain_env):
    """Start ``mw_peer.py MODE`` on this module's domain; stop it when the test ends."""
    procs = []

    def start(mode: str) -> subprocess.Popen:
        proc = subprocess.Popen([sys.executable, str(PEER), mode], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, text=True, env=domain_env)
        procs.append(proc)
        assert proc.stdout.readline().strip() == 'ready', f'peer {mode=} did not start'
        return proc

    yield start
    for proc in procs:
        if proc.stdin:
            proc.stdin.close()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            pytest.fail(f'peer {proc.args} did not exit')


def _spin_until(node, predicate, timeout: float = 10.0) -> None:
    from frf_ident import middleware as mw
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, 'timed out waiting for DDS data'
        mw.spin_once(node, 0.05)


def test_topics_cross_process(peer):
    from frf_ident import middleware as mw
    assert mw.backend_name() == 'dds'
    peer('publish')
    node = mw.create_node('mw_test_sub')
    states, commands = [], []
    node.create_subscription(mw.msg('sensor_msgs/msg/JointState'), 'joint_states',
                             states.append, mw.qos_sensor_data())  # best-effort reader
    node.create_subscription(mw.msg('std_msgs/msg/Float64MultiArray'),
                             '/effort_controller/commands', commands.append, 10)
    _spin_until(node, lambda: states and commands)
    js = states[-1]
    assert js.header.frame_id == 'base' and js.header.stamp.nanosec == 123
    assert js.header.stamp.sec >= 1
    assert list(js.name) == ['joint1', 'joint2']
    assert list(js.position) == [0.5, -1.25] and list(js.velocity) == [1e-3, 2.0]
    assert list(js.effort) == [float(js.header.stamp.sec), 7.0]
    cmd = commands[-1]
    assert list(cmd.data) == [3.5, -4.0]
    dim = cmd.layout.dim[0]
    assert (dim.label, dim.size, dim.stride, cmd.layout.data_offset) == ('joints', 2, 2, 0)
    node.destroy_node()


def test_publisher_to_other_process(peer):
    from frf_ident import middleware as mw
    node = mw.create_node('mw_test_pub')
    JointState = mw.msg('sensor_msgs/msg/JointState')
    pub = node.create_publisher(JointState, '/joint_states', 10)
    proc = peer('subscribe')
    result: list[str] = []
    reader = threading.Thread(target=lambda: result.append(proc.stdout.readline()), daemon=True)
    reader.start()
    deadline = time.monotonic() + 10
    while reader.is_alive() and time.monotonic() < deadline:
        pub.publish(JointState(
            header=mw.msg('std_msgs/msg/Header')(
                stamp=mw.msg('builtin_interfaces/msg/Time')(sec=42, nanosec=0)),
            name=['a'], position=[2.5]))
        time.sleep(0.02)
    assert result and json.loads(result[0]) == {'name': ['a'], 'position': [2.5], 'sec': 42}
    node.destroy_node()


def test_trigger_service_cross_process(peer):
    from frf_ident import middleware as mw
    peer('service')
    Trigger = mw.srv('std_srvs/srv/Trigger')
    node = mw.create_node('mw_test_client')
    client = node.create_client(Trigger, '/frf/run_iteration')
    assert client.wait_for_service(timeout_sec=10)
    # call() from this thread while nobody spins the node: must not deadlock
    first = client.call(Trigger.Request(), timeout_sec=5)
    assert (first.success, first.message) == (True, 'iteration 1 done')
    # call() from a second thread while the main thread spins the node
    stop = threading.Event()
    spinner = threading.Thread(target=mw.spin, args=(node, stop))
    spinner.start()
    try:
        out = []
        caller = threading.Thread(target=lambda: out.append(
            client.call(Trigger.Request(), timeout_sec=5)))
        caller.start()
        caller.join(10)
        assert out and out[0].message == 'iteration 2 done'
        future = client.call_async(Trigger.Request())  # completed by the spinning thread
        assert future.wait(5) and future.result().message == 'iteration 3 done'
    finally:
        stop.set()
        spinner.join(5)
    node.destroy_node()


def test_call_without_service_times_out(domain_env):
    from frf_ident import middleware as mw
    node = mw.create_node('mw_test_lonely')
    client = node.create_client(mw.srv('std_srvs/srv/Trigger'), '/nobody_here')
    assert not client.wait_for_service(timeout_sec=0.2)
    with pytest.raises(TimeoutError, match='nobody_here'):
        client.call(mw.srv('std_srvs/srv/Trigger').Request(), timeout_sec=0.2)
    node.destroy_node()


def test_transient_local_late_joiner(peer):
    from frf_ident import middleware as mw
    peer('latched')
    time.sleep(0.2)  # the samples are written before we exist
    node = mw.create_node('mw_test_late')
    got = []
    node.create_subscription(mw.msg('std_msgs/msg/String'), '/frf/experiment',
                             got.append, mw.qos_transient_local())
    _spin_until(node, lambda: got)
    time.sleep(0.2)
    mw.spin_once(node, 0.1)
    assert [json.loads(m.data) for m in got] == [{'segment': 2}]  # keep-last 1
    node.destroy_node()
