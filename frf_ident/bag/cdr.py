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
Hand-rolled little-endian CDR (XCDR1) codecs for the few message types frf_ident bags hold.

Why: per message, rosbags' generic ``deserialize_cdr`` builds Python objects for every field;
these codecs read exactly what the reader needs with ``struct.unpack_from`` and reuse the
decoded joint names while consecutive messages carry the same ``frame_id`` and ``name`` bytes
(the normal case), which makes reading several times faster (``benchmarks.bag_read``). The
byte layout is tested against rosbags' ``serialize_cdr``/``deserialize_cdr`` in test/bag.

Alignment is counted from the byte after the 4-byte encapsulation header; sequences of float64
are 8-aligned only when non-empty, as rosbags and rmw do.
"""
from __future__ import annotations

from functools import lru_cache
import struct
from typing import Sequence

import numpy as np

from .structs import U32

_HDR_LE = b'\x00\x01\x00\x00'
_STAMP = struct.Struct('<iI')


class CdrError(ValueError):
    """A serialized message is malformed (truncated, bad length, not little-endian CDR)."""


@lru_cache(maxsize=64)
def _doubles(n: int) -> struct.Struct:
    return struct.Struct(f'<{n}d')


def _align(off: int, n: int) -> int:
    """Align absolute offset ``off`` (header included) to ``n`` bytes of the CDR body."""
    rel = off - 4
    return off + (-rel % n)


def _check_header(data: bytes | memoryview) -> None:
    if len(data) < 8:
        raise CdrError(f'message of {len(data)} bytes is too short for CDR')
    if bytes(data[:2]) != _HDR_LE[:2]:
        raise CdrError(f'encapsulation {bytes(data[:4]).hex()} is not little-endian CDR (00 01)')


def _read_string(data: bytes | memoryview, off: int) -> tuple[str, int]:
    off = _align(off, 4)
    (n,) = U32.unpack_from(data, off)
    off += 4
    if n == 0 or off + n > len(data):
        raise CdrError(f'string length {n} at byte {off - 4} exceeds the message')
    try:
        text = bytes(data[off:off + n - 1]).decode('utf-8')
    except UnicodeDecodeError as exc:
        raise CdrError(f'string at byte {off} is not UTF-8') from exc
    return text, off + n


def _read_doubles(data: bytes | memoryview, off: int) -> tuple[tuple[float, ...], int]:
    off = _align(off, 4)
    (n,) = U32.unpack_from(data, off)
    off += 4
    if n == 0:
        return (), off
    off = _align(off, 8)
    if off + 8 * n > len(data):
        raise CdrError(f'float64 sequence of {n} at byte {off} exceeds the message')
    return _doubles(n).unpack_from(data, off), off + 8 * n


class JointStateDecoder:
    """
    Decode ``sensor_msgs/msg/JointState`` CDR into stamp, names and value tuples.

    Keeps the names of the previous message: if the next message starts with the same bytes
    up to the end of its ``name`` sequence, the names are not decoded again.
    """

    def __init__(self) -> None:
        self._prefix: bytes = b''
        self._names: tuple[str, ...] = ()

    def decode(self, data: bytes | memoryview) -> tuple[int, tuple[str, ...], tuple[
            tuple[float, ...], tuple[float, ...], tuple[float, ...]]]:
        """Return ``(stamp_ns, names, (position, velocity, effort))``; raise CdrError."""
        try:
            _check_header(data)
            sec, nsec = _STAMP.unpack_from(data, 4)
            plen = len(self._prefix)
            if plen and data[12:12 + plen] == self._prefix:
                names, off = self._names, 12 + plen
            else:
                names, off = self._decode_names(data)
            pos, off = _read_doubles(data, off)
            vel, off = _read_doubles(data, off)
            eff, off = _read_doubles(data, off)
        except struct.error as exc:
            raise CdrError(f'truncated JointState ({len(data)} bytes)') from exc
        return sec * 1_000_000_000 + nsec, names, (pos, vel, eff)

    def _decode_names(self, data: bytes | memoryview) -> tuple[tuple[str, ...], int]:
        _, off = _read_string(data, 12)  # header.frame_id
        off = _align(off, 4)
        (n,) = U32.unpack_from(data, off)
        off += 4
        if n > (len(data) - off) // 5:
            raise CdrError(f'name count {n} exceeds the message')
        names = []
        for _ in range(n):
            name, off = _read_string(data, off)
            names.append(name)
        self._names = tuple(names)
        self._prefix = bytes(data[12:off])
        return self._names, off


def _float64_array_layout(data: bytes | memoryview) -> tuple[int, int]:
    """(data_start, count) of the ``data`` field of a Float64MultiArray."""
    try:
        _check_header(data)
        (ndim,) = U32.unpack_from(data, 4)
        off = 8
        if ndim > len(data) // 12:
            raise CdrError(f'layout.dim count {ndim} exceeds the message')
        for _ in range(ndim):
            _, off = _read_string(data, off)
            off = _align(off, 4) + 8  # size, stride
        off = _align(off, 4) + 4  # data_offset
        start, n, _ = _doubles_layout(data, off)
    except struct.error as exc:
        raise CdrError(f'truncated Float64MultiArray ({len(data)} bytes)') from exc
    return start, n


def decode_float64_array(data: bytes | memoryview) -> tuple[float, ...]:
    """Return the ``data`` field of a ``std_msgs/msg/Float64MultiArray`` (layout skipped)."""
    start, n = _float64_array_layout(data)
    return _doubles(n).unpack_from(data, start) if n else ()


def decode_string(data: bytes | memoryview) -> str:
    """Return the ``data`` field of a ``std_msgs/msg/String``."""
    try:
        _check_header(data)
        text, _ = _read_string(data, 4)
    except struct.error as exc:
        raise CdrError(f'truncated String ({len(data)} bytes)') from exc
    return text


# --------------------------------------------------------------------------- encoders

def _pad(buf: bytearray, n: int) -> None:
    buf.extend(b'\x00' * (-(len(buf) - 4) % n))


def _put_string(buf: bytearray, text: str) -> None:
    raw = text.encode('utf-8') + b'\x00'
    _pad(buf, 4)
    buf.extend(U32.pack(len(raw)))
    buf.extend(raw)


def _put_doubles(buf: bytearray, values: np.ndarray | Sequence[float]) -> None:
    arr = np.ascontiguousarray(values, dtype='<f8')
    _pad(buf, 4)
    buf.extend(U32.pack(arr.size))
    if arr.size:
        _pad(buf, 8)
        buf.extend(arr.tobytes())


class JointStateEncoder:
    """Encode JointState messages with fixed names and frame_id (the names part is cached)."""

    def __init__(self, names: Sequence[str], frame_id: str = '') -> None:
        buf = bytearray(_HDR_LE + b'\x00' * 8)
        _put_string(buf, frame_id)
        _pad(buf, 4)
        buf.extend(U32.pack(len(names)))
        for name in names:
            _put_string(buf, name)
        self._tail = bytes(buf[12:])

    def encode(self, stamp_ns: int, position: Sequence[float] | np.ndarray,
               velocity: Sequence[float] | np.ndarray,
               effort: Sequence[float] | np.ndarray) -> bytes:
        """CDR bytes of one JointState with header.stamp = ``stamp_ns``."""
        sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
        buf = bytearray(_HDR_LE)
        buf.extend(_STAMP.pack(sec, nsec))
        buf.extend(self._tail)
        for values in (position, velocity, effort):
            _put_doubles(buf, values)
        return bytes(buf)


def encode_float64_array(values: Sequence[float] | np.ndarray) -> bytes:
    """CDR bytes of a Float64MultiArray with an empty layout."""
    buf = bytearray(_HDR_LE + b'\x00' * 8)  # dim=[], data_offset=0
    _put_doubles(buf, values)
    return bytes(buf)


def encode_string(text: str) -> bytes:
    """CDR bytes of a std_msgs/msg/String."""
    buf = bytearray(_HDR_LE)
    _put_string(buf, text)
    return bytes(buf)


# --------------------------------------------------------------------------- batch decoders

def _all_of_length(starts: Sequence[int], ends: Sequence[int], length: int) -> bool:
    """Whether every message ``buf[starts[i]:ends[i]]`` is ``length`` bytes long."""
    return bool(np.all(np.subtract(ends, starts) == length))


def _gather(buf: bytes, starts: Sequence[int], length: int) -> np.ndarray:
    """(m, length) uint8 matrix of the equally long messages starting at ``starts``."""
    raw = np.frombuffer(buf, dtype=np.uint8)
    return raw[np.asarray(starts, dtype=np.intp)[:, None] + np.arange(length)]


def _same_structure(rows: np.ndarray, first: np.ndarray, data_regions: list[tuple[int, int]],
                    skip: tuple[int, int] | None) -> bool:
    """All rows equal ``first`` outside the float regions (and the stamp bytes ``skip``)."""
    mask = np.ones(first.size, dtype=bool)
    for a, b in data_regions:
        mask[a:b] = False
    if skip is not None:
        mask[skip[0]:skip[1]] = False
    return bool(np.all(rows[:, mask] == first[mask]))


def _doubles_layout(data: bytes | memoryview, off: int) -> tuple[int, int, int]:
    """(data_start, count, next_offset) of a float64 sequence at ``off``."""
    off = _align(off, 4)
    (n,) = U32.unpack_from(data, off)
    off += 4
    if n == 0:
        return off, 0, off
    off = _align(off, 8)
    if off + 8 * n > len(data):
        raise CdrError(f'float64 sequence of {n} at byte {off} exceeds the message')
    return off, n, off + 8 * n


def decode_joint_state_batch(buf: bytes, starts: Sequence[int], ends: Sequence[int]) -> tuple[
        np.ndarray, tuple[str, ...], list[np.ndarray]] | None:
    """
    Vectorised decode of JointStates that share names, frame_id and array lengths.

    Returns ``(stamps_ns (m,), names, [position, velocity, effort] each (m, count))`` or
    None when the messages differ in structure (the caller then decodes one by one).
    """
    length = ends[0] - starts[0]
    if not _all_of_length(starts, ends, length):
        return None
    first_mv = memoryview(buf)[starts[0]:ends[0]]
    try:
        _check_header(first_mv)
        names, off = JointStateDecoder()._decode_names(first_mv)
        regions = []
        for _ in range(3):
            a, n, off = _doubles_layout(first_mv, off)
            regions.append((a, a + 8 * n))
    except struct.error as exc:
        raise CdrError(f'truncated JointState ({length} bytes)') from exc
    rows = _gather(buf, starts, length)
    if not _same_structure(rows, rows[0], regions, (4, 12)):
        return None
    sec = rows[:, 4:8].copy().view('<i4')[:, 0].astype(np.int64)
    nsec = rows[:, 8:12].copy().view('<u4')[:, 0].astype(np.int64)
    arrays = [rows[:, a:b].copy().view('<f8') for a, b in regions]
    return sec * 1_000_000_000 + nsec, names, arrays


def decode_float64_array_batch(buf: bytes, starts: Sequence[int],
                               ends: Sequence[int]) -> np.ndarray | None:
    """Vectorised ``data`` of equally shaped Float64MultiArrays, (m, n); None if they differ."""
    length = ends[0] - starts[0]
    if not _all_of_length(starts, ends, length):
        return None
    start, n = _float64_array_layout(memoryview(buf)[starts[0]:ends[0]])
    rows = _gather(buf, starts, length)
    if not _same_structure(rows, rows[0], [(start, start + 8 * n)], None):
        return None
    return rows[:, start:start + 8 * n].copy().view('<f8')
