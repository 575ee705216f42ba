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
Read rosbag2 MCAP bags (frf_ident's own or any robot's) into a :class:`Recording`.

Streaming: messages are decoded one MCAP chunk at a time straight into numpy blocks, so
memory is bounded by the output arrays, not by the bag. Damaged or unfinished files are
recovered up to the last intact chunk (see :mod:`frf_ident.bag.mcapio`). Timing is analysed
and repaired by :mod:`frf_ident.bag.timing`. Every problem with the input ends in one
:class:`~frf_ident.errors.BagError` line naming the file, topic or field.
"""
from __future__ import annotations

from contextlib import contextmanager, nullcontext
from dataclasses import dataclass
import json
import math
from operator import itemgetter
from pathlib import Path
import shutil
import struct
import tempfile
from typing import Any, Callable, Iterator

from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import BagError
import numpy as np
import yaml

from . import timing as tm
from .cdr import (CdrError, decode_float64_array, decode_float64_array_batch,
                  decode_joint_state_batch, decode_string, JointStateDecoder)
from .coverage import cut_warning, split_covered
from .mcapio import (Batch, ChannelInfo, McapFormatError, McapScanner, read_summary, ScanStats,
                     zstd_module)
from .pairing import align_effort, effort_lag
from .topics import BagTopics, JOINT_STATE
from .writer import FRF_BAG_KEY, grid_times

_BLOCK = 8192
_NAN = float('nan')


# --------------------------------------------------------------------------- bag layout

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
def _readable(bag: BagFiles, f: Path) -> Iterator[Path]:
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


def _decompressed(batch: Batch) -> Batch:
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


# --------------------------------------------------------------------------- accumulation

class _Table:
    """
    Stamps, log times and value rows of one topic in preallocated, growing numpy arrays.

    Preallocated from the message count in the summary/metadata when known, so memory is the
    output arrays plus one chunk; otherwise capacity doubles as needed.
    """

    def __init__(self, width: int, capacity: int = 0) -> None:
        self.width = width
        self.n = 0
        cap = max(int(capacity), 1024)
        self.stamps = np.empty(cap, dtype=np.int64)
        self.logs = np.empty(cap, dtype=np.int64)
        self.vals = np.empty((cap, width))
        self._rows: list[tuple[float, ...]] = []
        self._rstamps: list[int] = []
        self._rlogs: list[int] = []

    def __len__(self) -> int:
        return self.n + len(self._rows)

    def _reserve(self, m: int) -> None:
        need = self.n + m
        if need <= self.stamps.size:
            return
        cap = max(need, 2 * self.stamps.size)
        for name in ('stamps', 'logs', 'vals'):
            old = getattr(self, name)
            new = np.empty((cap,) + old.shape[1:], dtype=old.dtype)
            new[:self.n] = old[:self.n]
            setattr(self, name, new)

    def add_block(self, stamps: np.ndarray | list[int], logs: np.ndarray | list[int],
                  vals: np.ndarray) -> None:
        self._seal()
        m = len(stamps)
        self._reserve(m)
        self.stamps[self.n:self.n + m] = stamps
        self.logs[self.n:self.n + m] = logs
        self.vals[self.n:self.n + m] = vals
        self.n += m

    def add_row(self, stamp: int, log: int, row: tuple[float, ...]) -> None:
        self._rows.append(row)
        self._rstamps.append(stamp)
        self._rlogs.append(log)
        if len(self._rows) >= _BLOCK:
            self._seal()

    def _seal(self) -> None:
        if self._rows:
            rows, stamps, logs = self._rows, self._rstamps, self._rlogs
            self._rows, self._rstamps, self._rlogs = [], [], []
            vals = np.array(rows, dtype=float).reshape(len(rows), self.width)
            self.add_block(stamps, logs, vals)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        self._seal()
        return self.stamps[:self.n], self.logs[:self.n], self.vals[:self.n]

    def times(self) -> np.ndarray:
        """Return the header stamps of the rows held when valid, else their log times in ns."""
        stamps, logs, _ = self.arrays()
        return stamps if tm.valid_header_stamps(stamps) else logs

    def subset(self, mask: np.ndarray) -> '_Table':
        """Return a new table holding the rows where ``mask`` is true (streaming windows)."""
        stamps, logs, vals = self.arrays()
        out = _Table(self.width, int(np.count_nonzero(mask)))
        out.add_block(stamps[mask], logs[mask], vals[mask])
        return out

    def keep(self, mask: np.ndarray) -> None:
        """Drop the rows where ``mask`` is false, in place (streaming: bounded memory)."""
        stamps, logs, vals = self.arrays()
        m = int(np.count_nonzero(mask))
        self.stamps[:m], self.logs[:m], self.vals[:m] = stamps[mask], logs[mask], vals[mask]
        self.n = m


_FIELDS = ('position', 'velocity', 'effort')


class _JointTable:
    """Maps JointState messages (any joint order, missing joints/interfaces) onto columns."""

    def __init__(self, fields: tuple[int, ...], where: str, capacity: int) -> None:
        self.fields = fields  # which of (position, velocity, effort) to keep
        self.where = where
        self.capacity = capacity
        self.joints: list[str] | None = None
        self.data: _Table | None = None
        self.getters: dict[tuple[str, ...], Callable[[tuple[float, ...]], tuple[float, ...]]] = {}
        self.columns: dict[tuple[str, ...], np.ndarray] = {}
        self.pending: list[tuple[Any, ...]] = []
        self.names_seen: set[str] = set()

    def __len__(self) -> int:
        return len(self.data) if self.data is not None else len(self.pending)

    def select(self, joints: list[str]) -> None:
        self.joints = list(joints)
        self.data = _Table(len(joints) * len(self.fields), self.capacity)
        pending, self.pending = self.pending, []
        for kind, *args in pending:
            (self.add_batch if kind == 'batch' else self.add)(*args)

    def _columns(self, names: tuple[str, ...]) -> np.ndarray:
        cols = self.columns.get(names)
        if cols is None:
            assert self.joints is not None
            pos = {n: i for i, n in enumerate(names)}
            cols = np.array([pos.get(j, len(names)) for j in self.joints], dtype=np.intp)
            self.columns[names] = cols
            self.names_seen.update(names)
        return cols

    def _getter(self, names: tuple[str, ...]) -> Callable[[tuple[float, ...]], tuple[float, ...]]:
        get = self.getters.get(names)
        if get is None:
            idx = [int(i) for i in self._columns(names)]  # len(names) -> appended NaN
            if len(idx) == 1:
                i0 = idx[0]
                get = self.getters[names] = lambda v: (v[i0],)
            else:
                get = self.getters[names] = itemgetter(*idx)
        return get

    def _bad_length(self, f: int, got: int, n: int, stamp: int) -> BagError:
        return BagError(f'{self.where}: JointState {_FIELDS[f]} has {got} values for {n} names '
                        f'at stamp {stamp * 1e-9:.6f} s; expected {n} or none')

    def add(self, stamp: int, log: int, names: tuple[str, ...],
            arrays: tuple[tuple[float, ...], ...]) -> None:
        """One decoded message."""
        if self.data is None:
            self.pending.append(('one', stamp, log, names, arrays))
            return
        get = self._getter(names)
        n = len(names)
        row: tuple[float, ...] = ()
        for f in self.fields:
            vals = arrays[f]
            if len(vals) == n:
                row += get(vals + (_NAN,))
            elif not vals:
                row += get((_NAN,) * (n + 1))
            else:
                raise self._bad_length(f, len(vals), n, stamp)
        self.data.add_row(stamp, log, row)

    def add_batch(self, stamps: np.ndarray, logs: list[int], names: tuple[str, ...],
                  arrays: list[np.ndarray]) -> None:
        """Messages of one chunk sharing names and array lengths (vectorised)."""
        if self.data is None:
            self.pending.append(('batch', stamps, logs, names, arrays))
            return
        cols = self._columns(names)
        n, m = len(names), stamps.size
        present = cols < n
        out = np.full((m, len(cols) * len(self.fields)), np.nan)
        for i, f in enumerate(self.fields):
            vals = arrays[f]
            if vals.shape[1] == n:
                out[:, i * len(cols):(i + 1) * len(cols)][:, present] = vals[:, cols[present]]
            elif vals.shape[1]:
                raise self._bad_length(f, vals.shape[1], n, int(stamps[0]))
        self.data.add_block(stamps, logs, out)


class Collector:
    """Decodes the wanted topics of a scan into tables and events."""

    def __init__(self, bag: BagFiles, topics: BagTopics, joints: list[str] | None,
                 counts: dict[str, int]) -> None:
        self.bag = bag
        self.topics = topics
        self.counts = counts
        self.expected = {t: ty for t, ty in topics.expected_types().items()
                         if t != topics.effort_commands}
        self.js = _JointTable((0, 1, 2), f'{bag.name}: {topics.joint_states}',
                              counts.get(topics.joint_states, 0))
        self.exc = _JointTable((1,), f'{bag.name}: {topics.excitation}',
                               counts.get(topics.excitation, 0))
        if joints:
            self.js.select(list(joints))
            self.exc.select(list(joints))
        self.ref: _Table | None = None
        self.ref_width = -1
        self.events: list[tuple[int, str]] = []
        self.js_first_names: tuple[str, ...] | None = None
        self.checked: set[int] = set()
        self.dec_js = JointStateDecoder()
        self.dec_exc = JointStateDecoder()

    def check_channel(self, ch: ChannelInfo) -> None:
        want = self.expected[ch.topic]
        if ch.msgtype != want:
            raise BagError(f'{self.bag.name}: topic {ch.topic} has type {ch.msgtype or "?"}; '
                           f'expected {want}')
        if ch.encoding != 'cdr':
            raise BagError(f'{self.bag.name}: topic {ch.topic} uses message encoding '
                           f'{ch.encoding!r}; expected cdr')
        self.checked.add(ch.id)

    def feed(self, batch: Batch) -> None:
        ch = batch.channel
        if ch.id not in self.checked:
            self.check_channel(ch)
        t = self.topics
        try:
            if ch.topic == t.joint_states:
                self._joint_states(batch, self.js, self.dec_js, first=True)
            elif ch.topic == t.excitation:
                self._joint_states(batch, self.exc, self.dec_exc, first=False)
            elif ch.topic == t.velocity_commands:
                self._commands(batch)
            elif ch.topic == t.experiment:
                mv = memoryview(batch.buf)
                for log, a, b in zip(batch.logs, batch.starts, batch.ends):
                    self.events.append((log, decode_string(mv[a:b])))
        except CdrError as exc:
            raise BagError(f'{self.bag.name}: malformed {ch.msgtype} on {ch.topic} near log time '
                           f'{batch.logs[0] * 1e-9:.6f} s: {exc}') from None

    def _first_names(self, names: tuple[str, ...]) -> None:
        self.js_first_names = names
        if self.js.joints is None:
            if not names:
                raise BagError(f'{self.bag.name}: first {self.topics.joint_states} message '
                               f'has no joint names')
            self.js.select(list(names))
            self.exc.select(list(names))

    def _joint_states(self, batch: Batch, table: _JointTable, dec: JointStateDecoder,
                      first: bool) -> None:
        fast = decode_joint_state_batch(batch.buf, batch.starts, batch.ends) \
            if len(batch.starts) > 8 else None
        if fast is not None:
            stamps, names, arrays = fast
            if first and self.js_first_names is None:
                self._first_names(names)
            table.add_batch(stamps, batch.logs, names, arrays)
            return
        mv = memoryview(batch.buf)
        for log, a, b in zip(batch.logs, batch.starts, batch.ends):
            stamp, names, arrays = dec.decode(mv[a:b])
            if first and self.js_first_names is None:
                self._first_names(names)
            table.add(stamp, log, names, arrays)

    def _commands(self, batch: Batch) -> None:
        fast = decode_float64_array_batch(batch.buf, batch.starts, batch.ends) \
            if len(batch.starts) > 8 else None
        if fast is not None:
            self._ref_table(fast.shape[1], batch.logs[0]).add_block(batch.logs, batch.logs, fast)
            return
        mv = memoryview(batch.buf)
        for log, a, b in zip(batch.logs, batch.starts, batch.ends):
            vals = decode_float64_array(mv[a:b])
            self._ref_table(len(vals), log).add_row(log, log, vals)

    def _ref_table(self, width: int, log: int) -> _Table:
        if self.ref is None:
            self.ref_width = width
            self.ref = _Table(width, self.counts.get(self.topics.velocity_commands, 0))
        if width != self.ref_width:
            raise BagError(f'{self.bag.name}: {self.topics.velocity_commands} data has {width} '
                           f'values at log time {log * 1e-9:.6f} s; earlier messages had '
                           f'{self.ref_width}')
        return self.ref


# --------------------------------------------------------------------------- scanning

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


def iter_batches(bag: BagFiles, topics: set[str] | None, progress: bool,
                 stats: list[ScanStats]) -> Iterator[Batch]:
    """
    Yield the wanted messages of every file of a bag in chunks.

    The wanted messages of every file of ``bag``, chunk by chunk; each file's
    :class:`ScanStats` is appended to ``stats`` when its scan ends.
    """
    total = sum(f.stat().st_size for f in bag.files)
    bar_cm: Any = nullcontext(None)
    if progress:
        from tqdm import tqdm
        bar_cm = tqdm(total=total, unit='B', unit_scale=True, desc=bag.path.name)
    with bar_cm as bar:
        for f in bag.files:
            with _readable(bag, f) as path:
                scanner = McapScanner(path, topics,
                                      on_bytes=bar.update if bar is not None else None)
                try:
                    for batch in scanner.batches():
                        yield _decompressed(batch) if bag.compression == 'message' else batch
                except McapFormatError as exc:
                    raise BagError(f'{f}: not a readable MCAP file ({exc})') from None
                stats.append(scanner.stats)


def _scan(bag: BagFiles, topics: set[str] | None, progress: bool,
          sink: Callable[[Batch], None]) -> list[ScanStats]:
    stats: list[ScanStats] = []
    for batch in iter_batches(bag, topics, progress, stats):
        sink(batch)
    return stats


def recovery_report(bag: BagFiles, stats: list[ScanStats], read_counts: dict[str, int],
                    expected: dict[str, int]) -> dict[str, Any]:
    rec: dict[str, Any] = {
        'complete': all(s.complete for s in stats),
        'bytes_lost': sum(s.bytes_lost for s in stats),
        'chunks_lost': sum(s.chunks_lost for s in stats),
        'problems': [p for s in stats for p in s.problems],
        'metadata_yaml': bag.metadata is not None,
    }
    # a chunk whose CRC or decompression failed loses its messages though every byte was read
    rec['damaged'] = bool(rec['bytes_lost'] or rec['chunks_lost'] or not rec['complete'])
    if expected:
        lost = {t: expected[t] - n for t, n in read_counts.items()
                if expected.get(t, 0) > n}       # topics not read are not lost
        rec['messages_lost'] = sum(lost.values())
        rec['messages_lost_per_topic'] = lost
    elif not rec['complete']:
        rec['messages_lost'] = 'unknown (no summary and no metadata.yaml)'
    else:
        rec['messages_lost'] = 0
    return rec


# --------------------------------------------------------------------------- public API

def read_recording(path: str | Path, *, joints: list[str] | None = None,
                   topics: BagTopics | None = None,
                   t_range: tuple[float, float] | None = None,
                   progress: bool = False, gaps: str = 'refuse'
                   ) -> tuple[Recording, tm.TimingReport]:
    """
    Read a bag into a uniformly sampled :class:`Recording` plus its :class:`TimingReport`.

    ``path`` is a rosbag2 directory, a directory holding .mcap files without metadata.yaml,
    or a bare .mcap file. ``joints`` selects joints by name (default: the names of the first
    joint state message, in its order). ``t_range`` = (t0, t1) in seconds of the bag clock
    keeps only that window. ``gaps``: a gap of more than
    :data:`~frf_ident.bag.timing.MAX_GAP_SAMPLES` missing joint states is refused
    ('refuse') or kept as missing data ('mark': NaN joint states on the grid inside it,
    listed in the report's ``missing`` and ``rec.meta['gaps']``). Raises :class:`BagError`
    (one line) for every input problem.

    Parameters
    ----------
    path : str or Path
        rosbag2 directory, directory of .mcap files, or a bare .mcap file.
    joints : list of str, optional
        Joint names to read, in this order; default: those of the first joint state message.
    topics : BagTopics, optional
        Topic names; default: the standard ones (/joint_states, /frf/experiment ...).
    t_range : tuple of float, optional
        (t0, t1) in s of the bag clock, t0 < t1: keep only this window; default: everything.
    progress : bool, optional
        Show a progress bar of the bytes read.
    gaps : {'refuse', 'mark'}, optional
        What to do with gaps of missing joint states (see above); default 'refuse'.

    Returns
    -------
    rec : Recording
        The uniformly sampled recording (joint states, commands, excitation, segments).
    report : TimingReport
        Timing analysis, repairs, recovery of damaged files and warnings.

    """
    topics = topics or BagTopics()
    if joints is not None and (isinstance(joints, str) or not joints):
        raise BagError(f'{joints=}: expected a non-empty list of joint names')
    if t_range is not None and not (len(t_range) == 2 and t_range[0] < t_range[1]):
        raise BagError(f'{t_range=}: expected (t_start, t_end) with t_start < t_end')
    if gaps not in tm.GAP_MODES:
        raise ValueError(f'{gaps=}: expected one of {tm.GAP_MODES}')
    bag = locate(path)
    try:
        return _read(bag, joints, topics, t_range, progress, gaps)
    except BagError:
        raise
    except (struct.error, ValueError, KeyError, IndexError, TypeError, UnicodeDecodeError,
            OverflowError, OSError) as exc:
        raise BagError(f'{bag.name}: unreadable bag ({type(exc).__name__}: {exc})') from None


def _read(bag: BagFiles, joints: list[str] | None, topics: BagTopics,
          t_range: tuple[float, float] | None,
          progress: bool, gaps: str) -> tuple[Recording, tm.TimingReport]:
    expected = expected_counts(bag)
    col = Collector(bag, topics, joints, expected)
    stats = _scan(bag, set(col.expected), progress, col.feed)
    n_js = len(col.js)
    read_counts = {topics.joint_states: n_js,
                   topics.velocity_commands: len(col.ref) if col.ref else 0,
                   topics.excitation: len(col.exc),
                   topics.experiment: len(col.events)}
    recovery = recovery_report(bag, stats, read_counts, expected)
    if col.js.data is None or n_js == 0:
        present = sorted({t for s in stats for t in s.topics})
        raise BagError(f'{bag.name}: no messages on {topics.joint_states} (expected '
                       f'{JOINT_STATE}; topics present: {present or "none"})'
                       f'{_lost_hint(recovery)}')
    meta, segments, warnings = read_descriptors(col.events, bag, topics)
    return assemble(bag, col, topics, meta, segments, warnings, recovery, t_range, gaps)


def _lost_hint(recovery: dict[str, Any]) -> str:
    if recovery.get('bytes_lost') or recovery.get('chunks_lost'):
        return (f'; the file is damaged: {recovery.get("bytes_lost", 0)} bytes unreadable, '
                f'{recovery.get("chunks_lost", 0)} chunks lost')
    return ''


def read_descriptors(events: list[tuple[int, str]], bag: BagFiles,
                     topics: BagTopics) -> tuple[dict[str, Any], list[Segment], list[str]]:
    """
    Return recording_meta and segments (start/end events paired) from /frf/experiment.

    A segment that started but never ended, in a bag whose producer writes end events (ours
    do) or reports aborts, is left out with a warning: its run was aborted or the recording
    stopped inside it, and the segments that ended before are analysed as they are
    (``meta['segments_left_out']`` lists their [t_start, t_end]).
    """
    meta: dict[str, Any] = {}
    segs: dict[str, Segment] = {}
    started: set[str] = set()
    ended: set[str] = set()
    other: dict[str, int] = {}
    aborted: list[str] = []
    for log, text in sorted(events, key=lambda e: e[0]):
        try:
            d = json.loads(text)
            if not isinstance(d, dict):
                raise TypeError('not a JSON object')
            if d.get('event') == 'recording_meta':
                d.pop('event')
                meta.update(d)
                continue
            if d.get('event') == 'procedure_end':      # our own end marker (CONTRACT §3)
                continue
            if d.get('event') == 'aborted':
                aborted.append(f'{d.get("procedure", "a procedure")} aborted at '
                               f'{float(d.get("t_end", 0.0)):.3f} s: {d.get("reason", "?")}')
                continue
            if d.get('event', 'start') not in ('start', 'end'):
                other[str(d.get('event'))] = other.get(str(d.get('event')), 0) + 1
                continue
            key = json.dumps({k: v for k, v in d.items() if k != 'event'}, sort_keys=True)
            event, seg = Segment.from_descriptor(text)
        except (ValueError, TypeError, KeyError) as exc:
            raise BagError(f'{bag.name}: {topics.experiment} message at {log * 1e-9:.6f} s is '
                           f'not a segment descriptor (JSON with t_start, t_end): {exc}') from None
        segs.setdefault(key, seg)
        (started if event == 'start' else ended).add(key)
    warnings = [f'segment {s.t_start:.3f}..{s.t_end:.3f} s has an end event but no start event'
                for k, s in segs.items() if k not in started]
    if ended or aborted:
        cut = [k for k in segs if k not in ended]
        warnings += [f'segment {segs[k].t_start:.3f}..{segs[k].t_end:.3f} s '
                     f'({segs[k].info.get("design", "?")}) never ended (its run was aborted or '
                     f'the recording stopped): left out' for k in cut]
        segs_all, segs = segs, {k: v for k, v in segs.items() if k not in cut}
        if cut:
            meta['segments_left_out'] = [[segs_all[k].t_start, segs_all[k].t_end] for k in cut]
    warnings += [f'{topics.experiment}: ignored {n} event(s) {name!r} (not start/end)'
                 for name, n in other.items()] + aborted
    return meta, list(segs.values()), warnings


# --------------------------------------------------------------------------- assembly

def _stamp_source(ns: np.ndarray) -> str:
    return 'header' if tm.valid_header_stamps(ns) else 'log'


def _window(ns: np.ndarray, t_range: tuple[float, float] | None) -> np.ndarray:
    if t_range is None:
        return np.ones(ns.size, dtype=bool)
    lo, hi = (int(round(x * 1e9)) for x in t_range)
    return (ns >= lo) & (ns <= hi)


def assemble(bag: BagFiles, col: Collector, topics: BagTopics, meta: dict[str, Any],
             segments: list[Segment], warnings: list[str], recovery: dict[str, Any],
             t_range: tuple[float, float] | None, gaps: str = 'refuse'
             ) -> tuple[Recording, tm.TimingReport]:
    """
    Assemble the collected messages into a Recording on a uniform grid.

    The joint states (and commands) on a uniform grid as a Recording, with the timing
    report; ``gaps`` as in :func:`read_recording`.
    """
    assert col.js.data is not None and col.js.joints is not None
    lag = effort_lag(segments, bag.name)     # declared by the producer (bag/pairing.py)
    joint_names = list(col.js.joints)
    frf = meta.pop(FRF_BAG_KEY, None)
    stamps, logs, vals = col.js.data.arrays()
    src = _stamp_source(stamps)
    if src == 'log':
        warnings.append(f'{topics.joint_states} header stamps are unset; using log time')
        stamps = logs
    if t_range is not None:
        sel = _window(stamps, t_range)
        if not np.any(sel):
            raise BagError(f'{bag.name}: no {topics.joint_states} samples in {t_range=} (bag '
                           f'covers {stamps.min() * 1e-9:.3f}..{stamps.max() * 1e-9:.3f} s)')
        stamps, logs, vals = stamps[sel], logs[sel], vals[sel]
    nj = len(joint_names)
    _check_joints(bag, topics, joint_names, vals, col)
    st = tm.analyse(topics.joint_states, stamps, logs, src)
    exact_t = _frf_grid(frf, st)
    exact = exact_t is not None or tm.on_exact_grid(st)
    if not exact:
        tm.check_resampling(st, bag.name, gaps)
    k_last = int(st.k[-1])
    # the grid is the least-squares line through the stamps, not the first (jittered) stamp:
    # a window of a streamed bag then lies on the grid of the whole bag up to the fit's noise
    offset = 0.0 if exact else tm.grid_offset(st)
    grid_ns = st.ns[0] + offset + np.arange(k_last + 1) * st.dt_ns  # float ns
    t = exact_t if exact_t is not None else grid_ns * 1e-9
    values = vals if _is_identity(st.order, vals.shape[0]) else vals[st.order]
    _check_finite(bag, topics, joint_names, values, st.ns)
    if exact:
        cols = values
    else:
        x = (st.ns - st.ns[0]).astype(float)
        xg = grid_ns - st.ns[0]
        cols = np.column_stack([np.interp(xg, x, values[:, j]) for j in range(values.shape[1])])
    missing = []
    for a, b in zip(*tm.long_gaps(st)):        # only with gaps='mark' (else refused above)
        cols[a:b + 1] = np.nan
        missing.append([float(t[a]), float(t[b])])
    if missing:
        meta['gaps'] = missing
    report = tm.TimingReport(dt_s=st.dt_ns * 1e-9, n_samples=int(t.size), t_start_s=float(t[0]),
                             t_end_s=float(t[-1]), resampled=not exact,
                             grid='exact' if exact else 'resampled',
                             topics={topics.joint_states: st.timing}, recovery=recovery,
                             warnings=warnings, missing=missing)
    per_sample = bool(frf and frf.get('reference') == 'per_sample' and exact_t is not None)
    reference = _reference(bag, col, topics, joint_names, frf, grid_ns, st, per_sample, report)
    excitation = _excitation(bag, col, topics, grid_ns, st, per_sample, report, t_range)
    if reference is None and excitation is not None:
        reference = excitation.copy()
    _rate_warnings(report, topics.joint_states)
    covered, cut = split_covered(segments, float(t[0]), float(t[-1]), st.dt_ns * 1e-9)
    if t_range is None and len(covered) + len(cut) < len(segments):
        # a recorder started late still gets the latched descriptors of earlier segments
        report.warnings.append(f'{len(segments) - len(covered) - len(cut)} segment(s) lie '
                               f'wholly outside the record: left out')
    segments = covered
    if cut:
        report.warnings.extend(cut_warning(s, float(t[0]), float(t[-1])) for s in cut)
        meta.setdefault('segments_left_out', []).extend([s.t_start, s.t_end] for s in cut)
    effort = align_effort(cols[:, 2 * nj:3 * nj], lag)
    rec = Recording(t=t, joint_names=joint_names, position=cols[:, 0:nj],
                    velocity=cols[:, nj:2 * nj], effort=effort,
                    reference=reference, excitation=excitation, segments=segments, meta=meta)
    return rec, report


def _is_identity(order: np.ndarray, n: int) -> bool:
    return order.size == n and bool(np.all(order == np.arange(n)))


def _frf_grid(frf: Any, st: tm.Stamps) -> np.ndarray | None:
    """
    Return the writer's exact time grid if the stamps lie on it.

    The writer's exact float time grid, if the bag's stamps are exactly on it (computed
    for the samples at hand only, so a window of a long bag costs its own size).
    """
    if not isinstance(frf, dict) or not isinstance(frf.get('time'), dict):
        return None
    try:
        spec, n_all = frf['time'], int(frf['n'])
        t1 = grid_times(spec, 2)
        step = float(t1[1] - t1[0])
        guess = int(round((st.ns[0] * 1e-9 - float(t1[0])) / step))
        for i0 in (guess, guess - 1, guess + 1):
            if i0 < 0 or i0 + st.ns.size > n_all:
                continue
            t = grid_times(spec, st.ns.size, i0)
            if np.all(np.isfinite(t)) and t[0] >= 0 and \
                    np.array_equal(np.round(t * 1e9).astype(np.int64), st.ns):
                return t
    except (TypeError, ValueError, KeyError, OverflowError, ZeroDivisionError):
        return None
    return None


def _check_joints(bag: BagFiles, topics: BagTopics, joint_names: list[str], vals: np.ndarray,
                  col: Collector) -> None:
    """Refuse a selected joint that no message carries, naming the joints that are there."""
    nj = len(joint_names)
    seen = set(col.js_first_names or ()) | col.js.names_seen
    for j, name in enumerate(joint_names):
        if name not in seen:
            raise BagError(f'{bag.name}: joint {name!r} not found in {topics.joint_states} '
                           f'(joints present: {sorted(seen)})')
        if np.all(np.isnan(vals[:, [j, nj + j, 2 * nj + j]])):
            raise BagError(f'{bag.name}: joint {name!r} has no values in {topics.joint_states}')


def _check_finite(bag: BagFiles, topics: BagTopics, joint_names: list[str], values: np.ndarray,
                  ns: np.ndarray) -> None:
    """
    Check the values of one topic for inf and partial NaN.

    inf anywhere, or NaN in part of a column, is an error; a column all NaN is a missing
    interface (ros2_control convention) and stays NaN.
    """
    nj = len(joint_names)
    bad = ~np.isfinite(values)
    if not bad.any():
        return
    for c in np.flatnonzero(bad.any(axis=0)):
        col = values[:, c]
        if np.all(np.isnan(col)):
            continue
        i = int(np.flatnonzero(~np.isfinite(col))[0])
        field_name = ('position', 'velocity', 'effort')[c // nj]
        raise BagError(f'{bag.name}: {topics.joint_states} {field_name}[{joint_names[c % nj]}] '
                       f'is {col[i]} at t={ns[i] * 1e-9:.6f} s '
                       f'({int(np.count_nonzero(~np.isfinite(col)))} non-finite values); '
                       f'expected finite values')


def _hold(c_ns: np.ndarray, c_vals: np.ndarray, grid_ns: np.ndarray,
          hold_ns: float) -> np.ndarray:
    """
    Hold a command series onto a time grid (zero-order hold).

    Zero-order hold of (c_ns, c_vals) onto grid_ns, NaN before the first value and where
    the last value is older than ``hold_ns``.
    """
    idx = np.searchsorted(c_ns, grid_ns, side='right') - 1
    out = np.full((grid_ns.size, c_vals.shape[1]), np.nan)
    ok = idx >= 0
    ok[ok] = grid_ns[ok] - c_ns[idx[ok]] <= hold_ns
    out[ok] = c_vals[idx[ok]]
    return out


def _exact_match(c_ns: np.ndarray, c_vals: np.ndarray, st: tm.Stamps, n: int) -> np.ndarray:
    """Values at exactly the sample stamps (NaN where none was published)."""
    out = np.full((n, c_vals.shape[1]), np.nan)
    pos = np.searchsorted(st.ns, c_ns)
    ok = pos < st.ns.size
    ok[ok] = st.ns[pos[ok]] == c_ns[ok]
    out[st.k[pos[ok]]] = c_vals[ok]
    return out


def _ref_columns(bag: BagFiles, col: Collector, topics: BagTopics, joint_names: list[str],
                 frf: Any) -> list[int]:
    """Column of each selected joint in the command arrays (controller joint order)."""
    order = list(frf.get('joint_names') or []) if isinstance(frf, dict) else []
    if len(order) != col.ref_width:
        order = list(col.js_first_names or [])
    if len(order) != col.ref_width:
        raise BagError(f'{bag.name}: {topics.velocity_commands} has {col.ref_width} values per '
                       f'message but {topics.joint_states} names {len(order)} joints; cannot map '
                       f'commands to joints')
    return [order.index(j) for j in joint_names]


def _reference(bag: BagFiles, col: Collector, topics: BagTopics, joint_names: list[str],
               frf: Any, grid_ns: np.ndarray, st: tm.Stamps, per_sample: bool,
               report: tm.TimingReport) -> np.ndarray | None:
    if col.ref is None or len(col.ref) == 0:
        return None
    ns, _, vals = col.ref.arrays()
    if np.any(np.isinf(vals)):
        raise BagError(f'{bag.name}: {topics.velocity_commands} data holds inf; expected finite '
                       f'velocity commands')
    vals = vals[:, _ref_columns(bag, col, topics, joint_names, frf)]
    cst = tm.analyse(topics.velocity_commands, ns, ns, 'log', None)
    report.topics[topics.velocity_commands] = cst.timing
    return _onto_grid(cst, vals[cst.order], st, grid_ns, per_sample)


def _excitation(bag: BagFiles, col: Collector, topics: BagTopics, grid_ns: np.ndarray,
                st: tm.Stamps, per_sample: bool, report: tm.TimingReport,
                t_range: tuple[float, float] | None) -> np.ndarray | None:
    if col.exc.data is None or len(col.exc.data) == 0:
        return None
    ns, logs, vals = col.exc.data.arrays()
    src = _stamp_source(ns)
    if src == 'log':
        ns = logs
    if np.any(np.isinf(vals)):
        raise BagError(f'{bag.name}: {topics.excitation} velocity holds inf; expected finite '
                       f'values')
    xst = tm.analyse(topics.excitation, ns, logs, src, None)
    report.topics[topics.excitation] = xst.timing
    return _onto_grid(xst, vals[xst.order], st, grid_ns, per_sample)


def _onto_grid(src: tm.Stamps, v: np.ndarray, st: tm.Stamps, grid_ns: np.ndarray,
               per_sample: bool) -> np.ndarray:
    """
    Put a command-like series onto the /joint_states grid.

    A command-like series on the /joint_states grid: matched by exact stamp for our own
    bags, else held for at most 3 sample or command periods (NaN beyond).
    """
    if per_sample:
        return _exact_match(src.ns, v, st, grid_ns.size)
    hold = 3.0 * max(st.dt_ns, src.dt_ns if src.ns.size > 1 else 0.0)
    return _hold(src.ns.astype(float), v, grid_ns, hold)


def _rate_warnings(report: tm.TimingReport, master: str) -> None:
    base = report.topics[master].rate_hz
    for name, tt in report.topics.items():
        if name != master and tt.count > 1 and math.isfinite(tt.rate_hz) and \
                abs(tt.rate_hz / base - 1.0) > 0.01:
            report.warnings.append(f'{name} runs at {tt.rate_hz:.3f} Hz, {master} at '
                                   f'{base:.3f} Hz (unequal rates; zero-order hold applied)')


# --------------------------------------------------------------------------- bag_info

def bag_info(path: str | Path) -> dict[str, Any]:
    """
    Topics, types, message counts, start and duration of a bag (like ``ros2 bag info``).

    Uses metadata.yaml when present, else the MCAP summary, else scans the file (then also
    reporting what could not be read).

    Parameters
    ----------
    path : str or Path
        rosbag2 directory or a bare .mcap file.

    Returns
    -------
    dict
        ``path``, ``files``, ``storage``, ``metadata_yaml``, ``message_count``, ``start_s``,
        ``end_s``, ``duration_s`` (s), ``topics`` (list of {``name``, ``type``,
        ``count``}), ``complete`` and ``bytes_lost``; with metadata.yaml also ``version``.

    """
    bag = locate(path)
    if bag.metadata is not None:
        return _info_from_metadata(bag)
    topics: dict[str, dict[str, Any]] = {}
    t0, t1, complete, lost = None, None, True, 0
    for f in bag.files:
        summ = read_summary(f)
        if summ is not None:
            chans, counts, s0, s1 = summ
            for cid, ch in chans.items():
                _add_topic(topics, ch.topic, ch.msgtype, counts.get(cid, 0))
            if counts:
                t0 = s0 if t0 is None else min(t0, s0)
                t1 = s1 if t1 is None else max(t1, s1)
            continue
        scanner = McapScanner(f)
        try:
            for ch, log, _ in scanner.messages():
                _add_topic(topics, ch.topic, ch.msgtype, 1)
                t0 = log if t0 is None else min(t0, log)
                t1 = log if t1 is None else max(t1, log)
        except McapFormatError as exc:
            raise BagError(f'{f}: not a readable MCAP file ({exc})') from None
        complete &= scanner.stats.complete
        lost += scanner.stats.bytes_lost
    return _info_dict(bag, topics, t0 or 0, t1 or 0, complete, lost)


def _add_topic(topics: dict[str, dict[str, Any]], name: str, msgtype: str, n: int) -> None:
    entry = topics.setdefault(name, {'name': name, 'type': msgtype, 'count': 0})
    entry['count'] += n


def _info_dict(bag: BagFiles, topics: dict[str, dict[str, Any]], t0: int, t1: int,
               complete: bool, lost: int) -> dict[str, Any]:
    return {'path': bag.name, 'files': [str(f) for f in bag.files], 'storage': 'mcap',
            'metadata_yaml': bag.metadata is not None,
            'message_count': sum(t['count'] for t in topics.values()),
            'start_s': t0 * 1e-9, 'end_s': t1 * 1e-9, 'duration_s': (t1 - t0) * 1e-9,
            'topics': sorted(topics.values(), key=lambda t: t['name']),
            'complete': complete, 'bytes_lost': lost}


def _info_from_metadata(bag: BagFiles) -> dict[str, Any]:
    m = bag.metadata or {}
    try:
        t0 = int(m['starting_time']['nanoseconds_since_epoch'])
        dur = int(m['duration']['nanoseconds'])
        topics = {}
        for e in m.get('topics_with_message_count') or []:
            tmeta = e['topic_metadata']
            topics[tmeta['name']] = {'name': tmeta['name'], 'type': tmeta['type'],
                                     'count': int(e['message_count'])}
    except (KeyError, TypeError, ValueError) as exc:
        raise BagError(f'{bag.path / "metadata.yaml"}: missing or malformed key {exc}') from None
    d = _info_dict(bag, topics, t0, t0 + dur, True, 0)
    d['version'] = m.get('version')
    d['storage'] = m.get('storage_identifier')
    return d


# --------------------------------------------------------------------------- repair

def reindex(path: str | Path, out: str | Path) -> Path:
    """
    Rewrite a damaged or unfinished bag as a complete one.

    Rewrite a damaged or unfinished bag as a complete one at ``out`` (all readable messages,
    summary, footer and metadata.yaml), like ``ros2 bag reindex`` plus recovery.

    Parameters
    ----------
    path : str or Path
        The damaged bag: rosbag2 directory or a bare .mcap file.
    out : str or Path
        Directory of the new bag (must not exist).

    Returns
    -------
    Path
        ``out``.

    """
    from .writer import BagRecorder

    bag = locate(path)
    rec = BagRecorder(chunk_bytes=1 << 20, flush_period_s=1e9)
    rec.open(out)
    try:
        def copy(batch: Batch) -> None:
            ch = batch.channel
            for log, a, b in zip(batch.logs, batch.starts, batch.ends):
                rec.write(ch.topic, ch.msgtype, log, batch.buf[a:b])
        _scan(bag, None, False, copy)
    finally:
        rec.close()
    return Path(out)


def iter_raw(path: str | Path, topics: set[str] | None = None) -> Iterator[tuple[str, str, int,
                                                                                 bytes]]:
    """
    (topic, type, log_time_ns, cdr) of every readable message, streaming.

    Parameters
    ----------
    path : str or Path
        rosbag2 directory or a bare .mcap file.
    topics : set of str, optional
        Topics to read; default: all.

    Yields
    ------
    tuple of (str, str, int, bytes)
        (topic name, message type, log time in ns, CDR-serialised message bytes), in file
        order.

    """
    bag = locate(path)
    stats: list[ScanStats] = []
    for batch in iter_batches(bag, topics, False, stats):
        ch = batch.channel
        for log, a, b in zip(batch.logs, batch.starts, batch.ends):
            yield ch.topic, ch.msgtype, log, bytes(batch.buf[a:b])


__all__ = ['BagFiles', 'bag_info', 'iter_raw', 'locate', 'read_recording', 'reindex']
