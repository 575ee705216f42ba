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
"""

import itertools
import os
import sys
import threading
import time
from typing import Any, Callable, Optional, Sequence
import uuid

from cyclonedds.core import (DDSException, GuardCondition, InstanceState, Policy, Qos,
                             ReadCondition, SampleState, ViewState, WaitSet)
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from frf_ident.middleware import ros_types
from frf_ident.middleware.dds_caller import CallerLookup, GRAPH_DEPTH
from frf_ident.middleware.params import parse_ros_args
from frf_ident.middleware.qos import as_qos_spec, qos_clock, qos_transient_local, QosSpec

BACKEND_NAME = 'dds'

#: Loopback-only configuration, equivalent to config/cyclonedds-localhost.xml (``lo`` may lack
#: the MULTICAST flag, so discovery is unicast to 127.0.0.1 with participant indices).
LOCALHOST_CONFIG = """<CycloneDDS xmlns="https://cdds.io/config"><Domain Id="any">
<General><Interfaces><NetworkInterface name="lo"/></Interfaces>
<AllowMulticast>false</AllowMulticast></General>
<Discovery><ParticipantIndex>auto</ParticipantIndex>
<MaxAutoParticipantIndex>32</MaxAutoParticipantIndex>
<Peers><Peer address="127.0.0.1"/></Peers></Discovery>
</Domain></CycloneDDS>"""

_INFINITE_NS = 2**63 - 1
_ANY_SAMPLE = SampleState.Any | ViewState.Any | InstanceState.Any
_TAKE_BATCH = 256
_SERVICE_REPLY_MATCH_TIMEOUT_S = 0.1  # rmw_cyclonedds waits at most 100 ms too
_CALL_WAIT_SLICE_NS = 50_000_000


#: what a node raises for a bad parameter value (this backend converts values as declared)
PARAMETER_ERRORS: tuple = (ValueError, TypeError)


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


def _user_data(**items: str) -> bytes:
    return ''.join(f'{k}={v};' for k, v in items.items()).encode()


def _parse_user_data(qos: Optional[Qos]) -> dict[str, str]:
    if qos is None or Policy.Userdata not in qos:
        return {}
    text = qos[Policy.Userdata].data.decode('utf-8', errors='replace')
    out = {}
    for item in text.split(';'):
        key, sep, value = item.partition('=')
        if sep:
            out[key.strip()] = value
    return out


def _dds_qos(spec: QosSpec, user_data: bytes, writer: bool) -> Qos:
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


def _delete(entity: Any) -> None:
    """Delete a DDS entity now instead of at garbage collection (idempotent)."""
    entity.__del__()


def _gid(entity: Any) -> ros_types.Gid:
    return ros_types.Gid(data=entity.get_guid().bytes)


def _new_endpoint_id() -> str:
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


class _Context:
    """One DomainParticipant per process (as rmw since Foxy), shared by all nodes."""

    def __init__(self, args: Sequence[str]) -> None:
        self.args = list(args)
        self.lock = threading.RLock()
        self.nodes: list['Node'] = []
        self.domain_id = domain_id_from_env()
        self._domain = (Domain(self.domain_id, LOCALHOST_CONFIG)
                        if localhost_only() and not os.environ.get('CYCLONEDDS_URI') else None)
        self.participant = DomainParticipant(
            self.domain_id, qos=Qos(Policy.Userdata(_user_data(enclave='/'))))
        self._topics: dict[tuple[str, type], Topic] = {}
        self._pub_reader: Any = None
        self._callers: Any = None
        self._graph_writer = DataWriter(
            self.participant,
            self.topic('ros_discovery_info', ros_types.ParticipantEntitiesInfo),
            _dds_qos(qos_transient_local(1), _user_data(typehash=ros_types.TYPE_HASHES[
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
                reader_gid_seq=[_gid(r) for r in n._graph_readers()],
                writer_gid_seq=[_gid(w) for w in n._graph_writers()]) for n in self.nodes]
            self._graph_writer.write(ros_types.ParticipantEntitiesInfo(
                gid=_gid(self.participant), node_entities_info_seq=infos))

    def caller_lookup(self) -> Any:
        """Return the lookup naming a request's caller (its readers created on first use)."""
        with self.lock:
            if self._callers is None:
                self._callers = CallerLookup(
                    self.participant,
                    self.topic('ros_discovery_info', ros_types.ParticipantEntitiesInfo),
                    _dds_qos(qos_transient_local(GRAPH_DEPTH), _user_data(
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
        _delete(self._graph_writer)
        if self._callers is not None:
            self._callers.close(_delete)
        if self._pub_reader is not None:
            _delete(self._pub_reader)
        _delete(self.participant)
        if self._domain is not None:
            _delete(self._domain)


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


def _get_context() -> _Context:
    init()
    assert _context is not None
    return _context


class RosTime:
    """A point in ROS time (rclpy.time.Time subset): ``.nanoseconds`` and ``.to_msg()``."""

    __slots__ = ('nanoseconds',)

    def __init__(self, nanoseconds: int = 0) -> None:
        self.nanoseconds = int(nanoseconds)

    def to_msg(self) -> ros_types.Time:
        sec, nanosec = divmod(self.nanoseconds, 1_000_000_000)
        return ros_types.Time(sec=sec, nanosec=nanosec)

    def seconds_nanoseconds(self) -> tuple[int, int]:
        return divmod(self.nanoseconds, 1_000_000_000)

    def __repr__(self) -> str:
        return f'RosTime(nanoseconds={self.nanoseconds})'


class Clock:
    """The node clock: system time, or the last ``/clock`` value with use_sim_time (0 before)."""

    def __init__(self, use_sim_time: bool) -> None:
        self.use_sim_time = use_sim_time
        self._sim_ns = 0

    def now_ns(self) -> int:
        return self._sim_ns if self.use_sim_time else time.time_ns()

    def now(self) -> RosTime:
        return RosTime(self.now_ns())

    def _set_sim(self, msg: ros_types.Clock) -> None:
        self._sim_ns = msg.clock.sec * 1_000_000_000 + msg.clock.nanosec


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


class Future:
    """Result of ``Client.call_async`` (rclpy.task.Future subset), thread-safe."""

    def __init__(self) -> None:
        self._done = threading.Event()
        self._result: Any = None
        self._exception: Optional[BaseException] = None
        self._callbacks: list[Callable[['Future'], None]] = []
        self._lock = threading.Lock()

    def done(self) -> bool:
        return self._done.is_set()

    def result(self) -> Any:
        """Return the result, or None while pending; re-raises the exception set by the backend."""
        if self._exception is not None:
            raise self._exception
        return self._result

    def exception(self) -> Optional[BaseException]:
        return self._exception

    def wait(self, timeout_sec: Optional[float] = None) -> bool:
        return self._done.wait(timeout_sec)

    def set_result(self, result: Any) -> None:
        self._finish(result, None)

    def set_exception(self, exception: BaseException) -> None:
        self._finish(None, exception)

    def add_done_callback(self, callback: Callable[['Future'], None]) -> None:
        with self._lock:
            if not self._done.is_set():
                self._callbacks.append(callback)
                return
        callback(self)

    def _finish(self, result: Any, exception: Optional[BaseException]) -> None:
        with self._lock:
            if self._done.is_set():
                return
            self._result, self._exception = result, exception
            self._done.set()
            callbacks, self._callbacks = self._callbacks, []
        for callback in callbacks:
            callback(self)


class Publisher:
    def __init__(self, node: 'Node', msg_cls: type, topic: str, qos: QosSpec) -> None:
        ros_type = ros_types.ros_type_name(msg_cls)
        self.topic_name = resolve_name(topic, node.get_name(), node.get_namespace())
        self.msg_type = msg_cls
        self._writer = DataWriter(
            node._ctx.participant, node._ctx.topic('rt' + self.topic_name, msg_cls),
            _dds_qos(qos, _user_data(typehash=ros_types.TYPE_HASHES[ros_type]), writer=True))
        self._write = self._writer.write

    def publish(self, msg: Any) -> None:
        self._write(msg)

    def get_subscription_count(self) -> int:
        return len(self._writer.get_matched_subscriptions())

    def _destroy(self) -> None:
        _delete(self._writer)


class Subscription:
    def __init__(self, node: 'Node', msg_cls: type, topic: str,
                 callback: Callable[[Any], None], qos: QosSpec) -> None:
        ros_type = ros_types.ros_type_name(msg_cls)
        self.topic_name = resolve_name(topic, node.get_name(), node.get_namespace())
        self.msg_type = msg_cls
        self.callback = callback
        self._reader = DataReader(
            node._ctx.participant, node._ctx.topic('rt' + self.topic_name, msg_cls),
            _dds_qos(qos, _user_data(typehash=ros_types.TYPE_HASHES[ros_type]), writer=False))
        self._condition = ReadCondition(self._reader, _ANY_SAMPLE)

    def get_publisher_count(self) -> int:
        return len(self._reader.get_matched_publications())

    def _dispatch(self) -> None:
        for sample in self._reader.take(_TAKE_BATCH, condition=self._condition):
            if sample.sample_info.valid_data:
                self.callback(sample)

    def _destroy(self) -> None:
        _delete(self._condition)
        _delete(self._reader)


class Timer:
    """A periodic timer on the node clock (rcl semantics: missed periods are skipped)."""

    def __init__(self, node: 'Node', period_sec: float, callback: Callable[[], None]) -> None:
        if not period_sec > 0:
            raise ValueError(f'timer period must be > 0 s, got {period_sec=}')
        self.timer_period_ns = int(round(period_sec * 1e9))
        self.callback = callback
        self._clock = node._clock
        self._next_ns = self._clock.now_ns() + self.timer_period_ns
        self._canceled = False

    def cancel(self) -> None:
        self._canceled = True

    def reset(self) -> None:
        self._canceled = False
        self._next_ns = self._clock.now_ns() + self.timer_period_ns

    def is_canceled(self) -> bool:
        return self._canceled

    def time_until_next_call(self) -> Optional[int]:
        """Nanoseconds until the next call (None when canceled)."""
        return None if self._canceled else self._next_ns - self._clock.now_ns()

    def _due(self, now_ns: int) -> bool:
        if self._canceled:
            return False
        period = self.timer_period_ns
        if self._next_ns - now_ns > period:  # the clock jumped backwards (sim reset)
            self._next_ns = now_ns + period
            return False
        if now_ns < self._next_ns:
            return False
        self._next_ns += ((now_ns - self._next_ns) // period + 1) * period
        return True


class Service:
    """A service server speaking rmw_cyclonedds' request/reply framing."""

    def __init__(self, node: 'Node', srv_type: ros_types.ServiceType, name: str,
                 callback: Callable[..., Any], caller: bool = False) -> None:
        self.srv_type = srv_type
        self.service_name = resolve_name(name, node.get_name(), node.get_namespace())
        self.callback = callback
        #: ``caller=True``: the callback also gets the request's Caller (dds_caller.py)
        self._callers = node._ctx.caller_lookup() if caller else None
        self._logger = node.get_logger()
        ctx = node._ctx
        qos = QosSpec(depth=10, reliable=True, transient_local=False)  # services_default
        user_data = _user_data(serviceid=_new_endpoint_id())
        self._reader = DataReader(
            ctx.participant, ctx.topic(f'rq{self.service_name}Request', srv_type.RequestWire),
            _dds_qos(qos, user_data, writer=False))
        self._writer = DataWriter(
            ctx.participant, ctx.topic(f'rr{self.service_name}Reply', srv_type.ResponseWire),
            _dds_qos(qos, user_data, writer=True))
        self._condition = ReadCondition(self._reader, _ANY_SAMPLE)
        self._matched_clients: set[str] = set()

    def _client_id_of(self, publication_handle: int) -> Optional[str]:
        endpoint = self._reader.get_matched_publication_data(publication_handle)
        return _parse_user_data(endpoint.qos if endpoint else None).get('clientid')

    def _reply_reader_matched(self, client_id: Optional[str]) -> bool:
        """Wait (<= 100 ms, as rmw) until the requesting client's reply reader has matched."""
        if client_id is None or client_id in self._matched_clients:
            return True
        deadline = time.monotonic() + _SERVICE_REPLY_MATCH_TIMEOUT_S
        while True:
            for handle in self._writer.get_matched_subscriptions():
                endpoint = self._writer.get_matched_subscription_data(handle)
                if endpoint is not None:
                    self._matched_clients.add(
                        _parse_user_data(endpoint.qos).get('clientid', ''))
            if client_id in self._matched_clients:
                return True
            if time.monotonic() > deadline:
                return False
            time.sleep(0.001)

    def _dispatch(self) -> None:
        for wire in self._reader.take(_TAKE_BATCH, condition=self._condition):
            if not wire.sample_info.valid_data:
                continue
            if self._callers is None:
                response = self.callback(wire.body, self.srv_type.Response())
            else:
                caller = self._callers.caller(self.service_name, self._reader, wire)
                response = self.callback(wire.body, self.srv_type.Response(), caller)
            if not isinstance(response, self.srv_type.Response):
                self._logger.error(
                    f'service {self.service_name} callback returned {response=}; '
                    f'expected a {self.srv_type.Response.__name__}, no reply sent')
                continue
            client_id = self._client_id_of(wire.sample_info.publication_handle)
            if not self._reply_reader_matched(client_id):
                self._logger.error(f'service {self.service_name}: reply reader of {client_id=} '
                                   'not matched within 100 ms, reply dropped')
                continue
            self._writer.write(self.srv_type.ResponseWire(
                client_guid=wire.client_guid, sequence_number=wire.sequence_number,
                body=response))

    def _destroy(self) -> None:
        _delete(self._condition)
        _delete(self._reader)
        _delete(self._writer)


class Client:
    """A service client; ``call`` is synchronous and safe from any thread."""

    def __init__(self, node: 'Node', srv_type: ros_types.ServiceType, name: str) -> None:
        self.srv_type = srv_type
        self.service_name = resolve_name(name, node.get_name(), node.get_namespace())
        ctx = node._ctx
        qos = QosSpec(depth=10, reliable=True, transient_local=False)  # services_default
        user_data = _user_data(clientid=_new_endpoint_id())
        self._writer = DataWriter(
            ctx.participant, ctx.topic(f'rq{self.service_name}Request', srv_type.RequestWire),
            _dds_qos(qos, user_data, writer=True))
        self._reader = DataReader(
            ctx.participant, ctx.topic(f'rr{self.service_name}Reply', srv_type.ResponseWire),
            _dds_qos(qos, user_data, writer=False))
        self._guid = self._writer.get_instance_handle() & 0xFFFF_FFFF_FFFF_FFFF  # as uint64
        self._seq = itertools.count(1)
        self._pending: dict[int, Future] = {}
        self._lock = threading.Lock()
        self._condition = ReadCondition(self._reader, _ANY_SAMPLE)  # for the node's WaitSet
        self._call_waitset = WaitSet(ctx.participant)
        self._call_waitset.attach(ReadCondition(self._reader, _ANY_SAMPLE))

    def service_is_ready(self) -> bool:
        """Return True when the request reader and the reply writer are matched (rmw's rule)."""
        request_ids = {_parse_user_data(e.qos).get('serviceid') for e in map(
            self._writer.get_matched_subscription_data, self._writer.get_matched_subscriptions())
            if e is not None}
        reply_ids = {_parse_user_data(e.qos).get('serviceid') for e in map(
            self._reader.get_matched_publication_data, self._reader.get_matched_publications())
            if e is not None}
        if not request_ids or not reply_ids:
            return False
        return bool(request_ids & reply_ids) or None in request_ids or None in reply_ids

    def wait_for_service(self, timeout_sec: Optional[float] = None) -> bool:
        deadline = None if timeout_sec is None else time.monotonic() + timeout_sec
        while not self.service_is_ready():
            if deadline is not None and time.monotonic() >= deadline:
                return False
            time.sleep(0.005)
        return True

    def call_async(self, request: Any) -> Future:
        """Send ``request``; the Future completes when the reply arrives (spin or ``call``)."""
        if not isinstance(request, self.srv_type.Request):
            raise TypeError(f'expected a {self.srv_type.Request.__name__}, got {request=}')
        future = Future()
        with self._lock:
            seq = next(self._seq)
            self._pending[seq] = future
        self._writer.write(self.srv_type.RequestWire(
            client_guid=self._guid, sequence_number=seq, body=request))
        return future

    def call(self, request: Any, timeout_sec: Optional[float] = None) -> Any:
        """Send ``request`` and block for the reply; TimeoutError after ``timeout_sec``."""
        deadline = None if timeout_sec is None else time.monotonic() + timeout_sec
        if not self.wait_for_service(timeout_sec):
            raise TimeoutError(f'service not available: {self.service_name=} {timeout_sec=}')
        future = self.call_async(request)
        while not future.done():
            remaining_ns = _CALL_WAIT_SLICE_NS if deadline is None else min(
                _CALL_WAIT_SLICE_NS, int((deadline - time.monotonic()) * 1e9))
            if remaining_ns <= 0:
                with self._lock:
                    self._pending = {k: v for k, v in self._pending.items() if v is not future}
                raise TimeoutError(f'no reply from {self.service_name=} within {timeout_sec=}')
            self._call_waitset.wait(remaining_ns)
            self._dispatch()
        return future.result()

    def _dispatch(self) -> None:
        resolved = []
        with self._lock:
            for wire in self._reader.take(_TAKE_BATCH):
                if wire.sample_info.valid_data and wire.client_guid == self._guid:
                    future = self._pending.pop(wire.sequence_number, None)
                    if future is not None:
                        resolved.append((future, wire.body))
        for future, body in resolved:
            future.set_result(body)

    def _destroy(self) -> None:
        _delete(self._call_waitset)
        _delete(self._condition)
        _delete(self._reader)
        _delete(self._writer)


class Node:
    """A ROS 2 node on Cyclone DDS with rclpy.node.Node's method names."""

    def __init__(self, name: str, *, namespace: str = '/',
                 parameter_overrides: Optional[dict[str, Any]] = None,
                 use_sim_time: Optional[bool] = None, global_arguments: bool = True) -> None:
        if not name or '/' in name:
            raise ValueError(f'invalid node name {name=}')
        self._ctx = _get_context()
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
        _delete(self._waitset)
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
