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
"""Wire format of the DDS backend against rosbags (the ROS 2 Jazzy CDR reference) and rmw."""

import dataclasses

from frf_ident.middleware import ros_types as rt
from frf_ident.middleware.dds_wire import resolve_name
import numpy as np
import pytest
from rosbags.typesys import get_types_from_msg, get_typestore, Stores

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
TYPESTORE.register(get_types_from_msg('bool success\nstring message',
                                      'std_srvs/msg/Trigger_Response'))

_NUMPY = {'float64': np.float64, 'uint8': np.uint8, 'char': np.uint8}


def to_rosbags(value, ros_type: str):
    """Convert a DDS-backend message to the rosbags object of ``ros_type`` (recursively)."""
    cls = TYPESTORE.types[ros_type]
    _, fields = TYPESTORE.fielddefs[ros_type]
    kwargs = {}
    for name, (kind, spec) in fields:
        v = getattr(value, name)
        if kind.name == 'NAME':
            kwargs[name] = to_rosbags(v, spec)
        elif kind.name in ('SEQUENCE', 'ARRAY'):
            (inner_kind, inner), _ = spec
            if inner_kind.name == 'NAME':
                kwargs[name] = [to_rosbags(x, inner) for x in v]
            elif inner[0] in _NUMPY:
                kwargs[name] = np.array(list(v), dtype=_NUMPY[inner[0]])
            else:
                kwargs[name] = list(v)
        else:
            kwargs[name] = v
    return cls(**kwargs)


T = rt.Time(sec=1_700_000_123, nanosec=987_654_321)
H = rt.Header(stamp=T, frame_id='base_link')
LAYOUT = rt.MultiArrayLayout(dim=[rt.MultiArrayDimension(label='joints', size=3, stride=3),
                                  rt.MultiArrayDimension(label='x', size=1, stride=1)],
                             data_offset=7)
SAMPLES = {
    'builtin_interfaces/msg/Time': T,
    'std_msgs/msg/Header': H,
    'std_msgs/msg/String': rt.String(data='{"design": "multisine", "ü": 1}'),
    'std_msgs/msg/MultiArrayDimension': rt.MultiArrayDimension(label='abc', size=4, stride=9),
    'std_msgs/msg/MultiArrayLayout': LAYOUT,
    'std_msgs/msg/Float64MultiArray': rt.Float64MultiArray(layout=LAYOUT,
                                                           data=[1.0, -2.5, 1e-300, np.pi]),
    'sensor_msgs/msg/JointState': rt.JointState(
        header=H, name=['joint1', 'j2', 'a_long_joint_name'], position=[0.1, 0.2, 0.3],
        velocity=[-1.0, 0.0, 1.0], effort=[5.5, float('inf'), -0.0]),
    'rosgraph_msgs/msg/Clock': rt.Clock(clock=T),
    'rmw_dds_common/msg/Gid': rt.Gid(data=bytes(range(16))),
    'rmw_dds_common/msg/NodeEntitiesInfo': rt.NodeEntitiesInfo(
        node_namespace='/', node_name='frf_excitation',
        reader_gid_seq=[rt.Gid(data=b'\x01' * 16)],
        writer_gid_seq=[rt.Gid(), rt.Gid(data=b'\xff' * 16)]),
    'rmw_dds_common/msg/ParticipantEntitiesInfo': rt.ParticipantEntitiesInfo(
        gid=rt.Gid(data=bytes(range(16, 32))), node_entities_info_seq=[rt.NodeEntitiesInfo(
            node_namespace='/', node_name='a', reader_gid_seq=[], writer_gid_seq=[rt.Gid()])]),
}


def test_every_registered_type_has_a_sample():
    assert set(SAMPLES) == set(rt.MESSAGES)


@pytest.mark.parametrize('ros_type', sorted(SAMPLES))
def test_payload_equals_rosbags_cdr(ros_type):
    value = SAMPLES[ros_type]
    assert isinstance(value, rt.MESSAGES[ros_type])
    ours = value.serialize()
    reference = bytes(TYPESTORE.serialize_cdr(to_rosbags(value, ros_type), ros_type))
    assert ours[:4] == b'\x00\x01\x00\x00'  # XCDR1 (CDR_LE), as rmw_cyclonedds writes
    assert ours == reference
    assert type(value).deserialize(reference) == value


