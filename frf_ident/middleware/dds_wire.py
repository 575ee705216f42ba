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
DDS plumbing shared by the Cyclone DDS backend's entities: ROS names, QoS and USER_DATA.

rmw_cyclonedds_cpp conventions (listed in :mod:`frf_ident.middleware.dds_backend`): explicit
QoS with XCDR1, ``typehash=`` / ``serviceid=`` / ``clientid=`` USER_DATA, fully qualified ROS
names.
"""

from typing import Any, Optional
import uuid

from cyclonedds.core import InstanceState, Policy, Qos, SampleState, ViewState
from cyclonedds.util import duration
from frf_ident.middleware import ros_types
from frf_ident.middleware.qos import QosSpec

__all__ = ['ANY_SAMPLE', 'TAKE_BATCH', 'dds_qos', 'delete_entity', 'format_user_data', 'gid',
           'new_endpoint_id', 'parse_user_data', 'resolve_name']


ANY_SAMPLE = SampleState.Any | ViewState.Any | InstanceState.Any
TAKE_BATCH = 256


def format_user_data(**items: str) -> bytes:
    return ''.join(f'{k}={v};' for k, v in items.items()).encode()


def parse_user_data(qos: Optional[Qos]) -> dict[str, str]:
    if qos is None or Policy.Userdata not in qos:
        return {}
    text = qos[Policy.Userdata].data.decode('utf-8', errors='replace')
    out = {}
    for item in text.split(';'):
        key, sep, value = item.partition('=')
        if sep:
            out[key.strip()] = value
    return out


def dds_qos(spec: QosSpec, user_data: bytes, writer: bool) -> Qos:
    policies = [
        Policy.History.KeepLast(spec.depth),
        Policy.Reliability.Reliable(duration(seconds=1)) if spec.reliable
        else Policy.Reliability.BestEffort,
        Policy.Durability.TransientLocal if spec.transient_local else Policy.Durability.Volatile,
        Policy.DataRepresentation(use_cdrv0_representation=True),
        Policy.Userdata(user_data),
    ]
    if writer:
        policies.append(Policy.WriterDataLifecycle(autodispose=False))
    return Qos(*policies)


def delete_entity(entity: Any) -> None:
    """Delete a DDS entity now instead of at garbage collection (idempotent)."""
    entity.__del__()


def gid(entity: Any) -> ros_types.Gid:
    return ros_types.Gid(data=entity.get_guid().bytes)


def new_endpoint_id() -> str:
    """Return a unique dotted-hex id for serviceid=/clientid= USER_DATA (compared for equality)."""
    return '.'.join(f'{b:x}' for b in uuid.uuid4().bytes)


def resolve_name(name: str, node_name: str, namespace: str = '/') -> str:
    """Fully qualified ROS name: ``~/x`` -> ``/<ns>/<node>/x``, ``x`` -> ``/<ns>/x``."""
    if not name or name.endswith('/') and name != '/':
        raise ValueError(f'invalid ROS topic or service name {name=}')
    ns = '/' + namespace.strip('/')
    base = ns.rstrip('/')
    if name.startswith('~'):
        return f'{base}/{node_name}{name[1:]}'
    if name.startswith('/'):
        return name
    return f'{base}/{name}'
