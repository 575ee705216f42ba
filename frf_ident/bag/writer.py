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
Write frf_ident recordings as rosbag2 MCAP bags (metadata.yaml version 9).

Two writers:

- :func:`write_recording` turns a finished (e.g. simulated) :class:`Recording` into a bag on
  the docs/CONTRACT.md §3 topics, log time = header stamp.
- :class:`BagRecorder` records incrementally from a running node and keeps the file readable
  if the process dies: it closes small MCAP chunks often and flushes them to the OS.

Both use rosbags' ``Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)``, the
ROS2_JAZZY typestore (message definitions and RIHS01 hashes) and always record
``offered_qos_profiles`` (docs/bag_format.md; ros2 bag play offers each topic
with them, e.g. /frf/experiment transient-local).
"""
from __future__ import annotations

import json
import os
from pathlib import Path
import shutil
import struct
import tempfile
import threading
import time
from typing import Any, Mapping
import zlib

from frf_ident.core.jsonable import json_default
from frf_ident.core.recording import Recording
from frf_ident.errors import BagError
import numpy as np
from rosbags.interfaces import Connection, Qos
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.storage_mcap import McapWriter
from rosbags.typesys import get_typestore, Stores
from rosbags.typesys.store import Typestore
import yaml

from . import cdr
from .topics import BagTopics, FLOAT64_ARRAY, JOINT_STATE, STRING

#: key of the recording_meta event that lets the reader rebuild the exact float time grid.
FRF_BAG_KEY = '_frf_bag'
BAG_FORMAT = 1

_TYPESTORE: Typestore | None = None


def typestore() -> Typestore:
    """Return the shared ROS 2 Jazzy typestore, built once."""
    global _TYPESTORE
    if _TYPESTORE is None:
        _TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
    return _TYPESTORE


# --------------------------------------------------------------------------- write_recording

def write_recording(rec: Recording, path: str | os.PathLike[str], *,
                    topics: BagTopics | None = None, overwrite: bool = False) -> Path:
    """
    Write ``rec`` as a rosbag2 MCAP bag directory at ``path`` and return the path.

    Topics (names from ``topics``): joint states per sample, velocity commands (finite
    reference rows only), effort commands, the excitation as JointState.velocity, experiment
    descriptors at segment start/end, and one ``recording_meta`` descriptor at the first stamp.
    An existing ``path`` is refused unless ``overwrite``; even then the old bag is only
    replaced after the new one has been written completely.
    """
    topics = topics or BagTopics()
    path = Path(path)
    if path.exists() and not overwrite:
        raise BagError(f'bag path {str(path)!r} exists; refusing to overwrite recorded data '
                       f'(pass overwrite=True or choose another path)')
    stamps = _stamps_ns(rec)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp_root = Path(tempfile.mkdtemp(prefix=f'.{path.name}.', dir=path.parent))
    try:
        tmp = tmp_root / path.name
        _write_bag(rec, stamps, tmp, topics)
        _replace(tmp, path)
    finally:
        shutil.rmtree(tmp_root, ignore_errors=True)
    return path


def _replace(new: Path, dst: Path) -> None:
    """Move ``new`` to ``dst``; an existing ``dst`` is removed only after the move worked."""
    if not dst.exists():
        new.rename(dst)
        return
    backup = dst.with_name(f'.{dst.name}.old-{os.getpid()}')
    dst.rename(backup)
    try:
        new.rename(dst)
    except OSError:
        backup.rename(dst)
        raise
    if backup.is_dir():
        shutil.rmtree(backup)
    else:
        backup.unlink()


def _stamps_ns(rec: Recording) -> np.ndarray:
    t = np.asarray(rec.t, dtype=float)
    if t.size == 0:
        raise BagError('recording has no samples; nothing to write')
    if not np.all(np.isfinite(t)) or t[0] < 0:
        raise BagError(f'recording times must be finite and >= 0 s (t[0]={t[0]!r})')
    stamps = np.round(t * 1e9).astype(np.int64)
    if np.any(np.diff(stamps) <= 0):
        raise BagError('recording times must increase by at least 1 ns per sample')
    return stamps


def _time_grid(t: np.ndarray) -> dict[str, Any] | None:
    """
    Return a formula that reproduces ``t`` bit-exactly (see :func:`grid_times`), or None.

    Tried: ``t0 + k*dt`` ('mul'), ``t0 + k/fs`` ('div') and ``(k0 + k)*dt`` ('idx'), the
    ways simulations build their time vectors.
    """
    if t.size < 2:
        return None
    t0, n = float(t[0]), int(t.size)
    dts = (float(t[1] - t[0]), float(np.median(np.diff(t))), float((t[-1] - t[0]) / (n - 1)))
    candidates: list[dict[str, Any]] = [{'grid': 'mul', 't0': t0, 'dt': dt} for dt in dts]
    for dt in dts:
        fs = 1.0 / dt
        candidates += [{'grid': 'div', 't0': t0, 'fs': f} for f in (fs, float(round(fs)))]
        candidates.append({'grid': 'idx', 'k0': int(round(t0 / dt)), 'dt': dt})
    for cand in candidates:
        if np.array_equal(grid_times(cand, n), t):
            return cand
    return None


def grid_times(spec: dict[str, Any], n: int, start: int = 0) -> np.ndarray:
    """
    Return the float times of samples ``start ..

    start + n - 1`` of a ``_time_grid`` spec (each element identical to the same element of the
    whole grid).
    """
    k = np.arange(start, start + n)
    if spec['grid'] == 'mul':
        return float(spec['t0']) + k * float(spec['dt'])
    if spec['grid'] == 'div':
        return float(spec['t0']) + k / float(spec['fs'])
    if spec['grid'] == 'idx':
        return (int(spec['k0']) + k) * float(spec['dt'])
    raise ValueError(f'unknown time grid {spec["grid"]!r}')


def _experiment_events(rec: Recording, stamps: np.ndarray) -> list[tuple[int, int, str]]:
    """(stamp_ns, order, json) of the recording_meta and segment start/end descriptors."""
    meta = {'event': 'recording_meta'}
    meta.update(rec.meta)
    frf: dict[str, Any] = {'format': BAG_FORMAT, 'n': int(rec.t.size),
                           'joint_names': list(rec.joint_names), 'reference': 'per_sample'}
    grid = _time_grid(rec.t)
    if grid:
        frf['time'] = grid
    meta[FRF_BAG_KEY] = frf
    events = [(int(stamps[0]), 0, json.dumps(meta, sort_keys=True, default=json_default))]
    for seg in rec.segments:
        for event, t, order in (('start', seg.t_start, 2), ('end', seg.t_end, 1)):
            ns = max(int(round(float(t) * 1e9)), 0)
            events.append((ns, order, seg.descriptor(event)))
    events.sort(key=lambda e: (e[0], e[1]))
    return events


def _write_bag(rec: Recording, stamps: np.ndarray, path: Path, topics: BagTopics) -> None:
    ts = typestore()
    writer = _CrcWriter(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    try:
        conn = _connections(writer, ts, rec, topics)
        js = cdr.JointStateEncoder(rec.joint_names)
        events = _experiment_events(rec, stamps)
        ev = 0
        ref_ok = (np.all(np.isfinite(rec.reference), axis=1)
                  if rec.reference is not None else None)
        empty = np.empty(0)
        for k, ns in enumerate(stamps.tolist()):
            while ev < len(events) and events[ev][0] <= ns:
                writer.write(conn['exp'], events[ev][0], cdr.encode_string(events[ev][2]))
                ev += 1
            writer.write(conn['js'], ns, js.encode(ns, rec.position[k], rec.velocity[k],
                                                   rec.effort[k]))
            if ref_ok is not None and ref_ok[k]:
                writer.write(conn['ref'], ns, cdr.encode_float64_array(rec.reference[k]))
            writer.write(conn['eff'], ns, cdr.encode_float64_array(rec.effort[k]))
            if rec.excitation is not None:
                writer.write(conn['exc'], ns, js.encode(ns, empty, rec.excitation[k], empty))
        for ns, _, text in events[ev:]:
            writer.write(conn['exp'], ns, cdr.encode_string(text))
    except BaseException:
        writer.abort()
        raise
    writer.close()


def _connections(writer: Writer, ts: Typestore, rec: Recording,
                 topics: BagTopics) -> dict[str, Connection]:
    def add(topic: str, msgtype: str) -> Connection:
        return writer.add_connection(topic, msgtype, typestore=ts,
                                     offered_qos_profiles=[topics.qos(topic)])

    conn = {'js': add(topics.joint_states, JOINT_STATE)}
    if rec.reference is not None:
        conn['ref'] = add(topics.velocity_commands, FLOAT64_ARRAY)
    conn['eff'] = add(topics.effort_commands, FLOAT64_ARRAY)
    if rec.excitation is not None:
        conn['exc'] = add(topics.excitation, JOINT_STATE)
    conn['exp'] = add(topics.experiment, STRING)
    return conn


# --------------------------------------------------------------------------- BagRecorder

class _CrcMcapWriter(McapWriter):
    """
    rosbags' MCAP storage with the chunk CRC filled in.

    rosbags writes 0 (not computed), so a reader cannot tell a damaged chunk from an intact
    one and a bad byte in the middle of a bag fails the whole read; with the CRC the reader
    (frf_ident/bag/mcapio.py) drops that chunk alone and reports what was lost, as for the
    bags of ``ros2 bag record``, whose MCAP writer computes it.
    """

    #: offset of uncompressed_crc in a chunk record: opcode, length, start, end, size
    _CRC_AT = 1 + 8 + 8 + 8 + 8

    def close_chunk(self) -> None:
        data = self.chunk.bio.getvalue()
        start = self.bio.tell()
        super().close_chunk()
        if data:
            end = self.bio.tell()
            self.bio.seek(start + self._CRC_AT)
            self.bio.write(struct.pack('<I', zlib.crc32(data)))
            self.bio.seek(end)


class _CrcWriter(Writer):
    STORAGE_PLUGINS = {StoragePlugin.MCAP: _CrcMcapWriter}


class _FlushingMcapWriter(_CrcMcapWriter):
    """rosbags' MCAP storage with small chunks that are handed to the OS as soon as closed."""

    chunk_bytes = 64 * 1024
    flush_period_s = 0.5

    def __init__(self, path: Path, compression: Any) -> None:
        super().__init__(path, compression)
        self.compression_mode = compression
        #: (connection, None) per add_msgtype, (connection, qos) per add_connection, in order
        self.registered: list[tuple[Connection, str | None]] = []
        self._last_flush = time.monotonic()

    def write(self, connection: Connection, timestamp: int, data: bytes | memoryview) -> None:
        super().write(connection, timestamp, data)
        if (self.chunk.bio.tell() >= self.chunk_bytes
                or time.monotonic() - self._last_flush >= self.flush_period_s):
            self.close_chunk()

    def close_chunk(self) -> None:
        if self.chunk.bio.tell():
            super().close_chunk()
        self.bio.flush()
        self._last_flush = time.monotonic()

    def add_msgtype(self, connection: Connection) -> None:
        super().add_msgtype(connection)
        self.registered.append((connection, None))

    def add_connection(self, connection: Connection, offered_qos_profiles: str) -> None:
        super().add_connection(connection, offered_qos_profiles)
        self.registered.append((connection, offered_qos_profiles))

    def close(self, version: int, metadata: str) -> None:
        super().close(version, _with_distro(metadata))

    def rename(self, path: Path) -> None:
        """Give the (open) file another name; the metadata names it so."""
        os.rename(self.path, path)
        self.path = path

    def next_part(self, path: Path) -> '_FlushingMcapWriter':
        """Return the storage of the bag's next file ``path``: same schemas, channels, chunking."""
        part = type(self)(self.path.parent, self.compression_mode)
        part.rename(path)
        part.chunk_bytes, part.flush_period_s = self.chunk_bytes, self.flush_period_s
        for conn, qos in self.registered:
            if qos is None:
                part.add_msgtype(conn)
            else:
                part.add_connection(conn, qos)
        return part


