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
Bounded-memory reading of bags longer than memory: the recording window by window.

:func:`read_recording` builds the whole recording's arrays; for a 10 GB /joint_states bag that
is more than a machine holds. Here the bag is scanned once (after a first pass over the small
/frf/experiment topic) and the joint states are kept only while a window needs them:

- bags with experiment descriptors: one window per segment (overlapping segments merged);
  samples between windows are dropped as soon as the scan has passed them;
- bags without descriptors (``window_s``): consecutive blocks of ``window_s`` seconds from the
  first sample, for detection and estimation block by block.

Each window is assembled by the same code as :func:`read_recording` (timing analysis,
resampling rules, exact time grid, command alignment), so a window equals the same time
range of the in-memory recording. Memory is bounded by the longest window plus
``drain_rows`` messages, independent of the bag's length.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

from frf_ident.core.estimation.detected import MIN_ADVANCE_S
from frf_ident.core.progress import checked, Progress
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import BagError
import numpy as np

from . import timing as tm
from .assemble import assemble, DEFAULT_GAPS
from .collect import Collector, iter_batches
from .layout import BagFiles, expected_counts, locate
from .mcapio import ScanStats
from .reader import ExperimentIndex, read_experiment
from .repair import recovery_report
from .topics import BagTopics

_PAD_NS = 10_000_000          # windows reach 10 ms beyond their segment


def segment_windows(segments: list[Segment]) -> list[tuple[int, int]]:
    """
    (start_ns, end_ns) windows covering the estimable segments, overlapping ones merged.

    Parameters
    ----------
    segments : list of Segment
        Experiment segments; only multisine, chirp and constant-velocity ones are covered.

    Returns
    -------
    list of tuple of int
        (start_ns, end_ns) in ns of the bag clock, each segment padded by 10 ms on both
        sides (start clipped at 0), sorted, overlapping windows merged.

    """
    spans = sorted((int(round(s.t_start * 1e9)) - _PAD_NS, int(round(s.t_end * 1e9)) + _PAD_NS)
                   for s in segments
                   if s.info.get('design') in ('multisine', 'chirp', 'constant_velocity'))
    out: list[list[int]] = []
    for a, b in spans:
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([max(a, 0), b])
    return [(a, b) for a, b in out]


@dataclass
class StreamStats:
    """
    What a streaming read did: windows, the most rows held at once, data loss.

    Parameters
    ----------
    windows : int, optional
        Number of windows assembled.
    messages : dict of str to int, optional
        Messages read per topic.
    peak_rows : int, optional
        The most message rows held in memory at once.
    recovery : dict, optional
        Recovery summary of damaged or unfinished files (as in the timing report).

    """

    windows: int = 0
    messages: dict[str, int] = field(default_factory=dict)
    peak_rows: int = 0
    recovery: dict[str, Any] = field(default_factory=dict)


