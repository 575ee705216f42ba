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
Rclpy backend (ROS 2 Jazzy): a thin subclass of rclpy.node.Node.

Only what differs from rclpy is written here: backend-neutral :class:`QosSpec` arguments,
dynamically typed parameters for ``None`` / empty-list defaults, parameter overrides as a dict,
and a client whose ``call`` raises TimeoutError and also works when nobody spins the node.
Everything else (parameters from ``--ros-args``, ``use_sim_time`` and the /clock-driven node
clock and timers, logging) is rclpy's own. This module is imported only when rclpy is.
"""

import importlib
import threading
import time
from typing import Any, Callable, Optional, Sequence

from frf_ident.middleware.caller import Caller
from frf_ident.middleware.qos import as_qos_spec, QosSpec
from rcl_interfaces.msg import ParameterDescriptor
import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.exceptions import (InvalidParameterTypeException, InvalidParameterValueException,
                              ParameterException)
from rclpy.executors import SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy_impl
from rclpy.node import Node as RclpyNode
from rclpy.parameter import Parameter
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, qos_profile_services_default,
                       QoSProfile, ReliabilityPolicy)
from rclpy.service import Service
from rclpy.type_support import check_is_valid_srv_type

BACKEND_NAME = 'rclpy'
#: a draining subscription takes at most this many more messages per wake
DRAIN_BATCH = 64
#: how long [s] a caller-aware service waits for the ROS graph to list the caller's node
#: (its ros_discovery_info can come after its request: a first call of `ros2 service call`
#: found no client listed)
CALLER_GRAPH_WAIT_S = 0.5
#: the part of the name rmw gives a writer whose node's info has not come yet
UNKNOWN_NODE = '_NODE_NAME_UNKNOWN_'
#: what rclpy raises for a parameter value of the wrong type or an invalid one
PARAMETER_ERRORS: tuple = (ParameterException, InvalidParameterTypeException,
                           InvalidParameterValueException)


def to_qos_profile(qos: 'QosSpec | int | QoSProfile') -> QoSProfile:
    """
    Backend-neutral QoS -> rclpy QoSProfile (unset policies keep rmw defaults).

    A QoSProfile passes through unchanged: rclpy's own Node internals (parameter events,
    TimeSource's /clock subscription) call the overridden create_* methods with one.
    """
    if isinstance(qos, QoSProfile):
        return qos
    spec = as_qos_spec(qos)
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST, depth=spec.depth,
        reliability=ReliabilityPolicy.RELIABLE if spec.reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if spec.transient_local
                    else DurabilityPolicy.VOLATILE))


class Client:
    """Rclpy client wrapper: ``call`` raises TimeoutError and spins the node if nobody does."""

    def __init__(self, node: 'Node', client: Any) -> None:
        self._node = node
        self._client = client
        self.srv_type = client.srv_type
        self.service_name = client.service_name

    def service_is_ready(self) -> bool:
        return self._client.service_is_ready()

    def wait_for_service(self, timeout_sec: Optional[float] = None) -> bool:
        return self._client.wait_for_service(timeout_sec=timeout_sec)

    def call_async(self, request: Any) -> Any:
        return self._client.call_async(request)

    def call(self, request: Any, timeout_sec: Optional[float] = None) -> Any:
        """Send ``request`` and block for the reply; TimeoutError after ``timeout_sec``."""
        if not self._client.wait_for_service(timeout_sec=timeout_sec):
            raise TimeoutError(f'service not available: {self.service_name=} {timeout_sec=}')
        if self._node.is_spinning():
            # another thread spins the node and delivers the reply
            response = self._client.call(request, timeout_sec=timeout_sec)
        else:
            future = self._client.call_async(request)
            self._node._spinning(+1)
            try:
                self._node.own_executor().spin_until_future_complete(
                    future, timeout_sec=timeout_sec)
            finally:
                self._node._spinning(-1)
            if not future.done():
                self._client.remove_pending_request(future)
            response = future.result()
        if response is None:
            raise TimeoutError(f'no reply from {self.service_name=} within {timeout_sec=}')
        return response

    def destroy(self) -> None:
        self._node.destroy_client(self._client)


class HeaderKeepingService(_rclpy_impl.Service):
    """
    Keep the rmw service info of the request taken last (an rclpy service handle).

    rclpy's executor takes a request (with its header) and calls the callback with the
    request alone; the executor of a node runs take and callback one after the other in its
    one thread, so the callback reads the header of its own request here.
    """

    last_info: Any = None

    def service_take_request(self, request_cls: Any) -> Any:
        taken = super().service_take_request(request_cls)
        self.last_info = taken[1]
        return taken


class Node(RclpyNode):
    """Rclpy Node accepting the backend-neutral arguments of frf_ident.middleware."""

    def __init__(self, name: str, *, namespace: str = '/',
                 parameter_overrides: Optional[dict[str, Any]] = None,
                 use_sim_time: Optional[bool] = None, global_arguments: bool = True) -> None:
        overrides = dict(parameter_overrides or {})
        if use_sim_time is not None:
            overrides['use_sim_time'] = bool(use_sim_time)
        super().__init__(name, namespace=namespace, parameter_overrides=[
            Parameter(key, value=value) for key, value in overrides.items()],
            use_global_arguments=global_arguments)
        self._client_group = ReentrantCallbackGroup()
        self._spinners = 0
        self._spinners_lock = threading.Lock()
        self._own_executor: Optional[SingleThreadedExecutor] = None

    def own_executor(self) -> SingleThreadedExecutor:
        """Return the node's own single-threaded executor (created once, reused)."""
        if self._own_executor is None:
            self._own_executor = SingleThreadedExecutor()
            self._own_executor.add_node(self)
        return self._own_executor

    def is_spinning(self) -> bool:
        """Tell whether :func:`spin` or :func:`spin_once` of this module runs this node."""
        return self._spinners > 0

    def _spinning(self, delta: int) -> None:
        with self._spinners_lock:
            self._spinners += delta

    def declare_parameter(self, name: str, value: Any = None,
                          descriptor: Optional[ParameterDescriptor] = None,
                          ignore_override: bool = False) -> Parameter:
        """
        As rclpy, but read-only, and ``None`` and ``[]`` defaults are dynamically typed.

        The nodes read their parameters once, at start-up, where they are checked: a
        ``ros2 param set`` at run time would report success and change nothing, so it fails.
        """
        if descriptor is None:
            descriptor = ParameterDescriptor(read_only=True, dynamic_typing=(
                value is None or (isinstance(value, (list, tuple)) and not value)))
        return super().declare_parameter(name, value, descriptor, ignore_override)

    def create_publisher(self, msg_type: Any, topic: str, qos: 'QosSpec | int | QoSProfile',
                         **kwargs: Any) -> Any:
        return super().create_publisher(msg_type, topic, to_qos_profile(qos), **kwargs)

    def create_subscription(self, msg_type: Any, topic: str, callback: Callable[[Any], None],
                            qos: 'QosSpec | int | QoSProfile', *, drain: bool = False,
                            **kwargs: Any) -> Any:
        """
        Create a subscription as rclpy does; ``drain`` takes every queued message per wake.

        rclpy's executor takes one message per ready subscription and waits again; with
        ``drain`` the callback also takes what else is queued on that subscription (the DDS
        backend always does). For a recorder that keeps up with several topics at 1 kHz.
        """
        if not drain:
            return super().create_subscription(msg_type, topic, callback, to_qos_profile(qos),
                                               **kwargs)
        holder: list = []

        def draining(msg: Any) -> None:
            callback(msg)
            sub = holder[0]
            for _ in range(DRAIN_BATCH):     # bounded: the other subscriptions get their turn
                with sub.handle:
                    got = sub.handle.take_message(sub.msg_type, sub.raw)
                if got is None:
                    return
                callback(got[0])

        holder.append(super().create_subscription(msg_type, topic, draining,
                                                  to_qos_profile(qos), **kwargs))
        return holder[0]

    def create_service(self, srv_type: Any, srv_name: str, callback: Callable[..., Any], *,
                       caller: bool = False, **kwargs: Any) -> Any:
        """
        As rclpy; ``caller``: ``callback(request, response, Caller)`` (middleware/caller.py).

        rclpy passes no request header to a callback, so a caller-aware service is built
        from a :class:`HeaderKeepingService` as ``rclpy.node.Node.create_service`` builds
        one (test/ros/test_ros_arming.py fails if rclpy changes this).
        """
        if not caller:
            return super().create_service(srv_type, srv_name, callback, **kwargs)
        group = kwargs.get('callback_group') or self.default_callback_group
        qos = kwargs.get('qos_profile', qos_profile_services_default)
        check_is_valid_srv_type(srv_type)
        with self.handle:
            impl = HeaderKeepingService(self.handle, srv_type, srv_name,
                                        qos.get_c_qos_profile())

        def with_caller(request: Any, response: Any) -> Any:
            return callback(request, response, self.caller_of(service, impl.last_info))
        service = Service(impl, srv_type, srv_name, with_caller, group, qos)
        group.add_entity(service)
        self._services.append(service)
        self._wake_executor()
        return service

    def caller_of(self, service: Any, info: Any) -> Caller:
        """Return what rclpy tells of a request: sequence, send time, the client nodes."""
        name = service.service_name
        deadline = time.monotonic() + CALLER_GRAPH_WAIT_S
        while True:       # the caller's node info may come a moment after its request
            clients = self.get_publishers_info_by_topic(f'rq{name}Request', no_mangle=True)
            nodes = sorted({f"{c.node_namespace.rstrip('/')}/{c.node_name}" for c in clients})
            # a writer the graph lists before its node's info came is named
            # _NODE_NAMESPACE_UNKNOWN_/_NODE_NAME_UNKNOWN_: not listed yet either
            known = [n for n in nodes if UNKNOWN_NODE not in n]
            if known or time.monotonic() > deadline:
                nodes = known or nodes
                break
            time.sleep(0.01)
        seq, sent = -1, None
        if info is not None:
            seq, sent = int(info.request_id.sequence_number), int(info.source_timestamp) or None
        return Caller('rclpy', name, seq, time.time_ns(), sent_ns=sent,
                      node=nodes[0] if len(nodes) == 1 else None, candidates=tuple(nodes))

    def create_client(self, srv_type: Any, srv_name: str, **kwargs: Any) -> Client:
        kwargs.setdefault('callback_group', self._client_group)
        return Client(self, super().create_client(srv_type, srv_name, **kwargs))


