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
DDS backend: who sent a service request, from DDS discovery data.

A request sample names its writer (``sample_info.publication_handle``); the matched
publication gives the writer's GUID, USER_DATA and participant; the participant's built-in
topic gives its USER_DATA (``enclave=``, set by rmw) and the properties Cyclone DDS announces
(``__Hostname``, ``__ProcessName``, ``__Pid``, ``__NetworkAddresses``); ``ros_discovery_info``
(published by every rmw participant, rmw_dds_common's graph) names the node owning the writer.
"""
from __future__ import annotations

import threading
import time
from typing import Any

from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsParticipant
from cyclonedds.sub import DataReader
from frf_ident.middleware import ros_types
from frf_ident.middleware.caller import Caller

__all__ = ['CallerLookup']

#: samples of ros_discovery_info kept between two requests (each participant re-sends its
#: whole table at every change; the newest per participant is what counts)
GRAPH_DEPTH = 1000
#: how long [s] a request waits for the caller's ros_discovery_info (it can follow the
#: request); a participant without rmw (a plain DDS tool) never sends one
GRAPH_WAIT_S = 0.5


def _properties(qos: Any) -> dict[str, str]:
    """Cyclone's announced participant properties and the USER_DATA items, by name."""
    out: dict[str, str] = {}
    for policy in qos or ():
        key = getattr(policy, 'key', None)
        if key is not None:
            out[key] = policy.value
        data = getattr(policy, 'data', None)
        if isinstance(data, bytes):
            for item in data.decode('utf-8', 'replace').split(';'):
                if '=' in item:
                    k, v = item.split('=', 1)
                    out[k.strip()] = v.strip()
    return out


class CallerLookup:
    """
    Names the caller of a request from discovery data (created once per participant).

    Parameters
    ----------
    participant : DomainParticipant
        This process's participant.
    graph_topic : Topic
        The ``ros_discovery_info`` topic of that participant.
    graph_qos : Qos
        Reader QoS of it (reliable, transient-local, depth ``GRAPH_DEPTH``).

    """

    def __init__(self, participant: Any, graph_topic: Any, graph_qos: Any) -> None:
        self._graph = DataReader(participant, graph_topic, graph_qos)
        self._participants = BuiltinDataReader(participant, BuiltinTopicDcpsParticipant)
        self._nodes: dict[bytes, str] = {}      # writer GUID -> '/ns/name'
        self._lock = threading.Lock()

    def _update_graph(self) -> None:
        for info in self._graph.take(N=GRAPH_DEPTH):
            if not isinstance(info, ros_types.ParticipantEntitiesInfo):
                continue        # an invalid sample (a participant left)
            for node in info.node_entities_info_seq:
                ns = node.node_namespace.rstrip('/')
                for gid in node.writer_gid_seq:
                    self._nodes[bytes(gid.data)] = f'{ns}/{node.node_name}'

    def _participant(self, key: Any) -> dict[str, str]:
        for p in self._participants.read(N=100000):
            if getattr(p, 'key', None) == key:
                return _properties(p.qos)
        return {}

    def caller(self, service: str, reader: Any, wire: Any) -> Caller:
        """
        Return what discovery tells about the writer of request ``wire``.

        Parameters
        ----------
        service : str
            The service's name.
        reader : DataReader
            The service's request reader (which matched the writer).
        wire : object
            The request sample as taken (header, body and ``sample_info``).

        Returns
        -------
        Caller
            The caller; fields discovery did not give stay None.

        """
        info = wire.sample_info
        received = time.time_ns()
        endpoint = reader.get_matched_publication_data(info.publication_handle)
        if endpoint is None:
            return Caller('dds', service, int(wire.sequence_number), received,
                          sent_ns=int(info.source_timestamp) or None)
        deadline = time.monotonic() + GRAPH_WAIT_S
        while True:       # the caller's ros_discovery_info can come after its request
            with self._lock:
                self._update_graph()
                node = self._nodes.get(endpoint.key.bytes)
            if node is not None or time.monotonic() > deadline:
                break
            time.sleep(0.01)
        props = self._participant(endpoint.participant_key)
        pid = props.get('__Pid')
        name = props.get('__ProcessName')
        process = f'{name} pid {pid}' if name and pid else None
        return Caller('dds', service, int(wire.sequence_number), received,
                      sent_ns=int(info.source_timestamp) or None, node=node,
                      writer=str(endpoint.key), participant=str(endpoint.participant_key),
                      enclave=props.get('enclave'), host=props.get('__Hostname'),
                      process=process, addresses=props.get('__NetworkAddresses'))

    def close(self, delete: Any) -> None:
        """Delete the readers with the backend's ``delete``."""
        delete(self._graph)
        delete(self._participants)
