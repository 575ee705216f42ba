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
A small, streaming, fault-tolerant MCAP record scanner (read side only).

Why not ``mcap.reader``: its seeking reader needs an intact summary section and its stream
reader raises on the first damaged byte and parses each message into an object. A recorder
that was killed leaves a file without summary and footer, and fuzzed/corrupt files must end
in a ``BagError``, never a traceback. This scanner walks the data section record by record
(reading one record, i.e. at most one chunk, at a time: memory is bounded by the chunk size),
validates lengths against the file size and chunk CRCs when present, skips a damaged chunk
whose framing is intact, resumes after a damaged record frame at the next chunk the summary
indexes (or stops there without an intact summary), and counts what was lost.

Spec: https://mcap.dev/spec (records, opcodes, field order).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
import struct
from typing import BinaryIO, Callable, Iterator
import zlib

import numba
import numpy as np

from .structs import U16, U32, U64

MAGIC = b'\x89MCAP0\r\n'
OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK = 1, 2, 3, 4, 5, 6
OP_CHUNK_INDEX, OP_STATISTICS, OP_METADATA, OP_DATA_END = 0x08, 0x0B, 0x0C, 0x0F
_REC = struct.Struct('<BQ')
_MSG = struct.Struct('<HIQQ')
_CHUNK = struct.Struct('<QQQI')
#: chunks (uncompressed) larger than this are treated as corrupt rather than allocated.
MAX_CHUNK_BYTES = 1 << 30


class McapFormatError(ValueError):
    """The file is not MCAP or its framing is damaged beyond recovery."""


@dataclass
class ChannelInfo:
    """One MCAP channel (a rosbag2 topic connection)."""

    id: int  # noqa: A003
    topic: str
    msgtype: str
    encoding: str
    metadata: dict[str, str] = field(default_factory=dict)


@dataclass
class Batch:
    """Messages of one channel from one chunk: ``buf[starts[i]:ends[i]]`` is message i."""

    channel: ChannelInfo
    buf: bytes
    logs: list[int]
    starts: list[int]
    ends: list[int]


@dataclass
class ScanStats:
    """What a scan read and what it had to give up on."""

    file_bytes: int = 0
    bytes_ok: int = 0
    bytes_lost: int = 0
    messages: int = 0
    chunks_ok: int = 0
    chunks_lost: int = 0
    complete: bool = False  # footer and trailing magic seen
    problems: list[str] = field(default_factory=list)
    topics: dict[str, str] = field(default_factory=dict)  # topic -> type of every channel


def _string(buf: bytes | memoryview, off: int) -> tuple[str, int]:
    (n,) = U32.unpack_from(buf, off)
    off += 4
    if off + n > len(buf):
        raise McapFormatError(f'string of {n} bytes overruns its record')
    return bytes(buf[off:off + n]).decode('utf-8'), off + n


def _bytes(buf: bytes | memoryview, off: int) -> tuple[bytes, int]:
    (n,) = U32.unpack_from(buf, off)
    off += 4
    if off + n > len(buf):
        raise McapFormatError(f'byte field of {n} bytes overruns its record')
    return bytes(buf[off:off + n]), off + n


def _string_map(buf: bytes | memoryview, off: int) -> tuple[dict[str, str], int]:
    (n,) = U32.unpack_from(buf, off)
    off += 4
    end = off + n
    if end > len(buf):
        raise McapFormatError(f'map of {n} bytes overruns its record')
    out: dict[str, str] = {}
    while off < end:
        key, off = _string(buf, off)
        out[key], off = _string(buf, off)
    return out, end


def zstd_module():
    """Return the zstd module: ``compression.zstd`` (Python >= 3.14) or its backport."""
    try:
        from compression import zstd  # type: ignore[import-not-found]  # Python >= 3.14
    except ImportError:
        from backports import zstd
    return zstd


