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
Services of the Cyclone DDS backend: :class:`Service`, :class:`Client` and its :class:`Future`.

rmw_cyclonedds_cpp's request/reply framing: ``rq/<name>Request`` / ``rr/<name>Reply`` with the
16-byte (guid, seq) header and ``serviceid=`` / ``clientid=`` USER_DATA. ``Client.call`` waits
on a private WaitSet of the client, so it works from any thread, spun or not.
"""

import itertools
import threading
import time
from typing import Any, Callable, Optional

from cyclonedds.core import ReadCondition, WaitSet
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from frf_ident.middleware import ros_types
from frf_ident.middleware.dds_wire import (ANY_SAMPLE, dds_qos, delete_entity, format_user_data,
                                           new_endpoint_id, parse_user_data, resolve_name,
                                           TAKE_BATCH)
from frf_ident.middleware.qos import QosSpec

__all__ = ['Client', 'Future', 'Service']


_SERVICE_REPLY_MATCH_TIMEOUT_S = 0.1  # rmw_cyclonedds waits at most 100 ms too
_CALL_WAIT_SLICE_NS = 50_000_000


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


class Service:
    """A service server speaking rmw_cyclonedds' request/reply framing."""

    def __init__(self, node: Any, srv_type: ros_types.ServiceType, name: str,
                 callback: Callable[..., Any], caller: bool = False) -> None:
        self.srv_type = srv_type
        self.service_name = resolve_name(name, node.get_name(), node.get_namespace())
        self.callback = callback
        #: ``caller=True``: the callback also gets the request's Caller (dds_caller.py)
        self._callers = node._ctx.caller_lookup() if caller else None
        self._logger = node.get_logger()
        ctx = node._ctx
        qos = QosSpec(depth=10, reliable=True, transient_local=False)  # services_default
        user_data = format_user_data(serviceid=new_endpoint_id())
        self._reader = DataReader(
            ctx.participant, ctx.topic(f'rq{self.service_name}Request', srv_type.RequestWire),
            dds_qos(qos, user_data, writer=False))
        self._writer = DataWriter(
            ctx.participant, ctx.topic(f'rr{self.service_name}Reply', srv_type.ResponseWire),
            dds_qos(qos, user_data, writer=True))
        self._condition = ReadCondition(self._reader, ANY_SAMPLE)
        self._matched_clients: set[str] = set()

    def _client_id_of(self, publication_handle: int) -> Optional[str]:
        endpoint = self._reader.get_matched_publication_data(publication_handle)
        return parse_user_data(endpoint.qos if endpoint else None).get('clientid')

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
                        parse_user_data(endpoint.qos).get('clientid', ''))
            if client_id in self._matched_clients:
                return True
            if time.monotonic() > deadline:
                return False
            time.sleep(0.001)

    def _dispatch(self) -> None:
        for wire in self._reader.take(TAKE_BATCH, condition=self._condition):
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
        delete_entity(self._condition)
        delete_entity(self._reader)
        delete_entity(self._writer)


class Client:
    """A service client; ``call`` is synchronous and safe from any thread."""

    def __init__(self, node: Any, srv_type: ros_types.ServiceType, name: str) -> None:
        self.srv_type = srv_type
        self.service_name = resolve_name(name, node.get_name(), node.get_namespace())
        ctx = node._ctx
        qos = QosSpec(depth=10, reliable=True, transient_local=False)  # services_default
        user_data = format_user_data(clientid=new_endpoint_id())
        self._writer = DataWriter(
            ctx.participant, ctx.topic(f'rq{self.service_name}Request', srv_type.RequestWire),
            dds_qos(qos, user_data, writer=True))
        self._reader = DataReader(
            ctx.participant, ctx.topic(f'rr{self.service_name}Reply', srv_type.ResponseWire),
            dds_qos(qos, user_data, writer=False))
        self._guid = self._writer.get_instance_handle() & 0xFFFF_FFFF_FFFF_FFFF  # as uint64
        self._seq = itertools.count(1)
        self._pending: dict[int, Future] = {}
        self._lock = threading.Lock()
        self._condition = ReadCondition(self._reader, ANY_SAMPLE)  # for the node's WaitSet
        self._call_waitset = WaitSet(ctx.participant)
        self._call_waitset.attach(ReadCondition(self._reader, ANY_SAMPLE))

    def service_is_ready(self) -> bool:
        """Return True when the request reader and the reply writer are matched (rmw's rule)."""
        request_ids = {parse_user_data(e.qos).get('serviceid') for e in map(
            self._writer.get_matched_subscription_data, self._writer.get_matched_subscriptions())
            if e is not None}
        reply_ids = {parse_user_data(e.qos).get('serviceid') for e in map(
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
            for wire in self._reader.take(TAKE_BATCH):
                if wire.sample_info.valid_data and wire.client_guid == self._guid:
                    future = self._pending.pop(wire.sequence_number, None)
                    if future is not None:
                        resolved.append((future, wire.body))
        for future, body in resolved:
            future.set_result(body)

    def _destroy(self) -> None:
        delete_entity(self._call_waitset)
        delete_entity(self._condition)
        delete_entity(self._reader)
        delete_entity(self._writer)
