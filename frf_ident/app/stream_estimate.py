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
Estimate bags larger than memory window by window.

Estimation of bags larger than memory: windows from :mod:`frf_ident.bag.windows` fed to the
core's segment-wise estimators.

- bags with /frf/experiment descriptors: one window per experiment segment, the spectra of
  each segment kept (:class:`~frf_ident.core.estimation.described.SegmentEstimator`); the estimates
  equal the in-memory ones;
- bags without descriptors: blocks of ``window_s`` seconds; each block's excitation is
  detected and its periods added to the H1 sums of that excitation
  (:func:`~frf_ident.core.estimation.detected.estimate_in_blocks`, which the in-memory
  estimate runs on the same blocks, so both take the same decisions).

Gaps longer than the resampling limit are kept as missing data (``gaps='mark'``): their
samples are estimated with the FRF (multisine periods, LPM frames; docs/bags.md), a chirp
excerpt they touch is dropped.

Memory is bounded by the longest window, not by the bag.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import os
from pathlib import Path
from typing import Any

from frf_ident.bag import timing as tm
from frf_ident.bag import windows as bs
from frf_ident.bag.coverage import cut_warning, split_covered
from frf_ident.bag.info import bag_info
from frf_ident.core.estimation.channels import check_joints, experiment_joints, joint_channels
from frf_ident.core.estimation.chirp_estimate import complete_chirp_iterations
from frf_ident.core.estimation.described import (check_recording, cut_short_error,
                                                 SegmentEstimator)
from frf_ident.core.estimation.detected import estimate_in_blocks, window_length
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.progress import Progress, sink
from frf_ident.errors import BagError, EstimationError

#: in-memory arrays take about this many bytes per byte of MCAP data (measured: 3-joint
#: JointState bags, float64 columns plus the copies of timing repair and assembly)
MEMORY_PER_BAG_BYTE = 3.0


@dataclass
class StreamedEstimate:
    """
    Estimates of a streamed bag with the merged timing report and what the stream did.

    Parameters
    ----------
    estimates : dict of str to FrequencyResponse
        Every estimate the bag supports, keyed by name ('multisine', 'chirp', ...).
    timing : TimingReport
        Timing report of all windows merged (:func:`frf_ident.bag.timing.merge_reports`).
    stats : StreamStats
        What the stream did: windows, messages read per topic, peak rows held, recovery.
    meta : dict, optional
        Recording metadata from the experiment descriptors (empty without them).
    notes : list of str, optional
        Per-block detection notes of bags without descriptors (empty otherwise).

    """

    estimates: dict[str, FrequencyResponse]
    timing: tm.TimingReport
    stats: bs.StreamStats
    meta: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    @property
    def summary(self) -> dict[str, Any]:
        """Return the procedures' summary the run recorded (poses; empty without)."""
        s = self.meta.get('summary')
        return s if isinstance(s, dict) else {}


