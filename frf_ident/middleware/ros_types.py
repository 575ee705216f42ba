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
ROS 2 message and service types as Cyclone DDS IDL structs (ROS2_CONVENTIONS.md section 1).

Every struct is *final* with non-optional members, so Cyclone serializes it as XCDR1, the
encoding rmw_cyclonedds_cpp uses; the bytes equal rosbags' ``serialize_cdr`` (checked in
test/middleware/test_wire.py). DDS type names are mangled as rosidl does for DDS
(``pkg::msg::dds_::Type_``), nested types included. Field names and order are the ROS ones, so
node code constructs and reads them exactly like rclpy messages (keyword arguments only).
"""

from dataclasses import dataclass, field
from typing import Any

from cyclonedds.idl import IdlStruct, make_idl_struct
import cyclonedds.idl.types as t


def _as_list(value: Any) -> list:
    """Sequences as lists: Cyclone's serializer tests ``if value:``, which numpy arrays refuse."""
    if isinstance(value, list):
        return value
    return value.tolist() if hasattr(value, 'tolist') else list(value)


def _dds_name(ros_type: str) -> str:
    """``pkg/msg/Type`` -> ``pkg::msg::dds_::Type_`` (rosidl_typesupport / rmw_cyclonedds)."""
    pkg, kind, name = ros_type.split('/')
    return f'{pkg}::{kind}::dds_::{name}_'


@dataclass
class Time(IdlStruct, typename=_dds_name('builtin_interfaces/msg/Time')):
    sec: t.int32 = 0
    nanosec: t.uint32 = 0


@dataclass
class Header(IdlStruct, typename=_dds_name('std_msgs/msg/Header')):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ''


@dataclass
class String(IdlStruct, typename=_dds_name('std_msgs/msg/String')):
    data: str = ''


@dataclass
class MultiArrayDimension(IdlStruct, typename=_dds_name('std_msgs/msg/MultiArrayDimension')):
    label: str = ''
    size: t.uint32 = 0
    stride: t.uint32 = 0


@dataclass
class MultiArrayLayout(IdlStruct, typename=_dds_name('std_msgs/msg/MultiArrayLayout')):
    dim: t.sequence[MultiArrayDimension] = field(default_factory=list)
    data_offset: t.uint32 = 0


@dataclass
class Float64MultiArray(IdlStruct, typename=_dds_name('std_msgs/msg/Float64MultiArray')):
    layout: MultiArrayLayout = field(default_factory=MultiArrayLayout)
    data: t.sequence[t.float64] = field(default_factory=list)

    def __post_init__(self) -> None:  # accept numpy arrays and tuples like rclpy does
        self.data = _as_list(self.data)


@dataclass
class JointState(IdlStruct, typename=_dds_name('sensor_msgs/msg/JointState')):
    header: Header = field(default_factory=Header)
    name: t.sequence[str] = field(default_factory=list)
    position: t.sequence[t.float64] = field(default_factory=list)
    velocity: t.sequence[t.float64] = field(default_factory=list)
    effort: t.sequence[t.float64] = field(default_factory=list)

    def __post_init__(self) -> None:  # accept numpy arrays and tuples like rclpy does
        self.name = _as_list(self.name)
        self.position = _as_list(self.position)
        self.velocity = _as_list(self.velocity)
        self.effort = _as_list(self.effort)


@dataclass
class Clock(IdlStruct, typename=_dds_name('rosgraph_msgs/msg/Clock')):
    clock: Time = field(default_factory=Time)


# rmw_dds_common (Jazzy): the ros_discovery_info topic that gives `ros2 node list` its names.
@dataclass
class Gid(IdlStruct, typename=_dds_name('rmw_dds_common/msg/Gid')):
    data: t.array[t.uint8, 16] = bytes(16)


@dataclass
class NodeEntitiesInfo(IdlStruct, typename=_dds_name('rmw_dds_common/msg/NodeEntitiesInfo')):
    node_namespace: t.bounded_str[256] = ''
    node_name: t.bounded_str[256] = ''
    reader_gid_seq: t.sequence[Gid] = field(default_factory=list)
    writer_gid_seq: t.sequence[Gid] = field(default_factory=list)


@dataclass
class ParticipantEntitiesInfo(IdlStruct,
                              typename=_dds_name('rmw_dds_common/msg/ParticipantEntitiesInfo')):
    gid: Gid = field(default_factory=Gid)
    node_entities_info_seq: t.sequence[NodeEntitiesInfo] = field(default_factory=list)


# Service bodies. Their own type names never reach the wire: rmw_cyclonedds sends each request
# and reply as one struct `{uint64 guid; int64 seq; <body members>}` under the name
# `pkg::srv::dds_::Srv_Request_` / `_Response_` (see ServiceType below).
@dataclass
class TriggerRequest(IdlStruct, typename='std_srvs::srv::Trigger_Request'):
    structure_needs_at_least_one_member: t.uint8 = 0