def _decompress(compression: str, data: bytes, size: int) -> bytes:
    if size > MAX_CHUNK_BYTES:
        raise McapFormatError(f'chunk claims {size} uncompressed bytes')
    if compression == '':
        return data
    if compression == 'zstd':
        out = zstd_module().ZstdDecompressor().decompress(data, max_length=size)
    elif compression == 'lz4':
        import lz4.frame
        out = lz4.frame.decompress(data)
    else:
        raise McapFormatError(f'unsupported chunk compression {compression!r}')
    if len(out) != size:
        raise McapFormatError(f'chunk decompressed to {len(out)} bytes, header says {size}')
    return out


def _scan_records(b: np.ndarray) -> tuple[np.ndarray, ...]:
    """
    Walk the records of a chunk body: opcode, body start and end; channel, log time of messages.

    Returns (ops, body, ends, channel ids, log times, bad): ``bad`` 0 when the body ends on a
    record boundary; 1 when a record header is cut (its start is the last ``ends``), 2 when
    a record overruns the body or a message record is shorter than its header (the last
    entry is that record). The records are counted first, so the arrays hold them exactly
    (a bound from the body's size would take four times the chunk).
    """
    none, none8 = np.empty(0, np.int64), np.empty(0, np.uint8)
    n, _ = _walk_records(b, False, none8, none, none, none, none)
    ops = np.empty(n, np.uint8)
    body, ends, cids, logs = (np.zeros(n, np.int64) for _ in range(4))
    _, bad = _walk_records(b, True, ops, body, ends, cids, logs)
    return ops, body, ends, cids, logs, bad


@numba.njit(cache=True)
def _walk_records(b, fill, ops, body, ends, cids, logs):
    """Count the records of a chunk body (and with ``fill`` write them); return (n, bad)."""
    end = b.size
    off = 0
    n = 0
    bad = 0
    while off < end:
        if off + 9 > end:
            if fill:
                ops[n], body[n], ends[n] = 0, off, off
            n += 1
            bad = 1
            break
        op = b[off]
        length = 0
        for j in range(8):
            length |= np.int64(b[off + 1 + j]) << (8 * j)
        start = off + 9
        stop = start + length
        if fill:
            ops[n], body[n], ends[n] = op, start, stop
        n += 1
        if length < 0 or stop > end or (length < 22 and op == 5):
            bad = 2
            break
        if fill and op == 5:
            cids[n - 1] = np.int64(b[start]) | (np.int64(b[start + 1]) << 8)
            t = np.int64(0)
            for j in range(8):
                t |= np.int64(b[start + 6 + j]) << (8 * j)
            logs[n - 1] = t
        off = stop
    return n, bad