@pytest.mark.parametrize('ros_type', sorted(rt.MESSAGES))
def test_dds_type_names_and_hashes(ros_type):
    pkg, kind, name = ros_type.split('/')
    assert rt.MESSAGES[ros_type].__idl_typename__ == f'{pkg}::{kind}::dds_::{name}_'
    assert rt.TYPE_HASHES[ros_type] == TYPESTORE.hash_rihs01(ros_type)
    assert rt.ros_type_name(rt.MESSAGES[ros_type]) == ros_type


@pytest.mark.parametrize('cls', list(rt.MESSAGES.values()) + [
    rt.Trigger.RequestWire, rt.Trigger.ResponseWire])
def test_structs_are_final_and_default_to_xcdr1(cls):
    cls.__idl__.populate()
    assert cls.__idl__.default_version == 1, cls  # final, non-optional: plain CDR
    assert getattr(cls, '__idl_annotations__', {}).get('extensibility', 'final') == 'final'


@pytest.mark.parametrize('name, dds_topic', [
    ('/joint_states', 'rt/joint_states'), ('joint_states', 'rt/joint_states'),
    ('~/commands', 'rt/frf_excitation/commands'),
    ('/effort_controller/commands', 'rt/effort_controller/commands')])
def test_topic_name_mangling(name, dds_topic):
    assert 'rt' + resolve_name(name, 'frf_excitation') == dds_topic


def test_namespaced_names():
    assert resolve_name('x', 'n', '/robot') == '/robot/x'
    assert resolve_name('~/x', 'n', '/robot') == '/robot/n/x'
    with pytest.raises(ValueError, match='name'):
        resolve_name('', 'n')


def test_trigger_request_framing():
    wire = rt.Trigger.RequestWire(client_guid=0x0123456789ABCDEF, sequence_number=7,
                                  body=rt.Trigger.Request())
    data = wire.serialize()
    assert data == (b'\x00\x01\x00\x00' + (0x0123456789ABCDEF).to_bytes(8, 'little')
                    + (7).to_bytes(8, 'little', signed=True) + b'\x00')
    assert rt.Trigger.RequestWire.__idl_typename__ == 'std_srvs::srv::dds_::Trigger_Request_'
    assert rt.Trigger.RequestWire.deserialize(data + b'\x00\x00\x00') == wire  # rmw pads to 4


def test_trigger_reply_framing_matches_doc_example():
    wire = rt.Trigger.ResponseWire(client_guid=2**64 - 1, sequence_number=1,
                                   body=rt.Trigger.Response(success=True,
                                                            message='iteration 1 done'))
    data = wire.serialize()
    header, body = data[4:20], data[20:]
    assert data[:4] == b'\x00\x01\x00\x00'
    assert header == b'\xff' * 8 + (1).to_bytes(8, 'little')
    assert body == bytes.fromhex('01000000' '11000000') + b'iteration 1 done\x00'
    assert rt.Trigger.ResponseWire.__idl_typename__ == 'std_srvs::srv::dds_::Trigger_Response_'
    # the body after the 16-byte header is exactly rosbags' CDR of the ROS response
    reference = bytes(TYPESTORE.serialize_cdr(
        TYPESTORE.types['std_srvs/msg/Trigger_Response'](success=True,
                                                         message='iteration 1 done'),
        'std_srvs/msg/Trigger_Response'))
    assert data[:4] + body == reference


def test_numpy_arrays_are_accepted():
    js = rt.JointState(name=('a', 'b'), position=np.array([1.0, 2.0]), velocity=np.zeros(2),
                       effort=np.arange(2.0))
    assert rt.JointState.deserialize(js.serialize()).position == [1.0, 2.0]
    cmd = rt.Float64MultiArray(data=np.array([0.5, -0.5]))
    assert rt.Float64MultiArray.deserialize(cmd.serialize()).data == [0.5, -0.5]


def test_messages_construct_with_ros_keywords_and_defaults():
    js = rt.JointState()
    assert js.header.stamp.sec == 0 and js.name == [] and js.effort == []
    assert rt.Float64MultiArray().layout.dim == []
    assert dataclasses.fields(rt.JointState)[0].name == 'header'
    response = rt.Trigger.Response(success=True, message='x')
    assert (response.success, response.message) == (True, 'x')
