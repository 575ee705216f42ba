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
rosbags' MCAP writer with the chunk CRC filled in, small flushed chunks, and splits.

:class:`CrcWriter` writes a finished bag (the chunk CRC that rosbags leaves 0, so a reader can
drop a damaged chunk alone); :class:`FlushingWriter` records incrementally: small chunks handed
to the OS as soon as closed (:class:`FlushingMcapWriter`), and splits named and listed in
metadata.yaml as ``ros2 bag record`` names and lists them.
"""
from __future__ import annotations

import os
from pathlib import Path
import struct
import time
from typing import Any
import zlib

from rosbags.interfaces import Connection
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.storage_mcap import McapWriter
import yaml

__all__ = ['CrcWriter', 'FlushingMcapWriter', 'FlushingWriter']


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


class CrcWriter(Writer):
    """rosbags' writer whose MCAP storage fills in the chunk CRC."""

    STORAGE_PLUGINS = {StoragePlugin.MCAP: _CrcMcapWriter}


class FlushingMcapWriter(_CrcMcapWriter):
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

    def next_part(self, path: Path) -> 'FlushingMcapWriter':
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


class FlushingWriter(Writer):
    """
    rosbags' writer that can split: close the current file and go on in the next one.

    One file ``<name>.mcap`` while never split; after a split the files are named as
    ``ros2 bag record`` names its splits, ``<name>_0.mcap``, ``<name>_1.mcap`` ..., and
    metadata.yaml lists every closed file (the open one is added when it closes).
    """

    STORAGE_PLUGINS = {StoragePlugin.MCAP: FlushingMcapWriter}

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        #: metadata (rosbag2_bagfile_information) of each closed file, in order
        self.parts: list[dict[str, Any]] = []
        self._last: FlushingMcapWriter | None = None

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
        assert isinstance(storage, FlushingMcapWriter)
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
