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
The multisine estimate (Secs. 4.3, 4.4): BLA over realisations x periods from its segments.

:class:`MultisineSpectra` gathers the DFT lines of each segment's steady periods (with the
constant-velocity run's, :mod:`~frf_ident.core.estimation.compensation`, and the samples a gap
took estimated from the other periods), then gives the best linear approximation (eq. 14) by
the reference-based estimator or the plain Y U^+ (eq. 7), with detection lines and
distortion levels.
"""
from __future__ import annotations

from typing import Any

from frf_ident.core.estimation.channels import channel_names, segment_arrays
from frf_ident.core.estimation.checks import check_remaining, EXPERIMENT, missing_rows
from frf_ident.core.estimation.compensation import disturbance_at
from frf_ident.core.estimation.distortion import distortion_lines
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.missing import MissingSamples
from frf_ident.core.estimation.missing_periodic import fill_periods, FilledPeriods, GAP_HINT
from frf_ident.core.estimation.segment_counts import (expected_experiments, planned_periods,
                                                      segment_periods)
from frf_ident.core.estimation.spectra import (best_linear_approximation,
                                               best_linear_approximation_reference, BLAResult,
                                               detection_levels_from_spectra,
                                               detection_line_spectra, periodic_spectra)
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import EstimationError
import numpy as np


def _filled_series(x: dict[str, np.ndarray], gone: np.ndarray,
                   names: tuple[list[str], list[str]]
                   ) -> tuple[dict[str, np.ndarray], FilledPeriods,
                              dict[bool, MissingSamples]] | None:
    """
    Return a segment's steady series with their missing samples estimated, or None.

    ``x`` holds (n_q, n_per, n) arrays u, y, r (and du, dy with a constant-velocity run),
    ``gone`` (n_q, n_per) the missing samples. u and y are estimated together (the account's
    channels), r alone (periodic: exactly). With a run the compensated series x - d are
    estimated, which the compensated BLA uses, and d becomes what gives them. Also the
    periods' :class:`FilledPeriods` and the account per ``compensate``. None where a sample
    is missing in every period (nothing to estimate it from).
    """
    n = x['u'].shape[2]
    channels = names[0] + names[1]
    uy = fill_periods(np.concatenate([x['u'], x['y']], axis=2), gone)
    r = fill_periods(x['r'], gone)
    if not (uy.complete and r.complete):
        return None
    out = {'u': uy.values[..., :n], 'y': uy.values[..., n:], 'r': r.values}
    missing = {False: uy.account(channels)}
    if 'du' in x:
        c = fill_periods(np.concatenate([x['u'] - x['du'], x['y'] - x['dy']], axis=2), gone)
        out['du'] = out['u'] - c.values[..., :n]
        out['dy'] = out['y'] - c.values[..., n:]
        missing[True] = c.account(channels)
    return out, uy.periods(), missing


class MultisineSpectra:
    """
    DFT lines of a multisine experiment, gathered one segment at a time.

    Each (realisation p, experiment m) segment contributes the spectra of its steady-state
    periods at the excited bins (u, y, r) and, when a constant-velocity run was added first,
    the spectra of that run's series as subtracted from it (Sec. 4.4 E; the DFT is linear, so
    X - D equals the spectrum of the compensated series). Memory is one segment plus the
    spectra, so a bag longer than memory can be estimated window by window.
    """

    def __init__(self, info: dict[str, Any], *, align: str = 'position') -> None:
        self.info = info
        self.align = align
        self.bins = np.asarray(info['design_params']['harmonics'])
        # the design's periods per segment; a segment stopped at its uncertainty target holds
        # fewer (segment_counts.segment_periods), the rest count as never run, not as dropped
        self.n_per, self.n_q = int(info['period_samples']), planned_periods(info)
        self.n_tr = int(info['transient_periods'])
        self.cv: dict[str, np.ndarray] | None = None
        self._tables: dict[tuple[str, int], Any] = {}    # compensation: position table per axis
        self.spec: dict[tuple[int, int], dict[str, np.ndarray]] = {}
        self.joint_names: list[str] = []

    def add_constant_velocity(self, rec: Recording, seg: Segment) -> None:
        """Return the constant-velocity run (Sec. 4.4 E); add it before the multisine segments."""
        self.set_constant_velocity(segment_arrays(rec, seg))

    def set_constant_velocity(self, arrays: dict[str, np.ndarray]) -> None:
        """
        Take the constant-velocity run's series (u, y, r, q; Sec. 4.4 E).

        Parameters
        ----------
        arrays : dict of str to ndarray, shape (N, n)
            Its effort, velocity, excitation and position from its first sample.

        Raises
        ------
        EstimationError
            Multisine segments were added before it.

        """
        if self.spec:
            raise EstimationError('the constant-velocity run must come before the multisine '
                                  'segments it compensates')
        self.cv = arrays
        self._tables = {}

    def add(self, rec: Recording, seg: Segment) -> None:
        """One multisine segment of ``rec``."""
        self.add_arrays(segment_arrays(rec, seg), seg.info, seg.t_start, rec.fs,
                        rec.joint_names)

    def add_arrays(self, a: dict[str, np.ndarray], info: dict[str, Any], t_start: float,
                   fs: float, joint_names: list[str]) -> None:
        """
        Add one multisine segment (or the whole periods of one so far) from its series.

        Parameters
        ----------
        a : dict of str to ndarray, shape (N, n)
            The segment's effort ``u``, velocity ``y``, excitation ``r`` and position ``q``
            from its first sample.
        info : dict
            Its descriptor; ``periods`` the steady periods it holds
            (:func:`~frf_ident.core.estimation.segment_counts.segment_periods`).
        t_start : float
            Its start [s].
        fs : float
            Sample rate [Hz].
        joint_names : list of str
            The joints of the columns.

        Raises
        ------
        EstimationError
            Fewer samples than its transient and steady periods.

        """
        n_q = segment_periods(info)
        need = (self.n_tr + n_q) * self.n_per
        if a['u'].shape[0] < need:
            raise EstimationError(f'multisine segment at t={t_start:.3f} s has '
                                  f'{a["u"].shape[0]} samples, expected {need} '
                                  f'({self.n_tr} transient + {n_q} periods of '
                                  f'{self.n_per})')
        self.joint_names = list(joint_names)
        steady = slice(self.n_tr * self.n_per, need)
        shape = (n_q, self.n_per, len(joint_names))

        def lines(x: np.ndarray) -> np.ndarray:          # (n_q, F, n)
            # zeroing costs a copy and three passes: only where a gap left NaN
            x = x if np.isfinite(x).all() else np.nan_to_num(x)
            return periodic_spectra(x, self.bins, axis=1)
        series = {k: a[k][:need] for k in ('u', 'y', 'r')}
        if self.cv is not None:
            for k in ('u', 'y'):
                series['d' + k] = disturbance_at(self.cv, k, a['q'][:need], self.align,
                                                 self._tables)
        steady_x = {k: x[steady].reshape(shape) for k, x in series.items()}
        # a sample missing in any series (NaN rows: gaps) is estimated from the other periods
        # (missing_periodic.py) and the period kept; only where a sample is missing in every
        # period is the period dropped, as are the periods a gap touches then
        gone = missing_rows(*(x[steady] for x in series.values())).reshape(n_q, self.n_per)
        filled = _filled_series(steady_x, gone, channel_names(self.joint_names)) if gone.any() \
            else None
        out = {k: lines(x) for k, x in (filled[0] if filled else steady_x).items()}
        out['valid'] = np.ones(n_q, bool) if filled else ~gone.any(axis=1)
        if filled:
            out['filled'], out['missing'] = filled[1], filled[2]
        if info['experiment'] == 0:                     # detection lines (Sec. 4.3 remark)
            src = filled[0] if filled else steady_x
            for k in ('y', 'dy') if 'dy' in src else ('y',):
                _, out['det_' + k] = detection_line_spectra(
                    np.nan_to_num(src[k]), int(self.bins[-1]), axis=1)
        # a run stopped at its uncertainty target holds fewer periods: padded, not valid
        out = {k: _pad_periods(v, self.n_q) for k, v in out.items()}
        out['run'] = n_q
        t_first = t_start + self.n_tr * self.n_per / fs
        out['t'] = t_first + np.arange(self.n_q + 1) * self.n_per / fs
        self.spec[(info['realisation'], info['experiment'])] = out

    def _shape(self) -> tuple[int, int]:
        """n_p realisations and n_ex experiments the design has (one per axis, eq. 9)."""
        n_p = 1 + max(p for p, _ in self.spec)
        # a realisation cut short in its last experiment lacks one no other realisation shows
        return n_p, expected_experiments({m for _, m in self.spec}, self.info)

    def _complete(self, p: int, n_ex: int) -> bool:
        return all((p, m) in self.spec for m in range(n_ex))

    def any_complete(self) -> bool:
        """
        Whether some realisation has every experiment's segment.

        Returns
        -------
        bool
            False when every realisation was cut short (then :meth:`frf` is refused).

        """
        n_p, n_ex = self._shape()
        return any(self._complete(p, n_ex) for p in range(n_p))

    def _check_complete(self) -> tuple[int, int]:
        """
        Return n_p and n_ex; a realisation missing an experiment's segment takes no part.

        Its run was cut short (the bag reader leaves out a segment that never ended), so its
        periods count as dropped (:meth:`dropped`); refused only when no realisation is
        complete.
        """
        n_p, n_ex = self._shape()
        if not self.any_complete():
            missing = [(p, m) for p in range(n_p) for m in range(n_ex)
                       if (p, m) not in self.spec]
            raise EstimationError(f'no multisine realisation is complete: expected {n_p} '
                                  f'realisation(s) x {n_ex} experiments (one per axis), missing '
                                  f'(realisation, experiment) = {missing[:4]} (a run cut short '
                                  f'or a time range that leaves them out)')
        return n_p, n_ex

    def used_periods(self) -> dict[int, np.ndarray]:
        """
        Return the periods of each realisation without missing samples.

        Realisation p -> indices of its periods without missing samples in any of its
        experiments (period q of a MIMO realisation is one estimate made of the n_ex
        experiments' period q, so a gap in one removes it); realisations left without a
        period are absent.
        """
        n_p, n_ex = self._check_complete()
        out = {}
        for p in range(n_p):
            if not self._complete(p, n_ex):
                continue
            ok = np.all([self.spec[(p, m)]['valid'] for m in range(n_ex)], axis=0)
            if np.any(ok):
                out[p] = np.flatnonzero(ok)
        return out

    def dropped(self) -> dict[str, Any]:
        """
        Report the periods that gaps removed.

        What gaps removed: the count and, per dropped period, realisation, period index and
        times [s] of the segment whose samples were missing; ``incomplete`` lists the
        realisations missing a segment (cut short), whose periods count as dropped.
        """
        n_p, n_ex = self._check_complete()
        used = self.used_periods()
        items = []
        for p in range(n_p):
            for q in range(self.n_q):
                if p in used and q in used[p]:
                    continue
                for m in range(n_ex):
                    s = self.spec.get((p, m))
                    if s is not None and q < s['run'] and not s['valid'][q]:
                        items.append({'realisation': p, 'experiment': m, 'period': q,
                                      't_start': float(s['t'][q]),
                                      't_end': float(s['t'][q + 1])})
        return {'periods': sum(self.periods_run(p, n_ex) for p in range(n_p))
                - sum(v.size for v in used.values()),
                'realisations': [p for p in range(n_p) if p not in used], 'items': items,
                'incomplete': [p for p in range(n_p) if not self._complete(p, n_ex)]}

    def periods_run(self, p: int, n_ex: int) -> int:
        """
        Return the MIMO periods realisation ``p`` ran: the fewest of its experiments.

        A realisation missing an experiment's segment (cut short) ran the design's periods
        (they count as dropped); one stopped at the uncertainty target ran fewer in its last
        experiment, and its other experiments' later periods make no MIMO period.
        """
        return min((self.spec[(p, m)]['run'] if (p, m) in self.spec else self.n_q)
                   for m in range(n_ex))

    def period_spectra(self, key: str, compensate: bool) -> list[np.ndarray]:
        """
        Return the spectra of every used period, one (n_q_p, F, n, n_ex) array per realisation.

        Parameters
        ----------
        key : {'u', 'y', 'r'}
            The series.
        compensate : bool
            Subtract the constant-velocity run's (not for 'r').

        Returns
        -------
        list of ndarray

        """
        return self._stack(key, compensate)

    def _stack(self, key: str, compensate: bool) -> list[np.ndarray]:
        """One (n_q_p, F, n, n_ex) array per realisation that kept periods."""
        _, n_ex = self._check_complete()
        rows = []
        for p, qs in self.used_periods().items():
            row = []
            for m in range(n_ex):
                s = self.spec[(p, m)]
                x = s[key]
                if compensate and key != 'r':
                    if 'd' + key not in s:
                        raise EstimationError('compensation requested but the recording has '
                                              'no constant-velocity run')
                    x = x - s['d' + key]
                row.append(x[qs])
            rows.append(np.stack(row, axis=-1))          # (n_q_p, F, n, n_ex)
        return rows

    def _filled(self, used: dict[int, np.ndarray], compensate: bool
                ) -> tuple[list[FilledPeriods] | None, MissingSamples | None]:
        """
        Return per used realisation its periods' :class:`FilledPeriods`, and the account.

        A MIMO period is made of the n_ex experiments' periods: its lost share and variance
        factor are their means. (None, None) when no used segment had a missing sample.
        """
        _, n_ex = self._check_complete()
        segs = [[self.spec[(p, m)] for m in range(n_ex)] for p in used]
        if not any('filled' in s for row in segs for s in row):
            return None, None
        filled, missing = [], None
        for row, qs in zip(segs, used.values()):
            lost = np.mean([s['filled'].lost[qs] if 'filled' in s else np.zeros(qs.size)
                            for s in row], axis=0)
            factor = np.mean([s['filled'].factor[qs] if 'filled' in s else np.ones(qs.size)
                              for s in row], axis=0)
            filled.append(FilledPeriods(lost, factor))
            for s in row:
                if 'missing' in s:
                    missing = s['missing'][compensate].merged(missing)
        return filled, missing

    def frf(self, *, compensate: bool = True, method: str = 'reference'
            ) -> tuple[FrequencyResponse, BLAResult]:
        """
        Multisine best linear approximation (eq. 14) of the gathered segments.

        method 'reference': P_p = (sum_q Y R^H)(sum_q U R^H)^-1 per realisation, averaged
        over p; 'plain': P[p,q] = Y U^+ (eq. 7) per period, averaged over p and q. Periods
        whose missing samples were estimated from the other periods are used, the noise
        variance corrected for them (:meth:`_filled`); a period holding a sample missing in
        every period is dropped (:meth:`used_periods`); fewer than two left is refused.
        """
        if not self.spec:
            raise EstimationError('recording has no multisine segments')
        used = self.used_periods()
        drop = self.dropped()
        n_used = sum(v.size for v in used.values())
        check_remaining(n_used, drop['periods'], need=2, what='multisine periods',
                        where=f'{EXPERIMENT} multisine',
                        dropped_at=[(d['t_start'], d['t_end']) for d in drop['items']],
                        hint=f'{GAP_HINT}; record again or more realisations')
        spec = {k: self._stack(k, compensate) for k in ('y', 'u', 'r')}
        filled, missing = self._filled(used, compensate)
        if method == 'reference':
            bla = best_linear_approximation_reference(spec['y'], spec['u'], spec['r'],
                                                      filled=filled)
        elif method == 'plain':
            bla = best_linear_approximation(spec['y'], spec['u'], filled=filled)
        else:
            raise ValueError(f"{method=} must be 'reference' or 'plain'")
        first = [(self.spec[(p, 0)], qs) for p, qs in used.items()]
        Yd = [(s['det_y'] - s['det_dy'] if compensate else s['det_y'])[qs] for s, qs in first]
        det = detection_levels_from_spectra(
            Yd, np.arange(1, Yd[0].shape[1] + 1), self.bins)
        ins, outs = channel_names(self.joint_names)
        f0 = self.info['design_params']['f0']
        dist = distortion_lines(Yd, np.arange(1, Yd[0].shape[1] + 1), self.bins, f0, outs)
        # their noise is the spread over the first experiment's periods: estimated samples
        # reduce it (missing_periodic.FilledPeriods)
        scale = np.mean([FilledPeriods(s['filled'].lost[qs], s['filled'].factor[qs])
                         .spread_scale() for s, qs in first if 'filled' in s] or [1.0])
        if scale != 1.0:
            det.noise = None if det.noise is None else det.noise * scale
            dist.noise = None if dist.noise is None else dist.noise * scale
        frf = FrequencyResponse(self.bins * f0, bla.response, ins, outs, bla.noise_variance,
                                bla.total_variance, {
                                    'design': 'multisine', 'method': method,
                                    'compensated': compensate, 'alignment': self.align,
                                    'n_p': len(used), 'n_q': int(self.n_q),
                                    'periods_used': {int(p): int(v.size)
                                                     for p, v in used.items()},
                                    'dropped': drop,
                                    **({'missing': missing.to_dict()} if missing else {}),
                                    'cond_max': float(np.max(bla.cond)),
                                    'detection_lines': det.to_dict(),
                                    'distortion': dist.to_dict()})
        return frf, bla


def _pad_periods(x: Any, n_q: int) -> Any:
    """Pad a per-period array (axis 0) to ``n_q`` periods: zeros, ``False`` validity."""
    if not isinstance(x, np.ndarray) or x.shape[0] >= n_q:
        return x
    pad = np.zeros((n_q - x.shape[0],) + x.shape[1:], dtype=x.dtype)
    return np.concatenate([x, pad])