def _with_distro(metadata: str) -> str:
    """Rosbags writes ``ros_distro: rosbags``; name the sourced ROS 2 distro when there is one."""
    distro = os.environ.get('ROS_DISTRO', '').strip()
    return metadata.replace('ros_distro: rosbags', f'ros_distro: {distro}') if distro else metadata


class _FlushingWriter(Writer):
    """
    rosbags' writer that can split: close the current file and go on in the next one.

    One file ``<name>.mcap`` while never split; after a split the files are named as
    ``ros2 bag record`` names its splits, ``<name>_0.mcap``, ``<name>_1.mcap`` ..., and
    metadata.yaml lists every closed file (the open one is added when it closes).
    """

    STORAGE_PLUGINS = {StoragePlugin.MCAP: _FlushingMcapWriter}

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        #: metadata (rosbag2_bagfile_information) of each closed file, in order
        self.parts: list[dict[str, Any]] = []
        self._last: _FlushingMcapWriter | None = None

    def _part_path(self, k: int) -> Path:
        return self.path / f'{self.path.name}_{k}.mcap'

    def add_connection(self, *args: Any, **kwargs: Any) -> Connection:
        self._reopen()
        return super().add_connection(*args, **kwargs)

    def write(self, connection: Connection, timestamp: int, data: bytes | memoryview) -> None:
        self._reopen()
        super().write(connection, timestamp, data)

    def split(self) -> None:
        """Close the current file (summary, footer) and list it in metadata.yaml."""
        if self.storage is None or not any(self.counts.values()):
            return                  # nothing written since the last split: no empty file
        self._close_part()

    def close(self) -> None:
        if self.storage is None:
            return                  # closed at a split, nothing written since
        if not self.parts:
            super().close()
            self.metapath.write_text(_with_distro(self.metapath.read_text('utf8')), 'utf8')
            return
        self._close_part()

    def _close_part(self) -> None:
        storage = self.storage
        assert isinstance(storage, _FlushingMcapWriter)
        if not self.parts:
            storage.rename(self._part_path(0))   # the first split renames the file
        self._last = storage
        super().close()            # this file's metadata.yaml, replaced by all files' below
        info = yaml.safe_load(self.metapath.read_text('utf8'))['rosbag2_bagfile_information']
        self.parts.append(info)
        text = yaml.safe_dump({'rosbag2_bagfile_information': _merged(self.parts)},
                              sort_keys=False)
        tmp = self.metapath.with_suffix('.yaml.tmp')
        tmp.write_text(_with_distro(text), 'utf8')
        tmp.replace(self.metapath)
        self.counts = {k: 0 for k in self.counts}
        self.min_timestamp, self.max_timestamp = 2**63 - 1, 0

    def _reopen(self) -> None:
        if self.storage is None and self.parts:
            self.storage = self._last.next_part(self._part_path(len(self.parts)))


