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
The Cyclone DDS backend's :class:`Node`, with rclpy.node.Node's method names.

A node declares :class:`Parameter` values (overrides from ``--ros-args`` and
``parameter_overrides``), logs with :class:`Logger`, creates the endpoints and timers, and
runs their callbacks in the thread that calls :meth:`Node.spin_once`: one WaitSet with a
ReadCondition per reader, created once.
"""

import sys
import threading
import time
from typing import Any, Callable, Optional

from cyclonedds.core import DDSException, GuardCondition, WaitSet
from frf_ident.middleware import ros_types
from frf_ident.middleware.dds_context import get_context
from frf_ident.middleware.dds_service import Client, Service
from frf_ident.middleware.dds_time import Clock, Timer
from frf_ident.middleware.dds_topics import Publisher, Subscription
from frf_ident.middleware.dds_wire import delete_entity, resolve_name
from frf_ident.middleware.params import parse_ros_args
from frf_ident.middleware.qos import as_qos_spec, qos_clock, QosSpec

__all__ = ['Logger', 'Node', 'Parameter', 'ParameterNotDeclaredError']


_INFINITE_NS = 2**63 - 1


class Logger:
    """rcutils-style console logger: ``[LEVEL] [time] [node]: message`` on stderr."""

    _LEVELS = {'DEBUG': 10, 'INFO': 20, 'WARN': 30, 'ERROR': 40, 'FATAL': 50}

    def __init__(self, name: str, level: str = 'INFO') -> None:
        self.name = name
        self._threshold = self._LEVELS[level]

    def _log(self, level: str, message: str) -> None:
        if self._LEVELS[level] >= self._threshold:
            print(f'[{level}] [{time.time():.9f}] [{self.name}]: {message}', file=sys.stderr,
                  flush=True)

    def debug(self, message: str) -> None:
        self._log('DEBUG', message)

    def info(self, message: str) -> None:
        self._log('INFO', message)

    def warn(self, message: str) -> None:
        self._log('WARN', message)

    warning = warn

    def error(self, message: str) -> None:
        self._log('ERROR', message)

    def fatal(self, message: str) -> None:
        self._log('FATAL', message)


class Parameter:
    """A declared parameter (rclpy.parameter.Parameter subset)."""

    __slots__ = ('name', 'value')

    def __init__(self, name: str, value: Any) -> None:
        self.name = name
        self.value = value

    def __repr__(self) -> str:
        return f'Parameter({self.name!r}, {self.value!r})'


class ParameterNotDeclaredError(LookupError):
    """get_parameter() of a name that was never declared (rclpy: ParameterNotDeclaredException)."""


class Node:
    """A ROS 2 node on Cyclone DDS with rclpy.node.Node's method names."""

    def __init__(self, name: str, *, namespace: str = '/',
                 parameter_overrides: Optional[dict[str, Any]] = None,
                 use_sim_time: Optional[bool] = None, global_arguments: bool = True) -> None:
        if not name or '/' in name:
            raise ValueError(f'invalid node name {name=}')
        self._ctx = get_context()
        self._name = name
        self._namespace = '/' + namespace.strip('/')
        self._logger = Logger(name)
        # global_arguments False: the command line's --ros-args are not this node's (rclpy's
        # use_global_arguments): a helper node of a process takes no parameters from them
        file_values, cli_overrides = (parse_ros_args(self._ctx.args, name, self._namespace)
                                      if global_arguments else ({}, {}))
        self._overrides = {**file_values, **cli_overrides, **(parameter_overrides or {})}
        if use_sim_time is not None:
            self._overrides['use_sim_time'] = bool(use_sim_time)
        self._parameters: dict[str, Parameter] = {}
        self._publishers: list[Publisher] = []
        self._subscriptions: list[Subscription] = []
        self._services: list[Service] = []
        self._clients: list[Client] = []
        self._timers: list[Timer] = []
        self._lock = threading.RLock()
        self._waitset = WaitSet(self._ctx.participant)
        self._guard = GuardCondition(self._ctx.participant)
        self._waitset.attach(self._guard)
        self._destroyed = False
        sim = self.declare_parameter('use_sim_time', False).value
        if not isinstance(sim, bool):
            raise ValueError(f'parameter use_sim_time must be a bool, got {sim=}')
        self._clock = Clock(sim)
        self._clock_sub = (self.create_subscription(
            ros_types.Clock, '/clock', self._clock._set_sim, qos_clock()) if sim else None)
        with self._ctx.lock:
            self._ctx.nodes.append(self)
        self._ctx.publish_graph()

    # -- identity, logging, time, parameters ------------------------------------------------
    def get_name(self) -> str:
        return self._name

    def get_namespace(self) -> str:
        return self._namespace

    def get_logger(self) -> Logger:
        return self._logger

    def get_clock(self) -> Clock:
        return self._clock

    def declare_parameter(self, name: str, value: Any = None) -> Parameter:
        """Declare ``name``; an override (params file, ``-p``, parameter_overrides) wins."""
        if name in self._parameters:
            raise ValueError(f'parameter already declared: {name=}')
        param = Parameter(name, self._overrides.get(name, value))
        self._parameters[name] = param
        return param

    def has_parameter(self, name: str) -> bool:
        return name in self._parameters

    def get_parameter(self, name: str) -> Parameter:
        try:
            return self._parameters[name]
        except KeyError:
            raise ParameterNotDeclaredError(
                f'parameter not declared: {name=} on node {self._name!r}') from None

    # -- entities ----------------------------------------------------------------------------
    def _add(self, bucket: list, entity: Any) -> Any:
        with self._lock:
            bucket.append(entity)
        condition = getattr(entity, '_condition', None)
        if condition is not None:
            self._waitset.attach(condition)
        self._guard.set(True)
        self._ctx.publish_graph()
        return entity

    def create_publisher(self, msg_cls: type, topic: str, qos: 'QosSpec | int') -> Publisher:
        return self._add(self._publishers, Publisher(self, msg_cls, topic, as_qos_spec(qos)))

    def create_subscription(self, msg_cls: type, topic: str, callback: Callable[[Any], None],
                            qos: 'QosSpec | int', *, drain: bool = True) -> Subscription:
        # drain: accepted for the rclpy backend's sake; here every wake takes a whole batch
        return self._add(self._subscriptions,
                         Subscription(self, msg_cls, topic, callback, as_qos_spec(qos)))

    def create_timer(self, period_sec: float, callback: Callable[[], None]) -> Timer:
        return self._add(self._timers, Timer(self, period_sec, callback))

    def create_service(self, srv_type: ros_types.ServiceType, name: str,
                       callback: Callable[..., Any], *, caller: bool = False) -> Service:
        """As rclpy; ``caller``: ``callback(request, response, Caller)`` (caller.py)."""
        return self._add(self._services, Service(self, srv_type, name, callback, caller))

    def create_client(self, srv_type: ros_types.ServiceType, name: str) -> Client:
        return self._add(self._clients, Client(self, srv_type, name))

    def count_publishers(self, topic: str) -> int:
        """Publish on ``topic`` in the domain, this node's own included (as rclpy)."""
        return self._ctx.count_publishers(resolve_name(topic, self._name, self._namespace))

    def _graph_readers(self) -> list:
        return ([s._reader for s in self._subscriptions] + [s._reader for s in self._services]
                + [c._reader for c in self._clients])

    def _graph_writers(self) -> list:
        return ([p._writer for p in self._publishers] + [s._writer for s in self._services]
                + [c._writer for c in self._clients])

    def destroy_node(self) -> None:
        with self._ctx.lock:
            if self not in self._ctx.nodes:
                return
            self._ctx.nodes.remove(self)
        with self._lock:
            self._destroyed = True
            entities = (self._subscriptions + self._services + self._clients + self._publishers)
            self._subscriptions, self._services, self._clients = [], [], []
            self._publishers, self._timers = [], []
        self._guard.set(True)
        for entity in entities:
            condition = getattr(entity, '_condition', None)
            if condition is not None:
                self._waitset.detach(condition)
            entity._destroy()
        delete_entity(self._waitset)
        self._ctx.publish_graph()

    # -- execution ---------------------------------------------------------------------------
    def spin_once(self, timeout_sec: Optional[float] = None) -> None:
        """Wait up to ``timeout_sec`` (None: forever) for work, then run every ready callback."""
        if self._destroyed:
            raise RuntimeError(f'spin_once on a destroyed node: {self._name=}')
        timeout_ns = _INFINITE_NS if timeout_sec is None else max(0, int(timeout_sec * 1e9))
        if not self._clock.use_sim_time:
            for timer in self._timers:
                left = timer.time_until_next_call()
                if left is not None:
                    timeout_ns = max(0, min(timeout_ns, left))
        try:
            self._waitset.wait(timeout_ns)
        except DDSException:
            if self._destroyed:  # destroy_node() from another thread while we waited
                return
            raise
        self._guard.take()
        with self._lock:
            subscriptions, services = list(self._subscriptions), list(self._services)
            clients, timers = list(self._clients), list(self._timers)
        if self._clock_sub is not None:
            self._clock_sub._dispatch()
        for sub in subscriptions:
            if sub is not self._clock_sub:
                sub._dispatch()
        for service in services:
            service._dispatch()
        for client in clients:
            client._dispatch()
        now_ns = self._clock.now_ns()
        for timer in timers:
            if timer._due(now_ns):
                timer.callback()

    def wake(self) -> None:
        """Make a blocked ``spin_once`` return (used by shutdown and stop events)."""
        self._guard.set(True)
