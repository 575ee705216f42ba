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
Who called a service: what each middleware tells about the client behind a request.

``node.create_service(T, name, callback, caller=True)`` calls ``callback(request, response,
caller)`` with a :class:`Caller`. What it holds depends on the backend (docs/ros2.md, "Who
asked"):

- rclpy: the request's sequence number and source timestamp (the client's clock) from the
  rmw service info; rclpy does not expose the request writer's GID, so the caller's node is
  known only when one node has a client on the service (``candidates`` lists them all, from
  the ROS graph at the moment of the request).
- DDS backend: the request writer's DDS GUID and its participant, the node that owns the
  writer (from the caller's ``ros_discovery_info``, as ``ros2 node info`` finds it), the
  participant's SROS2 enclave (USER_DATA ``enclave=``) and what Cyclone DDS announces of the
  process (host name, process name and id, network addresses). These are the caller's own
  statements: informative, not proof (SROS2 authenticates, docs/ros2.md).
"""
from __future__ import annotations

from dataclasses import dataclass
import datetime
from typing import Optional

__all__ = ['Caller', 'wall_time_text']


def wall_time_text(ns: int) -> str:
    """
    Format a wall-clock time for a log line: local ISO 8601 with milliseconds and offset.

    Parameters
    ----------
    ns : int
        Nanoseconds since the epoch.

    Returns
    -------
    str
        For example ``2026-03-01T14:03:07.412+01:00``.

    Examples
    --------
    >>> wall_time_text(0).count(':') >= 2
    True

    """
    t = datetime.datetime.fromtimestamp(ns * 1e-9).astimezone()
    return t.isoformat(timespec='milliseconds')


@dataclass(frozen=True)
class Caller:
    """
    The client behind one service request, as far as the middleware tells.

    Parameters
    ----------
    backend : str
        'rclpy' or 'dds'.
    service : str
        Fully qualified service name.
    sequence : int
        The client's sequence number of this request.
    received_ns : int
        Wall clock of this process when the request was taken [ns since the epoch].
    sent_ns : int or None
        Source timestamp of the request (the caller's clock), None when unknown.
    node : str or None
        ``/namespace/name`` of the caller's node when known.
    candidates : tuple of str
        rclpy: every node with a client on the service when the request came.
    writer : str or None
        DDS GUID of the request writer (DDS backend).
    participant : str or None
        DDS GUID of the caller's participant (DDS backend).
    enclave : str or None
        The participant's SROS2 enclave, from its USER_DATA (DDS backend).
    host : str or None
        The host name the caller's Cyclone DDS announces (DDS backend).
    process : str or None
        Its process name and id (DDS backend).
    addresses : str or None
        Its network addresses (DDS backend).

    """

    backend: str
    service: str
    sequence: int
    received_ns: int
    sent_ns: Optional[int] = None
    node: Optional[str] = None
    candidates: tuple[str, ...] = ()
    writer: Optional[str] = None
    participant: Optional[str] = None
    enclave: Optional[str] = None
    host: Optional[str] = None
    process: Optional[str] = None
    addresses: Optional[str] = None

    def describe(self) -> str:
        """
        Return one line saying who called, for the log and the refusal.

        Returns
        -------
        str
            The node (or the candidate nodes), what else the middleware knows, the sequence
            number and the send time.

        Examples
        --------
        >>> Caller('dds', '/frf/run_multisine', 3, 0, node='/operator', host='robot-pc',
        ...        enclave='/frf_ident/operator').describe().split(',')[0]
        'node /operator on robot-pc'

        """
        parts = [self._who()]
        if self.enclave is not None:
            parts.append(f'enclave {self.enclave}')
        if self.process is not None:
            parts.append(f'process {self.process}')
        if self.addresses is not None:
            parts.append(f'at {self.addresses}')
        if self.writer is not None:
            parts.append(f'request writer {self.writer}')
        sent = f' sent {wall_time_text(self.sent_ns)}' if self.sent_ns else ''
        parts.append(f'request #{self.sequence}{sent}')
        return ', '.join(parts)

    def _who(self) -> str:
        host = f' on {self.host}' if self.host else ''
        if self.backend == 'rclpy' and self.node is not None:
            return (f'node {self.node} (the only client of {self.service}; rclpy tells no '
                    'request GID)')
        if self.node is not None:
            return f'node {self.node}{host}'
        if self.backend == 'rclpy':
            listed = ', '.join(self.candidates) or 'none listed yet'
            return (f'one of the clients of {self.service}: {listed} (rclpy tells no '
                    'request GID)')
        return f'an unnamed participant{host} (no ros_discovery_info names its writer)'