def init(args: Optional[Sequence[str]] = None) -> None:
    if not rclpy.ok():
        # signals stay the application's (nodes: common.StopOnSignal; else KeyboardInterrupt):
        # rclpy's handler shut the context down under a node still draining its queues (a
        # traceback in the estimator's final drain at Ctrl-C, issue 44)
        from rclpy.signals import SignalHandlerOptions
        rclpy.init(args=None if args is None else list(args),
                   signal_handler_options=SignalHandlerOptions.NO)


def ok() -> bool:
    return rclpy.ok()


def shutdown() -> None:
    rclpy.try_shutdown()


def create_node(name: str, *, namespace: str = '/',
                parameter_overrides: Optional[dict[str, Any]] = None,
                use_sim_time: Optional[bool] = None, global_arguments: bool = True) -> Node:
    init()
    return Node(name, namespace=namespace, parameter_overrides=parameter_overrides,
                use_sim_time=use_sim_time, global_arguments=global_arguments)


def spin_once(node: Node, timeout_sec: Optional[float] = None) -> None:
    node._spinning(+1)
    try:
        node.own_executor().spin_once(timeout_sec=timeout_sec)
    finally:
        node._spinning(-1)


def spin(node: Node, stop_event: Optional[threading.Event] = None) -> None:
    """
    Spin the node's SingleThreadedExecutor until ``stop_event`` is set or rclpy shuts down.

    One thread runs every callback, in order, as rclpy's own ``rclpy.spin`` (the
    MultiThreadedExecutor costs several times more per message). A client's ``call`` works
    from another thread while this one spins, not from inside a callback (use ``call_async``).
    """
    executor = node.own_executor()
    node._spinning(+1)
    try:
        while rclpy.ok() and not (stop_event is not None and stop_event.is_set()):
            executor.spin_once(timeout_sec=0.1)
    finally:
        node._spinning(-1)


def msg(type_name: str) -> type:
    """``pkg/msg/Type`` -> the generated rclpy message class."""
    pkg, kind, name = _split(type_name, 'msg')
    return getattr(importlib.import_module(f'{pkg}.{kind}'), name)


def srv(type_name: str) -> type:
    """``pkg/srv/Type`` -> the generated rclpy service class."""
    pkg, kind, name = _split(type_name, 'srv')
    return getattr(importlib.import_module(f'{pkg}.{kind}'), name)


def _split(type_name: str, kind: str) -> tuple[str, str, str]:
    parts = type_name.split('/')
    if len(parts) != 3 or parts[1] != kind:
        raise ValueError(f'expected a pkg/{kind}/Type name, got {type_name=}')
    return parts[0], parts[1], parts[2]
