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
Assemble collected messages into a uniformly sampled :class:`Recording`.

The joint states are put on a uniform time grid (the writer's exact grid, stamps already on a
grid, or linear interpolation when jitter allows it), the velocity commands and the excitation
are matched or held onto that grid, gaps are refused or marked, and every finding goes into
the :class:`~frf_ident.bag.timing.TimingReport`. Shared by ``read_recording`` and the
window reader (:mod:`frf_ident.bag.windows`), so a window equals the same range of the bag.
"""
from __future__ import annotations

import math
from typing import Any

from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import BagError
import numpy as np

from . import timing as tm
from .collect import Collector
from .coverage import cut_warning, split_covered
from .layout import BagFiles
from .pairing import align_effort, effort_lag
from .topics import BagTopics
from .writer import FRF_BAG_KEY, grid_times

#: what a gap of more than :data:`~frf_ident.bag.timing.MAX_GAP_SAMPLES` missing joint states
#: becomes unless a caller says otherwise: 'mark' keeps it as missing data (NaN rows, listed in
#: the report), which estimate, diagnose and the streamed estimate all need; 'refuse' (a
#: one-line BagError) is for callers that cannot handle missing samples
DEFAULT_GAPS = 'mark'


def _stamp_source(ns: np.ndarray) -> str:
    return 'header' if tm.valid_header_stamps(ns) else 'log'


def _window(ns: np.ndarray, t_range: tuple[float, float] | None) -> np.ndarray:
    if t_range is None:
        return np.ones(ns.size, dtype=bool)
    lo, hi = (int(round(x * 1e9)) for x in t_range)
    return (ns >= lo) & (ns <= hi)


def assemble(bag: BagFiles, col: Collector, topics: BagTopics, meta: dict[str, Any],
             segments: list[Segment], warnings: list[str], recovery: dict[str, Any],
             t_range: tuple[float, float] | None, gaps: str
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


__all__ = ['DEFAULT_GAPS', 'assemble']
