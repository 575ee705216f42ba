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
Timing analysis of recorded topics and the rules for resampling onto a uniform grid.

Robots do not sample perfectly: header stamps jitter, messages get dropped or duplicated,
arrive out of order, and the receive (log) time lags the header stamp. This module measures
all of that per topic and decides whether the joint states may be resampled:

- header stamps are used when valid (at most one zero stamp, not all equal), else log time;
- messages are sorted by stamp (``non_monotonic`` counts the reversals in file order) and
  exact duplicate stamps are dropped (first kept);
- sample indices k accumulate the rounded intervals ``round(diff(s) / dt)``, and the period
  ``dt`` is the least-squares slope of stamps over k; a gap is a step of k by more than one;
- ``jitter`` = std of the intervals between consecutive (non-gap) samples relative to dt;
- the uniform grid is s0 + k dt with s0 the least-squares intercept (:func:`grid_offset`),
  so it does not depend on the jitter of the first stamp of a bag or of a window;
- resampling (linear interpolation of joint states, zero-order hold of references) is
  applied only if jitter < 5 % of dt; a gap of at most 3 missing samples is interpolated, a
  longer one is either refused (``gaps='refuse'``: :class:`~frf_ident.errors.BagError`
  explains which rule failed where) or kept as missing data (``gaps='mark'``: the grid
  samples inside it are NaN and :func:`long_gaps` lists them, so an estimator drops only
  the periods or excerpts a gap touches).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from frf_ident.errors import BagError
import numpy as np

MAX_JITTER = 0.05
MAX_GAP_SAMPLES = 3
#: what a gap longer than MAX_GAP_SAMPLES does: 'refuse' the bag or 'mark' it missing (NaN)
GAP_MODES = ('refuse', 'mark')


@dataclass
class TopicTiming:
    """Timing findings of one topic."""

    topic: str
    count: int
    stamp_source: str = 'header'  # 'header' | 'log'
    dt_s: float = float('nan')
    rate_hz: float = float('nan')
    jitter: float = 0.0  # std(interval) / dt over non-gap intervals
    stamp_jitter: float = 0.0  # std(stamp - grid) / dt
    gaps: int = 0
    missing_samples: int = 0
    longest_gap_samples: int = 0
    longest_gap_at_s: float | None = None
    duplicates: int = 0
    non_monotonic: int = 0
    header_log_offset_mean_s: float | None = None
    header_log_offset_std_s: float | None = None
    header_log_offset_max_s: float | None = None

    def line(self) -> str:
        """One human-readable line."""
        txt = (f'{self.topic}: {self.count} msgs, {self.rate_hz:.3f} Hz ({self.stamp_source} '
               f'stamps), jitter {100 * self.jitter:.2f} % of dt')
        if self.gaps:
            txt += (f', {self.gaps} gaps / {self.missing_samples} missing samples (longest '
                    f'{self.longest_gap_samples} at t={self.longest_gap_at_s:.3f} s)')
        if self.duplicates:
            txt += f', {self.duplicates} duplicate stamps'
        if self.non_monotonic:
            txt += f', {self.non_monotonic} non-monotonic stamps'
        if self.header_log_offset_mean_s is not None:
            txt += (f', log-header offset {1e3 * self.header_log_offset_mean_s:.3f} '
                    f'+- {1e3 * (self.header_log_offset_std_s or 0.0):.3f} ms')
        return txt


