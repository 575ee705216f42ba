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
The process's DDS participant (one per process, as rmw since Foxy), shared by all nodes.

:func:`init`, :func:`ok`, :func:`shutdown` and :func:`get_context` manage it; the context
publishes ``ros_discovery_info`` (which readers and writers belong to which node) and counts
a topic's publishers from the discovery data. ``ROS_DOMAIN_ID`` and the discovery range are read
as rcl reads them; a localhost-only range without ``CYCLONEDDS_URI`` installs
:data:`LOCALHOST_CONFIG`.
"""

import os
import sys
import threading
from typing import Any, Optional, Sequence

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from frf_ident.middleware import ros_types
from frf_ident.middleware.dds_caller import CallerLookup, GRAPH_DEPTH
from frf_ident.middleware.dds_wire import (dds_qos, delete_entity, format_user_data, gid)
from frf_ident.middleware.qos import qos_transient_local

__all__ = ['LOCALHOST_CONFIG', 'domain_id_from_env', 'get_context', 'init', 'localhost_only',
           'ok', 'shutdown']


#: Loopback-only configuration, equivalent to config/cyclonedds-localhost.xml (``lo`` may lack
#: the MULTICAST flag, so discovery is unicast to 127.0.0.1 with participant indices).
LOCALHOST_CONFIG = """<CycloneDDS xmlns="https://cdds.io/config"><Domain Id="any">
<General><Interfaces><NetworkInterface name="lo"/></Interfaces>
<AllowMulticast>false</AllowMulticast></General>
<Discovery><ParticipantIndex>auto</ParticipantIndex>
<MaxAutoParticipantIndex>32</MaxAutoParticipantIndex>
<Peers><Peer address="127.0.0.1"/></Peers></Discovery>
</Domain></CycloneDDS>"""


def domain_id_from_env() -> int:
    """``ROS_DOMAIN_ID`` as rcl reads it (unset or empty -> 0)."""
    text = os.environ.get('ROS_DOMAIN_ID', '').strip()
    if not text:
        return 0
    try:
        value = int(text)
    except ValueError:
        raise ValueError(f'ROS_DOMAIN_ID must be an integer, got {text=}') from None
    if not 0 <= value <= 232:
        raise ValueError(f'ROS_DOMAIN_ID must be in 0..232, got {value=}')
    return value


def localhost_only() -> bool:
    """Return true when ROS 2 Jazzy would restrict discovery to this host."""
    rng = os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE', '').strip().upper()
    if rng:
        return rng == 'LOCALHOST'
    return os.environ.get('ROS_LOCALHOST_ONLY', '').strip() == '1'


class _Context:
    """One DomainParticipant per process (as rmw since Foxy), shared by all nodes."""

    def __init__(self, args: Sequence[str]) -> None:
        self.args = list(args)
        self.lock = threading.RLock()
        self.nodes: list[Any] = []  # dds_node.Node (it imports this module)
        self.domain_id = domain_id_from_env()
        self._domain = (Domain(self.domain_id, LOCALHOST_CONFIG)
                        if localhost_only() and not os.environ.get('CYCLONEDDS_URI') else None)
        self.participant = DomainParticipant(
            self.domain_id, qos=Qos(Policy.Userdata(format_user_data(enclave='/'))))
        self._topics: dict[tuple[str, type], Topic] = {}
        self._pub_reader: Any = None
        self._callers: Any = None
        self._graph_writer = DataWriter(
            self.participant,
            self.topic('ros_discovery_info', ros_types.ParticipantEntitiesInfo),
            dds_qos(qos_transient_local(1), format_user_data(typehash=ros_types.TYPE_HASHES[
                'rmw_dds_common/msg/ParticipantEntitiesInfo']), writer=True))

    def topic(self, dds_name: str, data_type: type) -> Topic:
        with self.lock:
            key = (dds_name, data_type)
            if key not in self._topics:
                self._topics[key] = Topic(self.participant, dds_name, data_type)
            return self._topics[key]

    def publish_graph(self) -> None:
        """Publish ros_discovery_info: which readers and writers belong to which node."""
        with self.lock:
            infos = [ros_types.NodeEntitiesInfo(
                node_namespace=n.get_namespace(), node_name=n.get_name(),
                reader_gid_seq=[gid(r) for r in n._graph_readers()],
                writer_gid_seq=[gid(w) for w in n._graph_writers()]) for n in self.nodes]
            self._graph_writer.write(ros_types.ParticipantEntitiesInfo(
                gid=gid(self.participant), node_entities_info_seq=infos))

    def caller_lookup(self) -> Any:
        """Return the lookup naming a request's caller (its readers created on first use)."""
        with self.lock:
            if self._callers is None:
                self._callers = CallerLookup(
                    self.participant,
                    self.topic('ros_discovery_info', ros_types.ParticipantEntitiesInfo),
                    dds_qos(qos_transient_local(GRAPH_DEPTH), format_user_data(
                        typehash=ros_types.TYPE_HASHES[
                            'rmw_dds_common/msg/ParticipantEntitiesInfo']), writer=False))
            return self._callers

    def count_publishers(self, topic_name: str) -> int:
        """Alive DDS writers on ROS topic ``topic_name`` in the domain (discovery data)."""
        from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication
        from cyclonedds.core import InstanceState
        with self.lock:
            if self._pub_reader is None:
                self._pub_reader = BuiltinDataReader(self.participant,
                                                     BuiltinTopicDcpsPublication)
            samples = self._pub_reader.read(N=100000)
        alive = {}
        for smp in samples:
            if smp.topic_name == 'rt' + topic_name:
                alive[smp.key] = smp.sample_info.instance_state == InstanceState.Alive
        return sum(alive.values())

    def close(self) -> None:
        for node in list(self.nodes):
            node.destroy_node()
        delete_entity(self._graph_writer)
        if self._callers is not None:
            self._callers.close(delete_entity)
        if self._pub_reader is not None:
            delete_entity(self._pub_reader)
        delete_entity(self.participant)
        if self._domain is not None:
            delete_entity(self._domain)


_context: Optional[_Context] = None
_context_lock = threading.Lock()


def init(args: Optional[Sequence[str]] = None) -> None:
    """Create the process's DDS participant; ``args`` (default ``sys.argv``) may hold ROS args."""
    global _context
    with _context_lock:
        if _context is None:
            _context = _Context(sys.argv if args is None else args)


def ok() -> bool:
    """Return true between :func:`init` and :func:`shutdown`."""
    return _context is not None


def shutdown() -> None:
    """Destroy all nodes and the participant (no-op if not initialised)."""
    global _context
    with _context_lock:
        if _context is not None:
            _context.close()
            _context = None


def get_context() -> _Context:
    init()
    assert _context is not None
    return _context
