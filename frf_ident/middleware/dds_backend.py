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
Cyclone DDS backend: ROS 2 nodes without ROS, wire-compatible with rmw_cyclonedds_cpp.

Conventions (ROS2_CONVENTIONS.md section 1): topics ``rt/<name>``, services ``rq/<name>Request`` /
``rr/<name>Reply`` with the 16-byte (guid, seq) header, mangled type names (ros_types), XCDR1,
explicit writer QoS, ``typehash=`` / ``serviceid=`` / ``clientid=`` USER_DATA, ROS_DOMAIN_ID, and
``ros_discovery_info`` so ``ros2 node list`` shows our nodes.

Threading model (as rclpy's single-threaded executor): subscription, service and timer callbacks
run in whichever thread calls :func:`spin` / :func:`spin_once` for the node. Each node owns one
WaitSet with a ReadCondition per reader, created once, so receiving costs one wake-up, one
``take`` and one deserialization per message. ``Client.call`` waits on a private WaitSet of the
client, so it works from any thread, spun or not, without deadlock.

This module is the backend interface :func:`frf_ident.middleware.backend` returns (the same
names as :mod:`frf_ident.middleware.rclpy_backend`). The pieces: :mod:`.dds_context` (the
process's participant, ``init`` / ``shutdown``), :mod:`.dds_node` (``Node``), :mod:`.dds_topics`
(publishers, subscriptions), :mod:`.dds_service` (services, clients, futures),
:mod:`.dds_time` (clock, timers) and :mod:`.dds_wire` (names, QoS, USER_DATA).
"""

import threading
from typing import Any, Optional

from frf_ident.middleware.dds_context import init, ok, shutdown
from frf_ident.middleware.dds_node import Node

#: the backend interface :func:`frf_ident.middleware.backend` returns (as rclpy_backend)
__all__ = ['BACKEND_NAME', 'PARAMETER_ERRORS', 'create_node', 'init', 'ok', 'shutdown', 'spin',
           'spin_once']

BACKEND_NAME = 'dds'

#: what a node raises for a bad parameter value (this backend converts values as declared)
PARAMETER_ERRORS: tuple = (ValueError, TypeError)


def create_node(name: str, *, namespace: str = '/',
                parameter_overrides: Optional[dict[str, Any]] = None,
                use_sim_time: Optional[bool] = None, global_arguments: bool = True) -> Node:
    return Node(name, namespace=namespace, parameter_overrides=parameter_overrides,
                use_sim_time=use_sim_time, global_arguments=global_arguments)


def spin_once(node: Node, timeout_sec: Optional[float] = None) -> None:
    node.spin_once(timeout_sec)


def spin(node: Node, stop_event: Optional[threading.Event] = None) -> None:
    """Run the node's callbacks until ``stop_event`` is set or the node is destroyed."""
    while not (stop_event is not None and stop_event.is_set()) and not node._destroyed:
        node.spin_once(0.05)
