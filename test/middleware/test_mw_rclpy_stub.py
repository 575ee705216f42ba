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
The rclpy backend's own logic against a minimal stand-in of the rclpy API (no ROS here).

This checks argument translation only; real rclpy behaviour is not exercised on this machine.
"""

import enum
import importlib
import sys
import types

import pytest


class _Recorder:
    def __init__(self, name, *, namespace=None, parameter_overrides=None, **kwargs):
        self.name, self.namespace = name, namespace
        self.overrides = {p.name: p.value for p in parameter_overrides or []}
        self.calls = []
        # rclpy's Node.__init__ creates /parameter_events with a native QoSProfile
        self.create_publisher('ParameterEvent', '/parameter_events', _QoSProfile(depth=1000))

    def create_publisher(self, msg_type, topic, qos, **kwargs):
        self.calls.append(('pub', topic, qos, kwargs))

    def create_subscription(self, msg_type, topic, callback, qos, **kwargs):
        self.calls.append(('sub', topic, qos, kwargs))

    def create_client(self, srv_type, name, **kwargs):
        self.calls.append(('client', name, kwargs))
        return types.SimpleNamespace(srv_type=srv_type, service_name=name)

    def declare_parameter(self, name, value, descriptor, ignore_override):
        self.calls.append(('param', name, value, descriptor))
        return types.SimpleNamespace(value=self.overrides.get(name, value))


class _QoSProfile:
    def __init__(self, **kwargs):
        self.__dict__.update(kwargs)


@pytest.fixture
def rclpy_backend(monkeypatch):
    Policy = enum.Enum('Policy', 'KEEP_LAST RELIABLE BEST_EFFORT VOLATILE TRANSIENT_LOCAL')
    fake = {
        'rclpy': types.ModuleType('rclpy'),
        'rclpy.node': types.SimpleNamespace(Node=_Recorder),
        'rclpy.qos': types.SimpleNamespace(
            QoSProfile=_QoSProfile, HistoryPolicy=Policy, ReliabilityPolicy=Policy,
            DurabilityPolicy=Policy, qos_profile_services_default=_QoSProfile(depth=10)),
        # caller-aware services (middleware/caller.py): not exercised by this stand-in
        'rclpy.impl': types.ModuleType('rclpy.impl'),
        'rclpy.impl.implementation_singleton': types.SimpleNamespace(
            rclpy_implementation=types.SimpleNamespace(Service=object)),
        'rclpy.service': types.SimpleNamespace(Service=object),
        'rclpy.type_support': types.SimpleNamespace(check_is_valid_srv_type=lambda t: None),
        'rclpy.parameter': types.SimpleNamespace(
            Parameter=lambda name, value=None: types.SimpleNamespace(name=name, value=value)),
        'rclpy.callback_groups': types.SimpleNamespace(ReentrantCallbackGroup=object),
        'rclpy.executors': types.SimpleNamespace(SingleThreadedExecutor=object),
        'rclpy.exceptions': types.SimpleNamespace(
            ParameterException=type('PE', (Exception,), {}),
            InvalidParameterTypeException=type('IPTE', (Exception,), {}),
            InvalidParameterValueException=type('IPVE', (Exception,), {})),
        'rcl_interfaces': types.ModuleType('rcl_interfaces'),
        'rcl_interfaces.msg': types.SimpleNamespace(
            ParameterDescriptor=lambda **kw: ('descriptor', kw)),
    }
    for name, module in fake.items():
        monkeypatch.setitem(sys.modules, name, module)
    monkeypatch.delitem(sys.modules, 'frf_ident.middleware.rclpy_backend', raising=False)
    module = importlib.import_module('frf_ident.middleware.rclpy_backend')
    yield module, Policy
    sys.modules.pop('frf_ident.middleware.rclpy_backend', None)


def test_rclpy_node_translation(rclpy_backend):
    from frf_ident import middleware as mw
    backend, Policy = rclpy_backend
    node = backend.Node('n', parameter_overrides={'rate_hz': 5.0}, use_sim_time=True)
    assert node.overrides == {'rate_hz': 5.0, 'use_sim_time': True}
    node.create_publisher('String', '/frf/experiment', mw.qos_transient_local())
    node.create_subscription('Clock', '/clock', print, mw.qos_clock())
    node.create_subscription('JointState', '/joint_states', print, 7)
    _, topic, qos, _ = node.calls[1]
    assert (qos.depth, qos.reliability, qos.durability) == (1, Policy.RELIABLE,
                                                            Policy.TRANSIENT_LOCAL)
    assert node.calls[2][2].reliability == Policy.BEST_EFFORT
    assert (node.calls[3][2].depth, node.calls[3][2].reliability) == (7, Policy.RELIABLE)
    assert node.calls[0][2].depth == 1000  # native profile passed through
    assert node.declare_parameter('joints', []).value == []
    # read once at start-up: read-only, so a runtime set fails instead of doing nothing
    assert node.calls[-1][3] == ('descriptor', {'read_only': True, 'dynamic_typing': True})
    assert node.declare_parameter('rate_hz', 1.0).value == 5.0
    assert node.calls[-1][3] == ('descriptor', {'read_only': True, 'dynamic_typing': False})
    client = node.create_client('Trigger', '/frf/run_iteration')
    assert node.calls[-1][2]['callback_group'] is node._client_group
    assert client.service_name == '/frf/run_iteration' and not node.is_spinning()
    with pytest.raises(ValueError, match='pkg/msg/Type'):
        backend.msg('std_msgs/String')
