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
Where a bag's data is: its MCAP files, metadata.yaml and rosbag2 compression.

The counterpart of rosbags' storage layer: :func:`locate` resolves a bag directory (with or
without metadata.yaml) or a bare .mcap into :class:`BagFiles`; :func:`readable` and
:func:`decompressed` undo rosbag2's own file and message compression; :func:`expected_counts`
gives the message counts the metadata or MCAP summaries promise.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
import shutil
import tempfile
from typing import Any, Iterator

from frf_ident.errors import BagError
import yaml

from .mcapio import Batch, read_summary, zstd_module


@dataclass
class BagFiles:
    """
    Where a bag's data is: MCAP files in order, plus metadata.yaml contents if present.

    ``compression`` is rosbag2's own compression from metadata.yaml ('' none, 'file': each
    file is a zstd-compressed MCAP, 'message': each message's data is zstd-compressed);
    MCAP chunk compression (zstd, lz4) is the scanner's business and needs nothing here.

    Parameters
    ----------
    path : Path
        The bag as given: a bag directory or a bare .mcap file.
    files : list of Path
        The MCAP files of the bag, in reading order.
    metadata : dict, optional
        Contents of metadata.yaml; None when the bag has none.
    compression : str, optional
        rosbag2 compression mode: '' (none, default), 'file' or 'message'.

    """

    path: Path
    files: list[Path]
    metadata: dict[str, Any] | None = None
    compression: str = ''

    @property
    def name(self) -> str:
        """Display name for messages."""
        return str(self.path)


def _compression(meta_path: Path, info: dict[str, Any]) -> str:
    """rosbag2's compression mode of a bag ('', 'file', 'message'); other formats refused."""
    mode = str(info.get('compression_mode') or '').strip().lower()
    fmt = str(info.get('compression_format') or '').strip().lower()
    if mode in ('', 'none') or not fmt:
        return ''
    if fmt != 'zstd' or mode not in ('file', 'message'):
        raise BagError(f'{meta_path}: compression {fmt!r} in mode {mode!r} is not supported; '
                       f'expected zstd in file or message mode (or MCAP chunk compression)')
    return mode


@contextmanager
def readable(bag: BagFiles, f: Path) -> Iterator[Path]:
    """
    Yield a readable MCAP path for one file of a bag.

    An MCAP path for the file ``f`` of ``bag``: itself, or (rosbag2 file compression) a
    temporary decompressed copy, streamed so memory stays bounded.
    """
    if bag.compression != 'file':
        yield f
        return
    with tempfile.TemporaryDirectory(prefix='frf_bag_') as tmp:
        out = Path(tmp) / f.name.removesuffix('.zstd')
        try:
            with zstd_module().open(f, 'rb') as src, out.open('wb') as dst:
                shutil.copyfileobj(src, dst, 1 << 20)
        except (OSError, ValueError, EOFError) as exc:
            raise BagError(f'{f}: not a readable zstd-compressed file ({type(exc).__name__}: '
                           f'{exc})') from None
        yield out


def decompressed(batch: Batch) -> Batch:
    """
    Decompress the messages of a batch.

    Each message of the batch is zstd-compressed (rosbag2 message compression).
    """
    dec = zstd_module()
    mv = memoryview(batch.buf)
    parts, starts, ends, pos = [], [], [], 0
    for a, b in zip(batch.starts, batch.ends):
        try:
            data = dec.decompress(mv[a:b])
        except Exception as exc:     # the zstd module raises its own ZstdError
            raise BagError(f'{batch.channel.topic}: a message near log time '
                           f'{batch.logs[0] * 1e-9:.6f} s is not zstd-compressed data '
                           f'({type(exc).__name__}) although metadata.yaml says message '
                           f'compression') from None
        parts.append(data)
        starts.append(pos)
        pos += len(data)
        ends.append(pos)
    return Batch(batch.channel, b''.join(parts), batch.logs, starts, ends)


def locate(path: str | Path) -> BagFiles:
    """
    Resolve a bag directory, a bag directory without metadata.yaml, or a bare .mcap.

    Parameters
    ----------
    path : str or Path
        rosbag2 directory (with or without metadata.yaml) or a bare .mcap file.

    Returns
    -------
    BagFiles
        The bag's MCAP files in order, with metadata.yaml contents and compression mode.

    Raises
    ------
    BagError
        The path does not exist, its storage is not MCAP, or it holds no MCAP file.

    """
    p = Path(path)
    if not p.exists():
        raise BagError(f'bag {str(p)!r} does not exist')
    if p.is_file():
        return BagFiles(p, [p])
    meta_path = p / 'metadata.yaml'
    if meta_path.is_file():
        info = _load_metadata(meta_path)
        storage = info.get('storage_identifier', 'mcap')
        if storage != 'mcap':
            raise BagError(f'{meta_path}: storage_identifier {storage!r} is not supported; '
                           f'expected mcap')
        compression = _compression(meta_path, info)
        rel = info.get('relative_file_paths') or []
        files = [p / str(f) for f in rel if (p / str(f)).is_file()]
        if not files:
            files = sorted(p.glob('*.mcap.zstd' if compression == 'file' else '*.mcap'))
        if not files:
            raise BagError(f'{meta_path}: none of the files {rel} exist in {str(p)!r}')
        return BagFiles(p, files, info, compression)
    files = sorted(p.glob('*.mcap'))
    if not files:
        raise BagError(f'bag directory {str(p)!r} holds neither metadata.yaml nor an .mcap file')
    return BagFiles(p, files)


def _load_metadata(meta_path: Path) -> dict[str, Any]:
    try:
        doc = yaml.safe_load(meta_path.read_text(encoding='utf-8'))
        info = doc['rosbag2_bagfile_information']
        if not isinstance(info, dict):
            raise TypeError('not a mapping')
    except (OSError, yaml.YAMLError, KeyError, TypeError, UnicodeDecodeError) as exc:
        raise BagError(f'{meta_path}: not a rosbag2 metadata.yaml (expected key '
                       f'rosbag2_bagfile_information): {type(exc).__name__}') from None
    return info


def _metadata_counts(meta: dict[str, Any] | None) -> dict[str, int]:
    out: dict[str, int] = {}
    try:
        for entry in (meta or {}).get('topics_with_message_count') or []:
            out[str(entry['topic_metadata']['name'])] = int(entry['message_count'])
    except (KeyError, TypeError, ValueError):
        return {}
    return out


def expected_counts(bag: BagFiles) -> dict[str, int]:
    """Message count per topic from metadata.yaml, else from the MCAP summaries (or {})."""
    counts = _metadata_counts(bag.metadata)
    if counts:
        return counts
    for f in bag.files:
        summ = read_summary(f)
        if summ is None:
            return {}
        chans, per_channel, _, _ = summ
        for cid, ch in chans.items():
            counts[ch.topic] = counts.get(ch.topic, 0) + per_channel.get(cid, 0)
    return counts


__all__ = ['BagFiles', 'decompressed', 'expected_counts', 'locate', 'readable']
