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
Record a bag incrementally from a running node (:class:`BagRecorder`).

The file stays readable if the process dies: small MCAP chunks are closed often and flushed to
the OS (:class:`~frf_ident.bag.mcap_storage.FlushingWriter`); ``split()`` closes the current
file and records on in the next, as ``ros2 bag record`` splits a bag.
"""
from __future__ import annotations

import os
from pathlib import Path
import threading
from typing import Any, Mapping

from frf_ident.errors import BagError
from rosbags.interfaces import Connection, Qos
from rosbags.rosbag2 import StoragePlugin, Writer

from .mcap_storage import FlushingMcapWriter, FlushingWriter
from .message_dict import serialize_dict, typestore
from .topics import BagTopics

__all__ = ['BagRecorder']


class BagRecorder:
    """
    Incremental rosbag2 MCAP recorder for a running node.

    ``open(path)``, then ``write(topic, msg_type, stamp_ns, data)`` with CDR bytes or a dict
    of message fields, ``flush()`` now and then, ``close()`` at the end (idempotent; safe to
    call from a signal handler or another thread: if a write is in progress in the same
    thread, the close happens right after it).

    Crash behaviour: messages are collected in an MCAP chunk that is closed and written to the
    OS when it reaches ``chunk_bytes`` (64 KiB), when ``flush_period_s`` (0.5 s) has passed
    since the last flush, and on ``flush()``. If the process is SIGKILLed, every closed chunk
    survives (the OS holds the written bytes; only a power loss can lose them unless
    ``fsync=True``); only the open chunk is lost, at most ``chunk_bytes`` of data or the last
    ``flush_period_s``. Summary, footer and metadata.yaml are written by ``close()``;
    :func:`frf_ident.bag.read_recording` reads a bag without them, and
    :func:`frf_ident.bag.repair.reindex` rewrites it as a complete bag.
    """

    def __init__(self, *, topics: BagTopics | None = None, chunk_bytes: int = 64 * 1024,
                 flush_period_s: float = 0.5, fsync: bool = False,
                 qos: Mapping[str, Qos] | None = None) -> None:
        self.topics = topics or BagTopics()
        self.chunk_bytes = int(chunk_bytes)
        self.flush_period_s = float(flush_period_s)
        self.fsync = fsync
        self.qos = dict(qos or {})
        self.path: Path | None = None
        self._writer: FlushingWriter | None = None
        self._conns: dict[str, Connection] = {}
        self._lock = threading.Lock()
        self._owner: int | None = None
        self._close_pending = False

    def __enter__(self) -> 'BagRecorder':
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def open(self, path: str | os.PathLike[str]) -> 'BagRecorder':  # noqa: A003
        """Create the bag directory ``path`` (which must not exist)."""
        path = Path(path)
        if self._writer is not None:
            raise BagError(f'recorder already open on {str(self.path)!r}')
        if path.exists():
            raise BagError(f'bag path {str(path)!r} exists; refusing to overwrite recorded data')
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            writer = FlushingWriter(path, version=9, storage_plugin=StoragePlugin.MCAP)
            writer.open()
        except OSError as err:       # a file on the way, no permission, a read-only disk
            on_way = next((p for p in path.parents if p.exists()), None)
            why = (f'{on_way} is a file, not a directory' if on_way and not on_way.is_dir()
                   else err.strerror or str(err))
            raise BagError(f'bag path {str(path)!r} cannot be created: {why}') from err
        storage = writer.storage
        assert isinstance(storage, FlushingMcapWriter)
        storage.chunk_bytes = self.chunk_bytes
        storage.flush_period_s = self.flush_period_s
        self._writer, self.path, self._conns = writer, path, {}
        return self

    @property
    def is_open(self) -> bool:
        """Return true between open() and close()."""
        return self._writer is not None

    def write(self, topic: str, msg_type: str, stamp_ns: int,
              data: bytes | bytearray | memoryview | Mapping[str, Any]) -> None:
        """Record one message on ``topic`` with log time ``stamp_ns`` [ns]."""
        with self._locked():
            writer = self._writer
            if writer is None:
                raise BagError('BagRecorder.write() called on a closed recorder')
            conn = self._conns.get(topic)
            if conn is None:
                conn = self._add(writer, topic, msg_type)
            elif conn.msgtype != msg_type:
                raise BagError(f'{topic=}: recorded as {conn.msgtype}, got {msg_type=}')
            raw = data if isinstance(data, (bytes, bytearray, memoryview)) else \
                serialize_dict(msg_type, data)
            writer.write(conn, int(stamp_ns), bytes(raw))

    def flush(self) -> None:
        """Close the open chunk and hand it to the OS (and the disk, if ``fsync``)."""
        with self._locked():
            self._flush()

    def split(self) -> None:
        """
        Close the current file now (summary, footer, metadata.yaml) and record on in the next.

        The bag is complete up to here for ``ros2 bag info``, ``ros2 bag play`` and the
        readers while recording goes on (files named as ``ros2 bag record`` splits them).
        """
        with self._locked():
            if self._writer is not None:
                self._flush()
                self._writer.split()

    def close(self) -> None:
        """Write summary, footer and metadata.yaml; later calls do nothing."""
        if self._owner == threading.get_ident():
            self._close_pending = True  # called from a signal handler inside write()
            return
        with self._locked():
            self._close()

    # ------------------------------------------------------------------ internals
    def _locked(self) -> '_Held':
        return _Held(self)

    def _flush(self) -> None:
        if self._writer is None or self._writer.storage is None:
            return
        storage = self._writer.storage
        assert isinstance(storage, FlushingMcapWriter)
        storage.close_chunk()
        if self.fsync:
            os.fsync(storage.bio.fileno())

    def _close(self) -> None:
        writer, self._writer = self._writer, None
        if writer is not None:
            writer.close()

    def _add(self, writer: Writer, topic: str, msg_type: str) -> Connection:
        ts = typestore()
        if msg_type not in ts.types:
            raise BagError(f'{topic=}: unknown message type {msg_type=} (not in ROS 2 Jazzy)')
        qos = self.qos.get(topic) or self.topics.qos(topic)
        conn = writer.add_connection(topic, msg_type, typestore=ts, offered_qos_profiles=[qos])
        self._conns[topic] = conn
        return conn


class _Held:
    """Context manager holding the recorder's lock and remembering the owner thread."""

    def __init__(self, rec: BagRecorder) -> None:
        self.rec = rec

    def __enter__(self) -> None:
        self.rec._lock.acquire()
        self.rec._owner = threading.get_ident()

    def __exit__(self, *exc: object) -> None:
        rec = self.rec
        try:
            if rec._close_pending:
                rec._close_pending = False
                rec._close()
        finally:
            rec._owner = None
            rec._lock.release()