class McapScanner:
    """
    Stream the messages of one MCAP file in file order, recovering what is readable.

    Use :meth:`messages` once; afterwards :attr:`stats`, :attr:`channels`, :attr:`schemas`
    and :attr:`metadata` describe the file. ``topics`` restricts which messages are yielded
    (channel records are always collected). ``on_bytes`` is called with the number of bytes
    consumed, for progress bars.
    """

    def __init__(self, path: Path | str, topics: set[str] | None = None,
                 on_bytes: Callable[[int], None] | None = None) -> None:
        self.path = Path(path)
        self.topics = topics
        self.on_bytes = on_bytes
        self.channels: dict[int, ChannelInfo] = {}
        self.schemas: dict[int, str] = {}
        self.metadata: dict[str, dict[str, str]] = {}
        self.stats = ScanStats()
        self._wanted: dict[int, ChannelInfo | None] = {}
        self._chunk_starts: list[int] | None = None

    # ------------------------------------------------------------------ records
    def _on_schema(self, buf: bytes | memoryview) -> None:
        (sid,) = U16.unpack_from(buf, 0)
        name, _ = _string(buf, 2)
        self.schemas[sid] = name

    def _on_channel(self, buf: bytes | memoryview) -> None:
        cid, sid = struct.unpack_from('<HH', buf, 0)
        topic, off = _string(buf, 4)
        enc, off = _string(buf, off)
        meta, _ = _string_map(buf, off)
        info = ChannelInfo(cid, topic, self.schemas.get(sid, ''), enc, meta)
        self.channels[cid] = info
        self.stats.topics[topic] = info.msgtype
        wanted = self.topics is None or topic in self.topics
        self._wanted[cid] = info if wanted else None

    def _on_metadata(self, buf: bytes | memoryview) -> None:
        name, off = _string(buf, 0)
        self.metadata[name], _ = _string_map(buf, off)

    def _records(self, buf: bytes) -> Iterator[Batch]:
        """
        Batches (one per wanted channel) of a chunk body; also parses schemas/channels.

        Messages before a damaged record are still yielded; the error is raised afterwards.
        The record headers are walked by :func:`_scan_records` (compiled); schema and
        channel records are parsed here in file order, and each stretch of messages between
        them is sorted to its channels at once.
        """
        batches: dict[int, Batch] = {}
        mv = memoryview(buf)
        ops, body, ends, cids, logs, bad = _scan_records(np.frombuffer(buf, np.uint8))
        error: Exception | None = None
        if bad == 1:
            error = McapFormatError(f'record header cut at chunk byte {ends[-1]}')
        elif bad == 2:
            error = McapFormatError(f'record of {ends[-1] - body[-1]} bytes overruns its '
                                    f'chunk')
        n = ops.size - (1 if bad else 0)
        others = np.flatnonzero(ops[:n] != OP_MESSAGE).tolist() + [n]
        start = 0
        try:
            for k in others:
                msg = np.flatnonzero(ops[start:k] == OP_MESSAGE) + start
                self._sort_messages(buf, batches, msg, body, ends, cids, logs)
                if k < n:
                    if ops[k] == OP_SCHEMA:
                        self._on_schema(mv[body[k]:ends[k]])
                    elif ops[k] == OP_CHANNEL:
                        self._on_channel(mv[body[k]:ends[k]])
                start = k + 1
        except (McapFormatError, struct.error, UnicodeDecodeError) as exc:
            error = exc
        yield from batches.values()
        if error is not None:
            raise error

    def _sort_messages(self, buf: bytes, batches: dict[int, Batch], msg: np.ndarray,
                       body: np.ndarray, ends: np.ndarray, cids: np.ndarray,
                       logs: np.ndarray) -> None:
        """Add message records ``msg`` (indices into the scan) to their channels' batches."""
        if not msg.size:
            return
        wanted = self._wanted
        ch = cids[msg]
        unknown = [c for c in np.unique(ch).tolist() if c not in wanted]
        if unknown:
            first = int(np.flatnonzero(np.isin(ch, unknown))[0])
            self._sort_messages(buf, batches, msg[:first], body, ends, cids, logs)
            self.stats.messages += 1
            raise McapFormatError(f'message on unknown channel {int(ch[first])}')
        self.stats.messages += int(msg.size)
        u, first = np.unique(ch, return_index=True)
        for c in u[np.argsort(first)].tolist():       # channels in the order they appear
            info = wanted[c]
            if info is None:
                continue
            sel = msg[ch == c]
            batch = batches.get(c)
            if batch is None:
                batch = batches[c] = Batch(info, buf, [], [], [])
            batch.logs.extend(logs[sel].tolist())
            batch.starts.extend((body[sel] + 22).tolist())
            batch.ends.extend(ends[sel].tolist())

    def _chunk(self, buf: bytes) -> Iterator[Batch]:
        _, _, size, crc = _CHUNK.unpack_from(buf, 0)
        compression, off = _string(buf, _CHUNK.size)
        (n,) = U64.unpack_from(buf, off)
        off += 8
        if off + n > len(buf):
            raise McapFormatError(f'chunk data of {n} bytes overruns the chunk record')
        data = _decompress(compression, buf[off:off + n], size) if compression else \
            buf[off:off + n]
        if crc and zlib.crc32(data) != crc:
            raise McapFormatError('chunk CRC mismatch')
        yield from self._records(data)

    # ------------------------------------------------------------------ main loop
    def batches(self) -> Iterator[Batch]:
        """
        Yield the wanted messages chunk by chunk, one :class:`Batch` per channel.

        Raises McapFormatError only when not even the MCAP magic is present.
        """
        st = self.stats
        with self.path.open('rb') as f:
            st.file_bytes = f.seek(0, 2)
            f.seek(0)
            if f.read(8) != MAGIC:
                raise McapFormatError('no MCAP magic at the start of the file')
            st.bytes_ok = 8
            yield from self._walk(f)
        st.bytes_lost = st.file_bytes - st.bytes_ok

    def messages(self) -> Iterator[tuple[ChannelInfo, int, memoryview]]:
        """Yield ``(channel, log_time_ns, cdr_bytes)`` for every readable wanted message."""
        for batch in self.batches():
            mv = memoryview(batch.buf)
            for log, a, b in zip(batch.logs, batch.starts, batch.ends):
                yield batch.channel, log, mv[a:b]

    def _walk(self, f: BinaryIO) -> Iterator[Batch]:
        st = self.stats
        pos = 8
        while True:
            head = f.read(9)
            if len(head) < 9:
                if head or not st.complete:
                    st.problems.append(f'file ends inside a record header at byte {pos}'
                                       if head else f'file ends at byte {pos} without footer')
                return
            op, length = _REC.unpack_from(head, 0)
            if length > st.file_bytes - pos - 9:
                problem = (f'record at byte {pos} (opcode 0x{op:02x}) claims {length} bytes, '
                           f'only {st.file_bytes - pos - 9} remain')
                nxt = self._resume_after(pos)
                if nxt is None:
                    st.problems.append(problem)
                    return
                skipped = [c for c in self._chunk_starts or () if pos <= c < nxt]
                st.chunks_lost += len(skipped)
                st.problems.append(f'{problem}: resumed at the next chunk the summary indexes, '
                                   f'byte {nxt} ({len(skipped)} chunk(s) skipped)')
                f.seek(nxt)
                if self.on_bytes:
                    self.on_bytes(nxt - pos)
                pos = nxt
                continue
            if op == OP_DATA_END or op == OP_FOOTER:
                self._finish(f, pos, length)
                return
            if op in (OP_CHUNK, OP_MESSAGE, OP_SCHEMA, OP_CHANNEL, OP_METADATA):
                buf = f.read(length)
                ok = yield from self._top_record(op, buf, pos)
                if ok:
                    st.bytes_ok += 9 + length
            else:  # index/attachment records: not needed, skip without reading them
                f.seek(length, 1)
                st.bytes_ok += 9 + length
            pos += 9 + length
            if self.on_bytes:
                self.on_bytes(9 + length)

    def _resume_after(self, pos: int) -> int | None:
        """
        Return the start of the first chunk after byte ``pos`` that the summary indexes.

        A damaged record frame hides where the next record begins; the summary's chunk
        indexes (when the file has an intact summary) still say where every chunk starts.
        None without an intact summary or a later chunk.
        """
        if self._chunk_starts is None:
            self._chunk_starts = chunk_starts(self.path)
        later = [c for c in self._chunk_starts if c > pos]
        return min(later) if later else None

    def _message(self, buf: bytes) -> Iterator[Batch]:
        """Yield the batch of one message record outside a chunk (if its channel is wanted)."""
        if len(buf) < 22:
            raise McapFormatError(f'record of {len(buf)} bytes overruns its chunk')
        cid, _, log_time, _ = _MSG.unpack_from(buf, 0)
        self.stats.messages += 1
        if cid not in self._wanted:
            raise McapFormatError(f'message on unknown channel {cid}')
        info = self._wanted[cid]
        if info is not None:
            yield Batch(info, buf, [log_time], [22], [len(buf)])

    def _top_record(self, op: int, buf: bytes, pos: int) -> Iterator[Batch]:
        """Process one top-level record; a damaged one is counted as lost (returns False)."""
        try:
            if op == OP_CHUNK:
                yield from self._chunk(buf)
                self.stats.chunks_ok += 1
            elif op == OP_MESSAGE:
                yield from self._message(buf)
            elif op == OP_SCHEMA:
                self._on_schema(buf)
            elif op == OP_CHANNEL:
                self._on_channel(buf)
            else:
                self._on_metadata(buf)
        except (McapFormatError, struct.error, UnicodeDecodeError, ValueError, OSError,
                EOFError, RuntimeError) as exc:
            if op == OP_CHUNK:
                self.stats.chunks_lost += 1
            self.stats.problems.append(f'damaged record at byte {pos} (opcode 0x{op:02x}): {exc}')
            return False
        return True

    def _finish(self, f: BinaryIO, pos: int, length: int) -> None:
        """
        Finish the scan after the data section ended.

        The rest (summary, footer) is intact iff the magic closes it.
        """
        st = self.stats
        st.bytes_ok = st.file_bytes  # summary bytes are not message data
        f.seek(st.file_bytes - 8)
        if f.read(8) == MAGIC:
            st.complete = True
        else:
            st.problems.append('file does not end with the MCAP magic (summary damaged)')