@dataclass
class TimingReport:
    """Everything read_recording found about timing and data loss."""

    dt_s: float
    n_samples: int
    t_start_s: float
    t_end_s: float
    resampled: bool
    grid: str  # 'exact' | 'resampled'
    topics: dict[str, TopicTiming] = field(default_factory=dict)
    recovery: dict[str, Any] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    #: gaps longer than MAX_GAP_SAMPLES kept as missing data: [t_first, t_last] of the
    #: missing grid samples [s], one pair per gap
    missing: list[list[float]] = field(default_factory=list)

    def summary(self) -> list[str]:
        """Human-readable lines (for logs and reports)."""
        lines = [f'{self.n_samples} samples at {1.0 / self.dt_s:.3f} Hz, '
                 f't = {self.t_start_s:.3f} .. {self.t_end_s:.3f} s, grid: {self.grid}'
                 + (' (resampled)' if self.resampled else '')]
        lines += [t.line() for t in self.topics.values()]
        if self.recovery.get('damaged'):
            r = self.recovery
            lines.append(f'recovered a damaged/unfinished bag: {r.get("bytes_lost", 0)} bytes '
                         f'lost, {r.get("chunks_lost", 0)} chunks lost, messages lost: '
                         f'{r.get("messages_lost", "unknown")}'
                         + ''.join(f'; {p}' for p in (r.get('problems') or [])[:3]))
        if self.missing:
            n = sum(int(round((b - a) / self.dt_s)) + 1 for a, b in self.missing)
            where = ', '.join(f'{a:.3f}..{b:.3f} s' for a, b in self.missing[:6])
            more = f' and {len(self.missing) - 6} more' if len(self.missing) > 6 else ''
            lines.append(f'{len(self.missing)} gaps longer than {MAX_GAP_SAMPLES} samples kept '
                         f'as missing data ({n} samples: {where}{more}); the estimators '
                         f'estimate them (multisine periods, LPM frames) or drop the chirp '
                         f'excerpts they touch')
        lines += [f'warning: {w}' for w in self.warnings]
        return lines

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable form."""
        d = asdict(self)
        d['topics'] = {k: asdict(v) for k, v in self.topics.items()}
        return d


def merge_reports(reports: list[TimingReport], recovery: dict[str, Any] | None = None
                  ) -> TimingReport:
    """
    Merge the timing reports of the windows of a streamed bag.

    One report for the windows of a streamed bag: counts and losses add up, jitter and
    offsets take the worst window, warnings are kept once each.
    """
    if not reports:
        raise ValueError('no timing reports to merge')
    topics: dict[str, TopicTiming] = {}
    for r in reports:
        for name, tt in r.topics.items():
            m = topics.get(name)
            if m is None:
                topics[name] = TopicTiming(**asdict(tt))
                continue
            m.count += tt.count
            m.gaps += tt.gaps
            m.missing_samples += tt.missing_samples
            m.duplicates += tt.duplicates
            m.non_monotonic += tt.non_monotonic
            m.jitter = max(m.jitter, tt.jitter)
            m.stamp_jitter = max(m.stamp_jitter, tt.stamp_jitter)
            if tt.longest_gap_samples > m.longest_gap_samples:
                m.longest_gap_samples = tt.longest_gap_samples
                m.longest_gap_at_s = tt.longest_gap_at_s
            for key in ('header_log_offset_std_s', 'header_log_offset_max_s'):
                vals = [v for v in (getattr(m, key), getattr(tt, key)) if v is not None]
                setattr(m, key, max(vals) if vals else None)
    warnings = list(dict.fromkeys(w for r in reports for w in r.warnings))
    return TimingReport(dt_s=float(np.median([r.dt_s for r in reports])),
                        n_samples=sum(r.n_samples for r in reports),
                        t_start_s=min(r.t_start_s for r in reports),
                        t_end_s=max(r.t_end_s for r in reports),
                        resampled=any(r.resampled for r in reports),
                        grid='exact' if all(r.grid == 'exact' for r in reports) else 'resampled',
                        topics=topics, recovery=recovery or {}, warnings=warnings,
                        missing=_merge_spans([g for r in reports for g in r.missing]))


def _merge_spans(spans: list[list[float]]) -> list[list[float]]:
    """Sorted spans, the same gap seen by overlapping windows once."""
    out: list[list[float]] = []
    for a, b in sorted(spans):
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return out


@dataclass
class Stamps:
    """Cleaned (sorted, de-duplicated) stamps of a topic and their sample indices."""

    ns: np.ndarray  # int64, sorted, unique
    order: np.ndarray  # indices into the raw (file-order) arrays
    k: np.ndarray  # int64 sample index of each stamp relative to ns[0]
    dt_ns: float
    timing: TopicTiming


def valid_header_stamps(ns: np.ndarray) -> bool:
    """
    Header stamps (file order) are usable unless zero ones follow set ones, or all are equal.

    Zero stamps before the first set one are a simulation's sample 0 (stamped t = 0), which
    the lockstep plant re-sends while idle (``ros2 bag record`` keeps every copy; the
    duplicates are dropped by :func:`analyse`).
    """
    if ns.size == 0:
        return False
    unset = ns <= 0
    if unset.any() and (unset.all() or unset[int(np.argmin(unset)):].any()):
        return False
    return ns.size == 1 or bool(np.ptp(ns) > 0)


def analyse(topic: str, stamps: np.ndarray, log: np.ndarray, source: str,
            dt_hint_ns: float | None = None) -> Stamps:
    """Sort/deduplicate ``stamps`` (int64 ns, file order) and measure the topic's timing."""
    tt = TopicTiming(topic=topic, count=int(stamps.size), stamp_source=source)
    tt.non_monotonic = int(np.count_nonzero(np.diff(stamps) < 0))
    order = np.argsort(stamps, kind='stable')
    s = stamps[order]
    keep = np.ones(s.size, dtype=bool)
    keep[1:] = np.diff(s) != 0
    tt.duplicates = int(s.size - np.count_nonzero(keep))
    s, order = s[keep], order[keep]
    if source == 'header' and log.size == stamps.size:
        off = (log[order] - s).astype(float) * 1e-9
        tt.header_log_offset_mean_s = float(off.mean())
        tt.header_log_offset_std_s = float(off.std())
        tt.header_log_offset_max_s = float(np.abs(off).max())
    if s.size < 2:
        dt = float(dt_hint_ns or 1e6)
        return Stamps(s, order, np.zeros(s.size, dtype=np.int64), dt, tt)
    dt, k = _fit_period(s, dt_hint_ns)
    _measure(tt, s, k, dt)
    return Stamps(s, order, k, dt, tt)


