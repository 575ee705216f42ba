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
"""DDS backend node behaviour: sim time, timers, discovery info, backend choice, loopback."""

from pathlib import Path
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

from frf_ident import middleware as mw
import pytest


def test_sim_time_drives_clock_and_timers(domain_env):
    Clock = mw.msg('rosgraph_msgs/msg/Clock')
    Time = mw.msg('builtin_interfaces/msg/Time')
    plant = mw.create_node('mw_sim_plant')
    clock_pub = plant.create_publisher(Clock, '/clock', mw.qos_clock())
    node = mw.create_node('mw_sim_node', use_sim_time=True)
    assert node.get_parameter('use_sim_time').value is True
    assert node.get_clock().now().nanoseconds == 0  # no /clock yet
    ticks = []
    node.create_timer(0.1, lambda: ticks.append(node.get_clock().now().nanoseconds))
    while clock_pub.get_subscription_count() == 0:
        time.sleep(0.005)
    for k in range(1, 21):  # 50 ms steps up to 1.0 s of simulated time
        target = k * 50_000_000
        clock_pub.publish(Clock(clock=Time(sec=target // 10**9, nanosec=target % 10**9)))
        deadline = time.monotonic() + 5
        while node.get_clock().now().nanoseconds != target:
            assert time.monotonic() < deadline, f'/clock {target} not received'
            mw.spin_once(node, 0.1)
    assert ticks == [k * 100_000_000 for k in range(1, 11)]
    now = node.get_clock().now()
    assert now.nanoseconds == 10**9 and now.to_msg() == Time(sec=1, nanosec=0)
    node.destroy_node()
    plant.destroy_node()


def test_wall_timer_and_cancel(domain_env):
    node = mw.create_node('mw_wall_timer')
    ticks = []
    timer = node.create_timer(0.02, lambda: ticks.append(time.monotonic()))
    end = time.monotonic() + 0.3
    while time.monotonic() < end:
        mw.spin_once(node, 0.05)
    assert 10 <= len(ticks) <= 16
    timer.cancel()
    count = len(ticks)
    mw.spin_once(node, 0.1)
    assert len(ticks) == count
    stamp = node.get_clock().now()
    assert abs(stamp.nanoseconds - time.time_ns()) < 10**9 and stamp.to_msg().sec > 1e9
    with pytest.raises(ValueError, match='period'):
        node.create_timer(0.0, lambda: None)
    node.destroy_node()


def test_ros_discovery_info_lists_node_entities(domain_env):
    from cyclonedds.core import Policy, Qos
    from cyclonedds.sub import DataReader
    from frf_ident.middleware import dds_context
    from frf_ident.middleware import ros_types as rt
    node = mw.create_node('mw_graph_node')
    pub = node.create_publisher(mw.msg('std_msgs/msg/String'), '/frf/experiment',
                                mw.qos_transient_local())
    sub = node.create_subscription(mw.msg('sensor_msgs/msg/JointState'), '/joint_states',
                                   lambda m: None, 10)
    ctx = dds_context.get_context()
    reader = DataReader(ctx.participant,
                        ctx.topic('ros_discovery_info', rt.ParticipantEntitiesInfo),
                        Qos(Policy.Reliability.Reliable(10**9), Policy.Durability.TransientLocal,
                            Policy.History.KeepLast(1)))
    deadline = time.monotonic() + 5
    info = None
    while info is None or 'mw_graph_node' not in {
            n.node_name for n in info.node_entities_info_seq}:
        assert time.monotonic() < deadline, 'no ros_discovery_info sample'
        samples = reader.take(10)
        info = samples[-1] if samples else info
        time.sleep(0.01)
    assert info.gid.data == ctx.participant.get_guid().bytes
    entry = next(n for n in info.node_entities_info_seq if n.node_name == 'mw_graph_node')
    assert entry.node_namespace == '/'
    assert pub._writer.get_guid().bytes in [g.data for g in entry.writer_gid_seq]
    assert sub._reader.get_guid().bytes in [g.data for g in entry.reader_gid_seq]
    assert ctx.participant.get_qos()[Policy.Userdata].data == b'enclave=/;'
    node.destroy_node()


def test_backend_selection(monkeypatch):
    from frf_ident import middleware
    monkeypatch.setenv('FRF_IDENT_MIDDLEWARE', 'dds')
    assert middleware._select_backend().BACKEND_NAME == 'dds'
    monkeypatch.setenv('FRF_IDENT_MIDDLEWARE', 'zenoh')
    with pytest.raises(ValueError, match='FRF_IDENT_MIDDLEWARE'):
        middleware._select_backend()
    try:
        import rclpy  # noqa: F401
    except ImportError:
        monkeypatch.setenv('FRF_IDENT_MIDDLEWARE', 'rclpy')
        with pytest.raises(ImportError, match='rclpy'):
            middleware._select_backend()
        monkeypatch.delenv('FRF_IDENT_MIDDLEWARE')
        assert middleware._select_backend().BACKEND_NAME == 'dds'


def test_msg_and_srv_lookup():
    JointState = mw.msg('sensor_msgs/msg/JointState')
    assert JointState(name=['a']).name == ['a']
    assert mw.srv('std_srvs/srv/Trigger').Response(success=True).success
    with pytest.raises(KeyError, match='geometry_msgs'):
        mw.msg('geometry_msgs/msg/Twist')


def _xml_items(text: str) -> list:
    root = ET.fromstring(text)
    return sorted((el.tag, (el.text or '').strip(), sorted(el.attrib.items()))
                  for el in root.iter())


def test_localhost_config_equals_shipped_xml():
    from frf_ident.middleware.dds_context import LOCALHOST_CONFIG
    shipped = Path(__file__).resolve().parents[2] / 'config' / 'cyclonedds-localhost.xml'
    assert _xml_items(LOCALHOST_CONFIG) == _xml_items(shipped.read_text())


GUARDED_CHILD = """
import os
from frf_ident.middleware import dds_context as dds
real_domain, real_participant, made = dds.Domain, dds.DomainParticipant, []
def domain(domain_id, config):
    made.append(config)
    return real_domain(domain_id, config)
def participant(*args, **kwargs):
    # refuse to touch the network unless the loopback config was installed first
    assert made == [dds.LOCALHOST_CONFIG], 'loopback config not enforced'
    return real_participant(*args, **kwargs)
dds.Domain, dds.DomainParticipant = domain, participant
assert 'CYCLONEDDS_URI' not in os.environ
from frf_ident import middleware as mw
node = mw.create_node('mw_uri_unset')
pub = node.create_publisher(mw.msg('std_msgs/msg/String'), '/frf/loopback_check', 10)
import time
deadline = time.monotonic() + 10
while pub.get_subscription_count() == 0:
    assert time.monotonic() < deadline, 'peer not discovered'
    time.sleep(0.01)
print('discovered', flush=True)
mw.shutdown()
"""


def test_localhost_enforced_without_cyclonedds_uri(domain_env):
    node = mw.create_node('mw_uri_peer')
    node.create_subscription(mw.msg('std_msgs/msg/String'), '/frf/loopback_check',
                             lambda m: None, 10)
    env = {k: v for k, v in domain_env.items() if k != 'CYCLONEDDS_URI'}
    out = subprocess.run([sys.executable, '-c', GUARDED_CHILD], env=env, capture_output=True,
                         text=True, timeout=30)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == 'discovered'
    node.destroy_node()