Summary = tuple[dict[int, ChannelInfo], dict[int, int], int, int]


def chunk_starts(path: Path | str) -> list[int]:
    """
    Return the file offsets of the chunks the MCAP summary indexes (ChunkIndex records).

    Empty when the file has no intact summary.
    """
    out = []
    try:
        for op, rec in _summary_records(_summary_bytes(Path(path))):
            if op == OP_CHUNK_INDEX and len(rec) >= 24:
                out.append(int(U64.unpack_from(rec, 16)[0]))
    except (McapFormatError, struct.error, OSError, ValueError):
        pass                          # a damaged summary: the chunks indexed before it
    return sorted(out)


def _summary_records(buf: bytes | None) -> Iterator[tuple[int, memoryview]]:
    """
    Yield (opcode, body) of every record of a summary section (none for None).

    Raises McapFormatError when a record claims more bytes than the section holds.
    """
    off = 0
    while buf is not None and off + 9 <= len(buf):
        op, length = _REC.unpack_from(buf, off)
        body, off = off + 9, off + 9 + length
        if off > len(buf):
            raise McapFormatError(f'summary record (opcode 0x{op:02x}) overruns the section')
        yield op, memoryview(buf)[body:off]


def _summary_bytes(path: Path) -> bytes | None:
    """Return the summary section of an MCAP file whose footer is intact, else None."""
    with path.open('rb') as f:
        size = f.seek(0, 2)
        if size < 8 + 9 + 20 + 8:
            return None
        f.seek(size - 8 - 29)
        tail = f.read(37)
        if tail[-8:] != MAGIC or tail[0] != OP_FOOTER:
            return None
        summary_start, _, _ = struct.unpack_from('<QQI', tail, 9)
        if summary_start == 0 or summary_start >= size - 37:
            return None
        f.seek(summary_start)
        return f.read(size - 37 - summary_start)