def default_memory_budget() -> int:
    """
    Return the memory budget of the in-memory reader.

    Bytes the in-memory reader may use before ``estimate`` streams: a quarter of the
    physical memory, at most 4 GiB.

    Returns
    -------
    int
        Budget in bytes (8 GiB of physical memory assumed when it cannot be queried).

    """
    try:
        phys = os.sysconf('SC_PAGE_SIZE') * os.sysconf('SC_PHYS_PAGES')
    except (ValueError, OSError, AttributeError):
        phys = 8 << 30
    return int(min(phys // 4, 4 << 30))


def needs_streaming(bag: str | Path, budget_bytes: int) -> bool:
    """
    Return true when reading the bag into memory would exceed ``budget_bytes``.

    Parameters
    ----------
    bag : str or Path
        Bag directory or .mcap file.
    budget_bytes : int
        Memory budget of the in-memory reader in bytes.

    Returns
    -------
    bool
        True when the size of the bag's MCAP files times :data:`MEMORY_PER_BAG_BYTE`
        exceeds ``budget_bytes``.

    """
    from frf_ident.bag.layout import locate
    size = sum(f.stat().st_size for f in locate(bag).files)
    return size * MEMORY_PER_BAG_BYTE > budget_bytes


def _in_range(windows: list[tuple[int, int]], t_range: tuple[float, float] | None
              ) -> list[tuple[int, int]]:
    if t_range is None:
        return windows
    lo, hi = (int(round(x * 1e9)) for x in t_range)
    return [(max(a, lo), min(b, hi)) for a, b in windows if b >= lo and a <= hi]


def stream_estimate(bag: str | Path, *, joints: list[str] | None = None,
                    t_range: tuple[float, float] | None = None, window_s: float | None = None,
                    options: Any = None, progress: Progress | None = None
                    ) -> StreamedEstimate:
    """
    Every estimate the bag supports, read window by window (see the module docstring).

    Each window is checked as
    :func:`~frf_ident.core.estimation.described.estimate_recording` checks a whole recording
    (band, periods, clipping); ``options``
    (:class:`~frf_ident.core.estimation.excitation_options.ExcitationOptions`) replace detection in
    every block.
    Only the last chirp iteration is read (the one estimated).

    Parameters
    ----------
    bag : str or Path
        Bag directory or .mcap file.
    joints : list of str, optional
        Joint names to analyse; default: all joints of the first joint state message.
    t_range : tuple of float, optional
        (t_start, t_end) in s of the bag clock, t_start < t_end: analyse only the segments
        or blocks inside this range; default: the whole bag.
    window_s : float, optional
        Block length in s for bags without experiment descriptors; default
        :data:`~frf_ident.core.estimation.detected.DEFAULT_WINDOW_S`.
    options : ExcitationOptions, optional
        Excitation options replacing detection; default None: detect the excitation.
    progress : callable, optional
        Called with one line of text per step; default None: silent. Given, the
        bag's scan also draws a bar of the bytes read on a terminal
        (:mod:`frf_ident.core.progress`).

    Returns
    -------
    StreamedEstimate
        The estimates with the merged timing report, stream statistics, recording metadata
        and detection notes.

    Raises
    ------
    EstimationError
        ``t_range`` is malformed, an experiment segment has no joint states, no joint state
        lies inside the analysed windows, or the data do not support an estimate.

    """
    say = sink(progress)
    window_s = window_length(window_s, None if window_s is not None else _joint_state_rate(bag))
    if t_range is not None and not (len(t_range) == 2 and t_range[0] < t_range[1]):
        raise EstimationError(f'{t_range=}: expected (t_start, t_end) with t_start < t_end')
    if joints is not None:
        check_joints(joints)
    exp = bs.read_experiment(bag)
    segments, cut = estimated_segments(exp, t_range, say)
    reports: list[tm.TimingReport] = []
    notes: list[str] = []
    if segments:
        reader = bs.WindowReader(bag, windows=_in_range(bs.segment_windows(segments), t_range),
                                 experiment=exp, progress=progress)
        say(f'streaming: {len(segments)} experiment segments in {len(reader.windows)} windows')
        estimates = segment_estimates(reader, segments, exp, joints, options, reports)
    elif exp.segments_left_out and (t_range is None or cut):
        raise cut_short_error(len(exp.segments_left_out))
    else:
        say(f'streaming: no experiment descriptors; detecting the excitation in blocks of '
            f'{window_s:g} s')
        span = None if t_range is None else tuple(int(round(x * 1e9)) for x in t_range)
        reader = bs.WindowReader(bag, window_s=window_s, joints=joints, experiment=exp,
                                 span=span, progress=progress)
        estimates = block_estimates(reader, options, window_s, reports)
        notes = [n for n in next(iter(estimates.values())).notes.get('detected', [])
                 if n.startswith('block ')]
    if not reports:
        raise EstimationError(f'{bag}: no joint states inside the analysed windows')
    timing = tm.merge_reports(reports, reader.stats.recovery)
    meta = dict(exp.meta)
    meta.pop('_frf_bag', None)
    return StreamedEstimate(estimates, timing, reader.stats, meta, notes)


def estimated_segments(exp: Any, t_range: tuple[float, float] | None, say: Progress
                       ) -> tuple[list, list]:
    """
    Return the segments to estimate and those ``t_range`` cuts (named, left out).

    Only the last chirp iteration is read (the estimate), or the last complete one when it
    was cut short.
    """
    segments = [s for s in exp.segments
                if s.info.get('design') in ('multisine', 'chirp', 'constant_velocity')]
    chirps = [s.info.get('iteration', 0) for s in segments if s.info.get('design') == 'chirp']
    if chirps:
        keep = {max(chirps)} | set(complete_chirp_iterations(segments)[-1:])
        segments = [s for s in segments if s.info.get('design') != 'chirp'
                    or s.info.get('iteration', 0) in keep]
    cut: list = []
    if t_range is not None:
        # a segment the range cuts is left out, named (its samples are not all in the range)
        segments, cut = split_covered(segments, t_range[0], t_range[1], 0.0)
        for s in cut:
            say(f'warning: {cut_warning(s, *t_range)}')
        exp.meta.setdefault('segments_left_out', []).extend([s.t_start, s.t_end] for s in cut)
    return segments, cut


def segment_estimates(reader: Any, segments: list, exp: Any, joints: list[str] | None,
                      options: Any, reports: list) -> dict[str, FrequencyResponse]:
    """
    Estimate the described segments window by window; add each window's timing to ``reports``.

    Every joint the experiments excited takes part; the wanted channels are picked after.
    """
    est = SegmentEstimator(segments)
    for rec, report in reader:
        if joints is not None:
            check_joints(joints, rec.joint_names)
            rec = rec.select_joints(experiment_joints(rec, joints))
        check_recording(rec, options)
        est.add_window(rec)
        reports.append(report)
    missing = est.missing()
    if missing:
        s = missing[0]
        raise EstimationError(f'{len(missing)} experiment segment(s) have no joint states '
                              f'in the bag, first {s.info.get("design")} at '
                              f'{s.t_start:.3f}..{s.t_end:.3f} s')
    estimates = est.results()
    if not estimates:
        left_out = len(exp.segments_left_out)
        raise (cut_short_error(left_out) if left_out else
               EstimationError('the experiment segments give no estimate'))
    if joints is not None:
        estimates = {k: joint_channels(v, joints) for k, v in estimates.items()}
    return estimates


def block_estimates(reader: Any, options: Any, window_s: float, reports: list
                    ) -> dict[str, FrequencyResponse]:
    """Detect and estimate block by block (no descriptors); add the timings to ``reports``."""
    def blocks():
        for rec, report in reader:
            reports.append(report)
            yield rec
    return estimate_in_blocks(blocks(), options, resume=reader.continue_from, window_s=window_s)


def _joint_state_rate(bag: Path) -> float | None:
    """Return the joint-state rate [Hz] the bag's summary gives (None: not known)."""
    try:
        info = bag_info(bag)
    except (BagError, OSError):      # the reader names what is wrong with the bag, later
        return None
    n = sum(t['count'] for t in info['topics'] if t['name'] == '/joint_states')
    return (n - 1) / info['duration_s'] if n > 1 and info['duration_s'] > 0 else None


__all__ = ['MEMORY_PER_BAG_BYTE', 'StreamedEstimate', 'default_memory_budget',
           'needs_streaming', 'stream_estimate']
