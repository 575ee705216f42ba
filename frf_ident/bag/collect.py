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
Collect the wanted topics of a bag, chunk by chunk, into numpy tables and events.

:func:`iter_batches` streams the messages of every file of a bag one MCAP chunk at a time;
:class:`Collector` decodes /joint_states, the velocity commands, the excitation and the
experiment events into growing numpy tables (joint states matched by name, any order), so
memory is bounded by the output arrays, not by the bag.
"""
from __future__ import annotations

from contextlib import nullcontext
from operator import itemgetter
import time
from typing import Any, Callable, Iterator

from frf_ident.core.progress import Progress
from frf_ident.errors import BagError
import numpy as np

from . import timing as tm
from .cdr import (CdrError, decode_float64_array, decode_float64_array_batch,
                  decode_joint_state_batch, decode_string, JointStateDecoder)
from .layout import BagFiles, decompressed, readable
from .mcapio import Batch, ChannelInfo, McapFormatError, McapScanner, ScanStats
from .topics import BagTopics


_BLOCK = 8192
_NAN = float('nan')


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


def iter_batches(bag: BagFiles, topics: set[str] | None, progress: Progress | None,
                 stats: list[ScanStats]) -> Iterator[Batch]:
    """
    Yield the wanted messages of every file of a bag in chunks.

    The wanted messages of every file of ``bag``, chunk by chunk; each file's
    :class:`ScanStats` is appended to ``stats`` when its scan ends. With a ``progress`` sink
    a tqdm bar of the bytes read is drawn on stderr (on a terminal only) and the finished
    scan is reported as one line (:mod:`frf_ident.core.progress`); None: silent.
    """
    total = sum(f.stat().st_size for f in bag.files)
    bar_cm: Any = nullcontext(None)
    if progress is not None:
        from tqdm import tqdm
        bar_cm = tqdm(total=total, unit='B', unit_scale=True, desc=bag.path.name, disable=None)
    t0 = time.perf_counter()
    with bar_cm as bar:
        for f in bag.files:
            with readable(bag, f) as path:
                scanner = McapScanner(path, topics,
                                      on_bytes=bar.update if bar is not None else None)
                try:
                    for batch in scanner.batches():
                        yield decompressed(batch) if bag.compression == 'message' else batch
                except McapFormatError as exc:
                    raise BagError(f'{f}: not a readable MCAP file ({exc})') from None
                stats.append(scanner.stats)
    if progress is not None:
        progress(f'{bag.name}: read {total / 1e6:.1f} MB in {len(bag.files)} file(s), '
                 f'{time.perf_counter() - t0:.1f} s')


def scan(bag: BagFiles, topics: set[str] | None, progress: Progress | None,
         sink: Callable[[Batch], None]) -> list[ScanStats]:
    """Feed every batch of :func:`iter_batches` to ``sink``; return the files' scan stats."""
    stats: list[ScanStats] = []
    for batch in iter_batches(bag, topics, progress, stats):
        sink(batch)
    return stats


__all__ = ['Collector', 'iter_batches', 'scan']
