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

The stages live in their own modules: :mod:`~frf_ident.bag.layout` (files, metadata,
compression), :mod:`~frf_ident.bag.collect` (scanning and decoding),
:mod:`~frf_ident.bag.assemble` (the uniform grid), :mod:`~frf_ident.bag.repair` (recovery),
:mod:`~frf_ident.bag.info` (``ros2 bag info``).
"""
from __future__ import annotations

from dataclasses import dataclass
import json
from pathlib import Path
import struct
from typing import Any

from frf_ident.core.progress import checked, Progress
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import BagError

from . import timing as tm
from .assemble import assemble, DEFAULT_GAPS
from .collect import Collector, scan
from .layout import BagFiles, expected_counts, locate
from .repair import recovery_report
from .topics import BagTopics, JOINT_STATE


def read_recording(path: str | Path, *, joints: list[str] | None = None,
                   topics: BagTopics | None = None,
                   t_range: tuple[float, float] | None = None,
                   progress: Progress | None = None, gaps: str = DEFAULT_GAPS
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
    progress : callable, optional
        Progress sink (:mod:`frf_ident.core.progress`): given, a bar of the bytes read is
        drawn on a terminal and the finished scan reported as one line; None: silent.
    gaps : {'mark', 'refuse'}, optional
        What to do with gaps of missing joint states (see above); default
        :data:`~frf_ident.bag.assemble.DEFAULT_GAPS` ('mark').

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
    checked(progress)
    bag = locate(path)
    try:
        return _read(bag, joints, topics, t_range, progress, gaps)
    except BagError:
        raise
    except (struct.error, ValueError, KeyError, IndexError, TypeError, UnicodeDecodeError,
            OverflowError, OSError) as exc:
        raise BagError(f'{bag.name}: unreadable bag ({type(exc).__name__}: {exc})') from None


@dataclass
class ExperimentIndex:
    """
    What the /frf/experiment topic says: recording_meta, segments, warnings.

    Parameters
    ----------
    meta : dict
        Contents of the ``recording_meta`` events (empty without them).
    segments : list of Segment
        The experiment segments described, with times in s of the bag clock.
    warnings : list of str
        Problems found in the descriptors (end without start, ignored events).
    events : int, optional
        Number of messages read on the experiment topic.

    """

    meta: dict[str, Any]
    segments: list[Segment]
    warnings: list[str]
    events: int = 0

    @property
    def summary(self) -> dict[str, Any]:
        """Return the procedures' summary the run recorded (poses; empty without)."""
        s = self.meta.get('summary')
        return s if isinstance(s, dict) else {}

    @property
    def segments_left_out(self) -> list[list[float]]:
        """Return the [t_start, t_end] of the segments a time range cut (left out, named)."""
        return list(self.meta.get('segments_left_out') or [])


def read_experiment(path: str | Path, *, topics: BagTopics | None = None) -> ExperimentIndex:
    """
    Read only the experiment descriptors of a bag: its recording meta and segments.

    Scans the experiment topic alone (no joint states are decoded), so it costs a fraction
    of :func:`read_recording`: the first pass of the bounded-memory reader
    (:mod:`.windows`), and how ``frf-ident estimate`` finds the poses of a bag recorded at
    several (``identify --poses --one-bag``).

    Parameters
    ----------
    path : str or Path
        rosbag2 directory, directory of .mcap files, or a bare .mcap file.
    topics : BagTopics, optional
        Topic names; default: the standard ones.

    Returns
    -------
    ExperimentIndex
        Metadata, segments (start and end paired, in time order) and warnings of the
        descriptors, and the number of messages.

    Raises
    ------
    BagError
        The bag cannot be read (one line naming it).

    """
    topics = topics or BagTopics()
    bag = locate(path)
    try:
        col = Collector(bag, topics, None, expected_counts(bag))
        scan(bag, {topics.experiment}, None, col.feed)
        meta, segments, warnings = read_descriptors(col.events, bag, topics)
    except BagError:
        raise
    except (struct.error, ValueError, KeyError, IndexError, TypeError, UnicodeDecodeError,
            OverflowError, OSError) as exc:
        raise BagError(f'{bag.name}: unreadable bag ({type(exc).__name__}: {exc})') from None
    return ExperimentIndex(meta, segments, warnings, len(col.events))


def _read(bag: BagFiles, joints: list[str] | None, topics: BagTopics,
          t_range: tuple[float, float] | None,
          progress: Progress | None, gaps: str) -> tuple[Recording, tm.TimingReport]:
    expected = expected_counts(bag)
    col = Collector(bag, topics, joints, expected)
    stats = scan(bag, set(col.expected), progress, col.feed)
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
            key = json.dumps({k: v for k, v in d.items() if k not in ('event', 'stopped')},
                             sort_keys=True)
            event, seg = Segment.from_descriptor(text)
            stop = seg.info.pop('stopped', None)
            if event == 'end' and isinstance(stop, dict) and key in segs:
                stopped_early(segs[key], stop)
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


def stopped_early(seg: Segment, stop: dict[str, Any]) -> None:
    """
    Shorten a multisine segment to where its run stopped at the uncertainty target.

    The end descriptor of such a segment repeats its start descriptor with ``stopped``:
    ``{"t_end": s, "periods": n}``, the time of its last whole period's end and the steady
    periods it holds (docs/CONTRACT.md §3).

    Parameters
    ----------
    seg : Segment
        The segment from its start descriptor (changed in place).
    stop : dict
        The ``stopped`` entry of its end descriptor.

    Raises
    ------
    KeyError, TypeError, ValueError
        ``stopped`` lacks ``t_end`` or ``periods``, or they are no numbers.

    """
    t_end, periods = float(stop['t_end']), int(stop['periods'])
    if not seg.t_start < t_end <= seg.t_end or not 1 <= periods <= int(seg.info['periods']):
        raise ValueError(f'stopped {stop} is outside the segment {seg.t_start:.3f}..'
                         f'{seg.t_end:.3f} s of {seg.info["periods"]} periods')
    seg.info.setdefault('periods_planned', int(seg.info['periods']))
    seg.info['periods'] = periods
    seg.t_end = t_end


__all__ = ['ExperimentIndex', 'read_descriptors', 'read_experiment', 'read_recording',
           'stopped_early']