@dataclass
class TriggerResponse(IdlStruct, typename='std_srvs::srv::Trigger_Response'):
    success: bool = False
    message: str = ''


class ServiceType:
    """
    A ROS service type: ``.Request`` / ``.Response`` body classes plus their wire wrappers.

    The wire structs prepend rmw_cyclonedds' request header (``client_guid: uint64``,
    ``sequence_number: int64``; ROS2_CONVENTIONS.md section 1.2). Nesting the body struct keeps
    XCDR1 bytes identical to the flat layout, since the header is 16 bytes (body 8-aligned).
    """

    def __init__(self, ros_type: str, request: type, response: type) -> None:
        pkg, kind, name = ros_type.split('/')
        if kind != 'srv':
            raise ValueError(f'not a service type: {ros_type=}')
        self.ros_type = ros_type
        self.Request = request
        self.Response = response
        self.RequestWire = make_idl_struct(
            f'{name}RequestWire', f'{pkg}::srv::dds_::{name}_Request_',
            {'client_guid': t.uint64, 'sequence_number': t.int64, 'body': request})
        self.ResponseWire = make_idl_struct(
            f'{name}ResponseWire', f'{pkg}::srv::dds_::{name}_Response_',
            {'client_guid': t.uint64, 'sequence_number': t.int64, 'body': response})

    def __repr__(self) -> str:
        return f'ServiceType({self.ros_type!r})'


Trigger = ServiceType('std_srvs/srv/Trigger', TriggerRequest, TriggerResponse)

#: ROS type name -> IDL class, for every message type the project uses.
MESSAGES: dict[str, type] = {
    'builtin_interfaces/msg/Time': Time,
    'std_msgs/msg/Header': Header,
    'std_msgs/msg/String': String,
    'std_msgs/msg/MultiArrayDimension': MultiArrayDimension,
    'std_msgs/msg/MultiArrayLayout': MultiArrayLayout,
    'std_msgs/msg/Float64MultiArray': Float64MultiArray,
    'sensor_msgs/msg/JointState': JointState,
    'rosgraph_msgs/msg/Clock': Clock,
    'rmw_dds_common/msg/Gid': Gid,
    'rmw_dds_common/msg/NodeEntitiesInfo': NodeEntitiesInfo,
    'rmw_dds_common/msg/ParticipantEntitiesInfo': ParticipantEntitiesInfo,
}

SERVICES: dict[str, ServiceType] = {'std_srvs/srv/Trigger': Trigger}

#: REP-2011 type hashes (rosbags ``typestore.hash_rihs01``, Jazzy store; verified in tests).
TYPE_HASHES: dict[str, str] = {
    'builtin_interfaces/msg/Time':
        'RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197',
    'std_msgs/msg/Header':
        'RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01',
    'std_msgs/msg/String':
        'RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18',
    'std_msgs/msg/MultiArrayDimension':
        'RIHS01_5e773a60a4c7fc8a54985f307c7837aa2994252a126c301957a24e31282c9cbe',
    'std_msgs/msg/MultiArrayLayout':
        'RIHS01_4c66e6f78e740ac103a94cf63259f968e48c617e7699e829b63c21a5cb50dac6',
    'std_msgs/msg/Float64MultiArray':
        'RIHS01_1025ddc6b9552d191f89ef1a8d2f60f3d373e28b283d8891ddcc974e8c55397f',
    'sensor_msgs/msg/JointState':
        'RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e',
    'rosgraph_msgs/msg/Clock':
        'RIHS01_692f7a66e93a3c83e71765d033b60349ba68023a8c689a79e48078bcb5c58564',
    'rmw_dds_common/msg/Gid':
        'RIHS01_a8e2f2bd4b156011c7ed7618c1db625ac341c2dc3ff09b8dd107f33f20dcec07',
    'rmw_dds_common/msg/NodeEntitiesInfo':
        'RIHS01_8ecbfcad87fa92b9c1458f525b5faf5bf7cab9427a92524d72a394112992b5ab',
    'rmw_dds_common/msg/ParticipantEntitiesInfo':
        'RIHS01_e725f4a506958c79f95dd693b965722c57b19cd18e7eff984f49561b93dc985d',
}

_ROS_NAME_OF: dict[type, str] = {cls: name for name, cls in MESSAGES.items()}


def ros_type_name(msg_cls: Any) -> str:
    """Return the ROS name (``pkg/msg/Type``) of a message class from this module."""
    try:
        return _ROS_NAME_OF[msg_cls]
    except (KeyError, TypeError):
        raise TypeError(f'not a message class of the DDS backend: {msg_cls=}') from None