def _merged(parts: list[dict[str, Any]]) -> dict[str, Any]:
    """Return the metadata of a bag made of the files whose own metadata are ``parts``."""
    out = dict(parts[-1])
    start = min(p['starting_time']['nanoseconds_since_epoch'] for p in parts)
    end = max(p['starting_time']['nanoseconds_since_epoch'] + p['duration']['nanoseconds']
              for p in parts)
    counts: dict[str, dict[str, Any]] = {}
    for p in parts:
        for entry in p['topics_with_message_count']:
            name = entry['topic_metadata']['name']
            if name in counts:
                counts[name]['message_count'] += entry['message_count']
            else:
                counts[name] = dict(entry)
    out.update(relative_file_paths=[f for p in parts for f in p['relative_file_paths']],
               files=[f for p in parts for f in p['files']],
               starting_time={'nanoseconds_since_epoch': start},
               duration={'nanoseconds': end - start},
               message_count=sum(p['message_count'] for p in parts),
               topics_with_message_count=list(counts.values()))
    return out


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
        self._writer: _FlushingWriter | None = None
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
            writer = _FlushingWriter(path, version=9, storage_plugin=StoragePlugin.MCAP)
            writer.open()
        except OSError as err:       # a file on the way, no permission, a read-only disk
            on_way = next((p for p in path.parents if p.exists()), None)
            why = (f'{on_way} is a file, not a directory' if on_way and not on_way.is_dir()
                   else err.strerror or str(err))
            raise BagError(f'bag path {str(path)!r} cannot be created: {why}') from err
        storage = writer.storage
        assert isinstance(storage, _FlushingMcapWriter)
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
        assert isinstance(storage, _FlushingMcapWriter)
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