def read_summary(path: Path | str) -> Summary | None:
    """
    Channels, per-channel message counts and start/end log time from the MCAP summary.

    Returns None when the file has no intact summary with a statistics record (then the
    caller scans the data section instead).
    """
    try:
        return _read_summary(Path(path))
    except (McapFormatError, struct.error, UnicodeDecodeError, OSError, ValueError):
        return None


def _read_summary(path: Path) -> Summary | None:
    schemas: dict[int, str] = {}
    chans: list[tuple[int, int, str, str, dict[str, str]]] = []
    stats: tuple[dict[int, int], int, int] | None = None
    for op, rec in _summary_records(_summary_bytes(path)):
        if op == OP_SCHEMA:
            (sid,) = U16.unpack_from(rec, 0)
            schemas[sid], _ = _string(rec, 2)
        elif op == OP_CHANNEL:
            cid, sid = struct.unpack_from('<HH', rec, 0)
            topic, o = _string(rec, 4)
            enc, o = _string(rec, o)
            meta, _ = _string_map(rec, o)
            chans.append((cid, sid, topic, enc, meta))
        elif op == OP_STATISTICS:
            t0, t1 = struct.unpack_from('<QQ', rec, 30)
            (n,) = U32.unpack_from(rec, 46)
            counts = {}
            for o in range(50, 50 + n, 10):
                cid, cnt = struct.unpack_from('<HQ', rec, o)
                counts[cid] = cnt
            stats = (counts, t0, t1)
    if stats is None:
        return None
    channels = {cid: ChannelInfo(cid, topic, schemas.get(sid, ''), enc, meta)
                for cid, sid, topic, enc, meta in chans}
    return channels, stats[0], stats[1], stats[2]