def _fit_period(s: np.ndarray, dt_hint_ns: float | None) -> tuple[float, np.ndarray]:
    """
    Sample period and per-stamp sample index.

    Indices accumulate the rounded interval lengths (robust to drops and to a slightly wrong
    first guess); the period is then the least-squares slope of stamps over indices.
    """
    step = np.diff(s).astype(float)
    dt = float(dt_hint_ns or np.median(step))
    for _ in range(2 if dt_hint_ns is None else 1):
        k = np.concatenate(([0], np.cumsum(np.round(step / dt)))).astype(np.int64)
        if dt_hint_ns is not None or k[-1] <= 0:
            break
        kc = k - k.mean()
        rel = (s - s[0]).astype(float)
        dt = float(np.dot(kc, rel - rel.mean()) / np.dot(kc, kc))
    return dt, k


def _measure(tt: TopicTiming, s: np.ndarray, k: np.ndarray, dt: float) -> None:
    tt.dt_s = dt * 1e-9
    tt.rate_hz = 1e9 / dt
    dk = np.diff(k)
    step = np.diff(s).astype(float)
    regular = step[dk == 1]
    tt.jitter = float(regular.std() / dt) if regular.size > 1 else 0.0
    resid = (s - s[0]).astype(float) - k * dt
    tt.stamp_jitter = float(resid.std() / dt)
    gap = dk > 1
    if np.any(gap):
        miss = dk[gap] - 1
        tt.gaps = int(gap.sum())
        tt.missing_samples = int(miss.sum())
        i = int(np.flatnonzero(gap)[np.argmax(miss)])
        tt.longest_gap_samples = int(dk[i] - 1)
        tt.longest_gap_at_s = float(s[i] * 1e-9)
    # two stamps mapped onto one sample index: irregular beyond half a period
    tt.jitter = max(tt.jitter, float(np.count_nonzero(dk == 0)) / max(dk.size, 1))


def check_resampling(st: Stamps, where: str, gaps: str = 'refuse') -> None:
    """
    Check the stamps against the resampling rules.

    Raise BagError when the stamps of ``st`` violate the resampling rules (with
    ``gaps='mark'`` long gaps are allowed: :func:`long_gaps`).
    """
    if gaps not in GAP_MODES:
        raise ValueError(f'{gaps=}: expected one of {GAP_MODES}')
    tt = st.timing
    if tt.jitter >= MAX_JITTER:
        raise BagError(f'stamp jitter of {100 * tt.jitter:.1f} % of dt ({tt.dt_s * 1e3:.3f} ms) '
                       f'in {tt.topic} of {where} exceeds {100 * MAX_JITTER:.0f} %; refusing to '
                       f'resample')
    if gaps == 'refuse' and tt.longest_gap_samples > MAX_GAP_SAMPLES:
        n = tt.longest_gap_samples
        raise BagError(f'gap of {n * tt.dt_s:.3f} s ({n} samples) at t={tt.longest_gap_at_s:.3f} '
                       f's in {tt.topic} of {where} exceeds {MAX_GAP_SAMPLES} samples; refusing '
                       f'to resample (pass t_range to read around it)')


def grid_offset(st: Stamps) -> float:
    """
    Return the intercept of the least-squares grid through the stamps.

    Intercept [ns] of the least-squares grid s = ns[0] + offset + k dt through the stamps
    (0 for stamps exactly on their grid): the uniform grid that jitter does not move.
    """
    if st.ns.size < 2:
        return 0.0
    return float(np.mean((st.ns - st.ns[0]).astype(float) - st.k * st.dt_ns))


def long_gaps(st: Stamps) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the grid index ranges of the samples lost in long gaps.

    Grid index ranges [first, last] of the samples missing in gaps longer than
    MAX_GAP_SAMPLES (two int arrays, one entry per gap).
    """
    dk = np.diff(st.k)
    i = np.flatnonzero(dk > MAX_GAP_SAMPLES + 1)
    return st.k[i] + 1, st.k[i + 1] - 1


def on_exact_grid(st: Stamps) -> bool:
    """Return true if the stamps are gap-free and within 1 ns of s0 + k * dt."""
    if st.ns.size < 2:
        return True
    if np.any(np.diff(st.k) != 1):
        return False
    resid = (st.ns - st.ns[0]).astype(float) - st.k * st.dt_ns
    return bool(np.max(np.abs(resid)) <= 1.0)