# --------------------------------------------------------------------------- dict -> CDR

def serialize_dict(msg_type: str, fields: Mapping[str, Any]) -> bytes:
    """CDR bytes of ``msg_type`` built from a (possibly nested, partial) dict of fields."""
    ts = typestore()
    try:
        msg = _build(ts, msg_type, fields)
        return bytes(ts.serialize_cdr(msg, msg_type))
    except BagError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise BagError(f'cannot serialise {msg_type=} from {sorted(fields)}: {exc}') from None


_BASE_DTYPES = {'float64': 'f8', 'float32': 'f4', 'int8': 'i1', 'uint8': 'u1', 'int16': 'i2',
                'uint16': 'u2', 'int32': 'i4', 'uint32': 'u4', 'int64': 'i8', 'uint64': 'u8',
                'byte': 'u1', 'char': 'u1', 'bool': 'bool'}


def _build(ts: Typestore, msg_type: str, d: Mapping[str, Any]) -> Any:
    if msg_type not in ts.fielddefs:
        raise BagError(f'unknown message type {msg_type=}')
    cls = ts.types[msg_type]
    kwargs = {name: _value(ts, spec, d.get(name)) for name, spec in ts.fielddefs[msg_type][1]}
    unknown = set(d) - set(kwargs)
    if unknown:
        raise BagError(f'{msg_type} has no field(s) {sorted(unknown)}')
    return cls(**kwargs)


def _value(ts: Typestore, spec: tuple[Any, Any], v: Any) -> Any:
    kind, arg = spec
    kind = int(kind)
    if kind == 2:  # NAME: nested message
        return _build(ts, arg, v or {})
    if kind == 1:  # BASE
        base = arg[0]
        if base == 'string':
            return '' if v is None else str(v)
        if base == 'bool':
            return bool(v)
        return (float(v) if v is not None else 0.0) if base.startswith('float') else int(v or 0)
    elem, _ = arg  # ARRAY (3) / SEQUENCE (4)
    items = [] if v is None else v
    if int(elem[0]) == 1 and elem[1][0] in _BASE_DTYPES:
        return np.asarray(items, dtype=_BASE_DTYPES[elem[1][0]])
    return [_value(ts, elem, x) for x in items]
