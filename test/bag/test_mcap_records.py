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
The compiled walk over a chunk's records against the record-by-record reading of the spec.

``McapScanner._records`` walks the record headers of a chunk body in compiled code and sorts
each stretch of messages to its channels at once. The reference here reads the body one
record after the other, as https://mcap.dev/spec lays it out (opcode u8, length u64, body;
message: channel u16, sequence u32, log time u64, publish time u64, data). On intact and on
cut or corrupted bodies both must yield the same messages per channel, count the same
messages and end on the same error.
"""
from __future__ import annotations

import struct

from frf_ident.bag.mcapio import McapFormatError, McapScanner
from hypothesis import given, settings
from hypothesis import strategies as st


def _rec(op: int, body: bytes) -> bytes:
    return struct.pack('<BQ', op, len(body)) + body


def _s(text: str) -> bytes:
    raw = text.encode()
    return struct.pack('<I', len(raw)) + raw


def _schema(sid: int) -> bytes:
    return _rec(3, struct.pack('<H', sid) + _s('sensor_msgs/msg/JointState') + _s('ros2msg')
                + struct.pack('<I', 0))


def _channel(cid: int, topic: str) -> bytes:
    return _rec(4, struct.pack('<HH', cid, 1) + _s(topic) + _s('cdr') + struct.pack('<I', 0))


def _message(cid: int, log: int, payload: bytes) -> bytes:
    return _rec(5, struct.pack('<HIQQ', cid, 0, log, log) + payload)


def _reference(buf: bytes, wanted_topics: set[str]):
    """Read the body record by record; return (per-topic messages, message count, error)."""
    scan = McapScanner('unused.mcap', topics=wanted_topics)   # its schema/channel parsers
    out: dict[str, list[tuple[int, bytes]]] = {}
    count, off = 0, 0
    try:
        while off < len(buf):
            if off + 9 > len(buf):
                raise McapFormatError(f'record header cut at chunk byte {off}')
            op, length = struct.unpack_from('<BQ', buf, off)
            body, off = off + 9, off + 9 + length
            if off > len(buf) or (op == 5 and length < 22):
                raise McapFormatError(f'record of {length} bytes overruns its chunk')
            if op == 5:
                cid, _, log, _ = struct.unpack_from('<HIQQ', buf, body)
                count += 1
                if cid not in scan._wanted:
                    raise McapFormatError(f'message on unknown channel {cid}')
                info = scan._wanted[cid]
                if info is not None:
                    out.setdefault(info.topic, []).append((log, bytes(buf[body + 22:off])))
            elif op == 3:
                scan._on_schema(memoryview(buf)[body:off])
            elif op == 4:
                scan._on_channel(memoryview(buf)[body:off])
    except (McapFormatError, struct.error, UnicodeDecodeError) as exc:
        return out, count, f'{type(exc).__name__}: {exc}'
    return out, count, None


def _compiled(buf: bytes, wanted_topics: set[str]):
    scan = McapScanner('unused.mcap', topics=wanted_topics)
    out: dict[str, list[tuple[int, bytes]]] = {}
    error = None
    try:
        for batch in scan._records(buf):
            out.setdefault(batch.channel.topic, []).extend(
                (log, bytes(batch.buf[a:b]))
                for log, a, b in zip(batch.logs, batch.starts, batch.ends))
    except (McapFormatError, struct.error, UnicodeDecodeError) as exc:
        error = f'{type(exc).__name__}: {exc}'
    return out, scan.stats.messages, error


@st.composite
def chunk_bodies(draw):
    """Return a chunk body of schema, channel and message records, possibly cut or corrupted."""
    parts = [_schema(1)]
    defined: list[int] = []
    for _ in range(draw(st.integers(1, 40))):
        kind = draw(st.sampled_from(['channel', 'message', 'message', 'message']))
        if kind == 'channel' or not defined:
            cid = draw(st.integers(1, 4))
            parts.append(_channel(cid, f'/topic_{cid}'))
            defined.append(cid)
        else:
            unknown = draw(st.integers(0, 30)) == 0
            cid = 9 if unknown else draw(st.sampled_from(defined))
            parts.append(_message(cid, draw(st.integers(0, 2 ** 62)),
                                  draw(st.binary(max_size=12))))
    buf = bytearray(b''.join(parts))
    damage = draw(st.sampled_from(['none', 'cut', 'flip']))
    if damage == 'cut':
        buf = buf[:draw(st.integers(0, len(buf)))]
    elif damage == 'flip' and buf:
        at = draw(st.integers(0, len(buf) - 1))
        buf[at] = draw(st.integers(0, 255))
    return bytes(buf)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(body=chunk_bodies(), wanted=st.sets(st.sampled_from(['/topic_1', '/topic_2',
                                                           '/topic_3', '/topic_4'])))
def test_compiled_record_walk_reads_like_the_spec(body: bytes, wanted: set[str]) -> None:
    """Same messages per wanted channel, same count, same error as record-by-record."""
    assert _compiled(body, wanted) == _reference(body, wanted)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(body=chunk_bodies(), wanted=st.sets(st.sampled_from(['/topic_1', '/topic_2'])))
def test_messages_outside_chunks_read_like_the_spec(tmp_path_factory, body: bytes,
                                                    wanted: set[str]) -> None:
    """The same records as top-level records of a file (no chunks): the same messages."""
    expected, count, error = _reference(body, wanted)
    if error is not None:
        return                   # a damaged top-level record is counted lost, not raised
    path = tmp_path_factory.mktemp('mcap') / 'plain.mcap'
    path.write_bytes(b'\x89MCAP0\r\n' + _rec(1, _s('') + _s('')) + body + _rec(0x0F, b'\0' * 4)
                     + _rec(2, b'\0' * 20) + b'\x89MCAP0\r\n')
    scan = McapScanner(path, topics=wanted)
    got: dict[str, list[tuple[int, bytes]]] = {}
    for batch in scan.batches():
        pairs = zip(batch.logs, batch.starts, batch.ends)
        got.setdefault(batch.channel.topic, []).extend(
            (log, bytes(batch.buf[a:b])) for log, a, b in pairs)
    assert got == expected and scan.stats.messages == count and not scan.stats.problems