class WindowReader:
    """
    Iterate ``(Recording, TimingReport)`` per window of a bag, in one scan.

    ``windows`` are (start_ns, end_ns) in the bag's sample time (header stamps when valid);
    ``window_s`` instead cuts consecutive blocks from the first sample (within ``span`` =
    (start_ns, end_ns) when given). ``joints`` selects joints as in :func:`read_recording`;
    ``experiment`` is the first pass (:func:`read_experiment`, run here when not given);
    ``gaps`` as in :func:`read_recording`. After the iteration :attr:`stats` holds the counts
    and the recovery summary of damaged files.

    Parameters
    ----------
    path : str or Path
        rosbag2 directory or a bare .mcap file.
    windows : list of tuple of int, optional
        (start_ns, end_ns) windows in ns of the bag clock; give either this or ``window_s``.
    window_s : float, optional
        Block length in s (> 0): consecutive blocks from the first sample.
    joints : list of str, optional
        Joint names to read, in this order; default: those of the first joint state message.
    topics : BagTopics, optional
        Topic names; default: the standard ones.
    experiment : ExperimentIndex, optional
        Result of :func:`read_experiment` for this bag; default: read here.
    span : tuple of int, optional
        (start_ns, end_ns) limiting the blocks of ``window_s`` mode; default: the whole bag.
    margin_s : float, optional
        Margin in s: a window is assembled once the scan has read this far beyond its end,
        and rows this close to a window are kept for it.
    drain_rows : int, optional
        Messages fed between two attempts to emit windows and drop passed rows.
    progress : callable, optional
        Progress sink, as in :func:`read_recording`; default None: silent.
    gaps : {'mark', 'refuse'}, optional
        Gaps of missing joint states, as in :func:`read_recording`; default
        :data:`~frf_ident.bag.assemble.DEFAULT_GAPS` ('mark').

    Raises
    ------
    ValueError
        Not exactly one of ``windows`` and ``window_s`` given, or an unknown ``gaps`` mode.
    BagError
        ``window_s`` is not > 0, ``joints`` is empty or a string, or the bag cannot be located.

    """

    def __init__(self, path: str | Path, *, windows: list[tuple[int, int]] | None = None,
                 window_s: float | None = None, joints: list[str] | None = None,
                 topics: BagTopics | None = None, experiment: ExperimentIndex | None = None,
                 span: tuple[int, int] | None = None,
                 margin_s: float = 1.0, drain_rows: int = 1 << 16,
                 progress: Progress | None = None, gaps: str = DEFAULT_GAPS) -> None:
        if (windows is None) == (window_s is None):
            raise ValueError('give exactly one of windows= or window_s=')
        if window_s is not None and not window_s > 0:
            raise BagError(f'{window_s=}: expected a window length > 0 s')
        if joints is not None and (isinstance(joints, str) or not joints):
            raise BagError(f'{joints=}: expected a non-empty list of joint names')
        self.bag: BagFiles = locate(path)
        self.topics = topics or BagTopics()
        self.joints = joints
        self.windows = sorted(windows) if windows is not None else None
        self.block_ns = int(round(window_s * 1e9)) if window_s is not None else None
        self.experiment = experiment or read_experiment(path, topics=self.topics)
        self.margin_ns = int(round(margin_s * 1e9))
        self.drain_rows = int(drain_rows)
        self.span = span
        self.progress = checked(progress)
        if gaps not in tm.GAP_MODES:
            raise ValueError(f'{gaps=}: expected one of {tm.GAP_MODES}')
        self.gaps = gaps
        self.stats = StreamStats()
        self._next = 0
        self._origin: int | None = None
        self._last_ns: int | None = None
        self._starts: list[int] = []
        self._resume: int | None = None

    def continue_from(self, t_s: float) -> None:
        """
        Start the next block at a given time.

        Block mode: start the next block at ``t_s`` [s] (e.g. where the last whole
        multisine period of the current block ends) instead of right after it; ignored
        unless it lies more than ``MIN_ADVANCE_S`` inside the block just read (the scan only
        moves forward; the in-memory blocks follow the same rule).

        Parameters
        ----------
        t_s : float
            Start time in s of the bag clock for the next block.

        """
        if self.block_ns is None or not self._starts:
            return
        ns = int(round(t_s * 1e9))
        lo = self._starts[-1]
        if lo + int(MIN_ADVANCE_S * 1e9) < ns <= lo + self.block_ns and \
                len(self._starts) == self._next:
            self._resume = ns

    # ------------------------------------------------------------------ windows
    def _window(self, i: int) -> tuple[int, int] | None:
        if self.windows is not None:
            return self.windows[i] if i < len(self.windows) else None
        if self._origin is None or self.block_ns is None:
            return None
        if i < len(self._starts):
            lo = self._starts[i]
        else:
            lo = self._resume if self._resume is not None else (
                self._origin if i == 0 else self._starts[-1] + self.block_ns)
            self._resume = None
            self._starts.append(lo)
        end = self.span[1] if self.span is not None else None
        if self._last_ns is not None:
            end = self._last_ns if end is None else min(end, self._last_ns)
        if end is not None and lo > end:
            return None
        hi = lo + self.block_ns - 1
        return lo, hi if self.span is None else min(hi, self.span[1])

    # ------------------------------------------------------------------ scan
    def __iter__(self) -> Iterator[tuple[Recording, tm.TimingReport]]:
        col = Collector(self.bag, self.topics, self.joints, {})
        wanted = set(col.expected) - {self.topics.experiment}
        scan: list[ScanStats] = []
        counts = self.stats.messages
        counts.update({t: 0 for t in wanted})
        fed = 0
        for batch in iter_batches(self.bag, wanted, self.progress, scan):
            col.feed(batch)
            counts[batch.channel.topic] = counts.get(batch.channel.topic, 0) + len(batch.logs)
            fed += len(batch.logs)
            if fed >= self.drain_rows:
                fed = 0
                yield from self._drain(col, final=False)
        yield from self._drain(col, final=True)
        read = dict(counts)
        read[self.topics.experiment] = self.experiment.events
        self.stats.recovery = recovery_report(self.bag, scan, read, expected_counts(self.bag))

    def _tables(self, col: Collector) -> list[Any]:
        tables = [col.js.data, col.exc.data, col.ref]
        return [t for t in tables if t is not None and len(t)]

    def _drain(self, col: Collector, final: bool) -> Iterator[tuple[Recording, tm.TimingReport]]:
        if col.js.data is None or not len(col.js.data):
            return
        held = sum(len(t) for t in self._tables(col))
        self.stats.peak_rows = max(self.stats.peak_rows, held)
        times = col.js.data.times()
        if self._origin is None:
            self._origin = int(times.min())
            if self.span is not None:
                self._origin = max(self._origin, self.span[0])
        if final:
            self._last_ns = int(times.max())
        horizon = int(times.max()) - self.margin_ns
        while True:
            w = self._window(self._next)
            if w is None or (not final and w[1] > horizon):
                break
            self._next += 1
            item = self._emit(col, w, times)
            if item is not None:
                yield item
        w = self._window(self._next)
        cut = (w[0] - self.margin_ns) if w is not None else horizon
        if final:
            return
        for table in self._tables(col):
            t = table.times()
            if t.size and t.min() < cut:
                table.keep(t >= cut)

    def _emit(self, col: Collector, w: tuple[int, int], t: np.ndarray
              ) -> tuple[Recording, tm.TimingReport] | None:
        """
        Assemble one window from the rows held.

        Assemble window ``w`` from the rows held, whose times are ``t`` (None if it
        holds no joint state).
        """
        lo, hi = w
        assert col.js.data is not None
        sel = (t >= lo) & (t <= hi)
        if not np.any(sel):
            return None
        view = copy.copy(col)
        view.js = copy.copy(col.js)
        view.js.data = col.js.data.subset(sel)
        reach = (lo - self.margin_ns, hi + self.margin_ns)
        if col.exc.data is not None and len(col.exc.data):
            view.exc = copy.copy(col.exc)
            te = col.exc.data.times()
            view.exc.data = col.exc.data.subset((te >= reach[0]) & (te <= reach[1]))
        if col.ref is not None and len(col.ref):
            tr = col.ref.times()
            view.ref = col.ref.subset((tr >= reach[0]) & (tr <= reach[1]))
        ex = self.experiment
        segs = [s for s in ex.segments
                if s.t_end * 1e9 >= lo and s.t_start * 1e9 <= hi]
        rec, report = assemble(self.bag, view, self.topics, copy.deepcopy(ex.meta), segs,
                               list(ex.warnings), {}, None, self.gaps)
        self.stats.windows += 1
        return rec, report


__all__ = ['ExperimentIndex', 'StreamStats', 'WindowReader', 'read_experiment',
           'segment_windows']
