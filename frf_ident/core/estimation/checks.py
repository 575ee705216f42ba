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
Checks that the data support an FRF estimate (pure numpy; scipy.signal-style signatures).

Each check takes the data first and keyword options, returns nothing when the data are fine
and raises :class:`~frf_ident.errors.EstimationError` with one line naming ``where`` (the
file, topic or segment), the value found and what was expected otherwise. They work on any
stretch of data, so an estimator can apply them segment by segment or window by window.

- :func:`check_not_clipped` — the plant input u (motor torque) must not sit at a saturation
  limit: a clipped input makes the estimate a describing function of the saturation, not P.
- :func:`check_band` — every analysed frequency below the Nyquist frequency fs / 2.
- :func:`check_periods` — enough whole steady-state periods of a multisine.
- :func:`check_covers` — a segment lies inside the recorded time span.
- :func:`check_whole_period` — a detected multisine period is a whole number of samples
  (within ``MAX_DRIFT`` samples): otherwise every period's DFT leaks.
- :func:`missing_rows` — the samples a gap removed (NaN rows of a recording read with
  ``gaps='mark'``); :func:`check_remaining` — enough periods or lines are left after
  dropping the ones such gaps touch.

Clipping thresholds (see :func:`clipping`): a side of a channel is clipped when samples equal
to its extreme value (within ``1e-9`` of the channel's range) come in runs of at least
``MIN_RUN`` = 5 consecutive samples, these runs hold at least ``MIN_FRACTION`` = 0.1 % of
the samples, and at least as many samples sit exactly at the extreme as in the band of
``PILEUP_BAND`` = 1 % of the range just inside it (a saturated signal piles up at the limit; a
smooth peak of a quantised signal is approached gradually, so the band holds more). A float
signal with noise practically never repeats its extreme value; a quantised sensor repeats it
at a slow peak a few times, which the run length, the fraction and the pile-up keep apart.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from frf_ident.errors import EstimationError
import numpy as np

__all__ = ['MAX_DRIFT', 'MIN_FRACTION', 'MIN_RUN', 'PILEUP_BAND', 'Clipping', 'check_band',
           'check_covers', 'check_not_clipped', 'check_periods', 'check_remaining', 'clipping',
           'check_whole_period', 'missing_rows']

MAX_DRIFT = 0.05       # samples per period a detected multisine period may be off whole
MIN_RUN = 5            # consecutive samples at the extreme value
MIN_FRACTION = 1e-3    # of all samples, in such runs
PILEUP_BAND = 0.01     # of the peak-to-peak range: the band just inside the extreme


@dataclass
class Clipping:
    """
    Saturation statistics of one channel over the given stretches of data.

    Parameters
    ----------
    low, high : float
        Smallest and largest finite value [unit of the data] (NaN when none is finite).
    clipped_low, clipped_high : bool
        Whether that side sits at its extreme in the sense of the module thresholds.
    fraction : float
        Share of all samples in qualifying runs at a clipped side (0 if none).
    longest_run : int
        Longest run of samples at a clipped side (0 if none).

    """

    low: float
    high: float
    clipped_low: bool
    clipped_high: bool
    fraction: float
    longest_run: int

    @property
    def clipped(self) -> bool:
        """Return true when either side is clipped."""
        return self.clipped_low or self.clipped_high

    def level(self, unit: str = '') -> str:
        """
        Return the clipping level or levels as text.

        For example '+-150 N m', '+150 N m' or '-150 and +148 N m'.

        Parameters
        ----------
        unit : str, optional
            Unit appended to the numbers (e.g. 'N m'); default none.

        Returns
        -------
        str
            Both extremes when both sides are clipped ('+-' when they are symmetric), else
            the clipped one; meaningful only when :attr:`clipped` is true.

        """
        u = f' {unit}' if unit else ''
        lo, hi = self.low, self.high
        if self.clipped_low and self.clipped_high:
            if np.isclose(-lo, hi, rtol=1e-6):
                return f'+-{hi:.4g}{u}'
            return f'{lo:+.4g} and {hi:+.4g}{u}'
        return f'{(hi if self.clipped_high else lo):+.4g}{u}'


def _runs(mask: np.ndarray) -> np.ndarray:
    """Lengths of the runs of True in a 1-D boolean array."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return np.flatnonzero(d == -1) - np.flatnonzero(d == 1)


def _side(parts: list[np.ndarray], extreme: float, sign: float, span: float,
          min_run: int, min_fraction: float, n_total: int) -> tuple[bool, int, int]:
    """(clipped, samples in qualifying runs, longest run) at one extreme (sign +1 high, -1 low)."""
    tol = 1e-9 * span
    runs = np.concatenate([_runs(np.abs(x - extreme) <= tol) for x in parts])
    long_runs = runs[runs >= min_run]
    n_at = int(long_runs.sum())
    if n_at == 0 or n_at < min_fraction * n_total:
        return False, 0, 0
    inside = sum(int(np.count_nonzero((sign * (extreme - x) > tol)
                                      & (sign * (extreme - x) <= PILEUP_BAND * span)))
                 for x in parts)
    if n_at < inside:
        return False, 0, 0
    return True, n_at, int(long_runs.max())


def clipping(x: np.ndarray | Sequence[np.ndarray], *, min_run: int = MIN_RUN,
             min_fraction: float = MIN_FRACTION) -> list[Clipping]:
    """
    Compute saturation statistics per channel.

    Saturation statistics per channel of ``x``: an (N, n) array or a sequence of them
    (stretches such as segments; runs never continue from one stretch into the next).

    Channels that are constant or not finite everywhere count as not clipped (a constant
    channel has no excitation to clip; a missing interface is all NaN).

    Parameters
    ----------
    x : ndarray, shape (N, n) or (N,), or sequence of them
        The data, one column per channel; stretches must have the same number of columns.
    min_run : int, optional
        Fewest consecutive samples at an extreme value that count as a run.
    min_fraction : float, optional
        Smallest share of all samples in such runs for a side to be clipped.

    Returns
    -------
    list of Clipping
        Statistics of each of the n channels.

    Raises
    ------
    ValueError
        No data, or stretches that are not (N, n) arrays with a common n.

    """
    parts = [np.asarray(p, dtype=float) for p in ([x] if isinstance(x, np.ndarray) else x)]
    parts = [p[:, None] if p.ndim == 1 else p for p in parts]
    if not parts or any(p.ndim != 2 or p.shape[1] != parts[0].shape[1] for p in parts):
        raise ValueError(f'expected (N, n) arrays with a common n, got '
                         f'{[p.shape for p in parts]}')
    n_total = sum(p.shape[0] for p in parts)
    out = []
    for j in range(parts[0].shape[1]):
        cols = [p[:, j] for p in parts if p.shape[0]]
        allv = np.concatenate(cols) if cols else np.zeros(0)
        finite = allv[np.isfinite(allv)]
        if finite.size == 0:
            out.append(Clipping(np.nan, np.nan, False, False, 0.0, 0))
            continue
        lo, hi = float(finite.min()), float(finite.max())
        span = hi - lo
        if span <= 0:
            out.append(Clipping(lo, hi, False, False, 0.0, 0))
            continue
        c_hi, n_hi, r_hi = _side(cols, hi, 1.0, span, min_run, min_fraction, n_total)
        c_lo, n_lo, r_lo = _side(cols, lo, -1.0, span, min_run, min_fraction, n_total)
        out.append(Clipping(lo, hi, c_lo, c_hi, (n_hi + n_lo) / n_total, max(r_hi, r_lo)))
    return out


def check_not_clipped(u: np.ndarray | Sequence[np.ndarray], *, joint_names: Sequence[str],
                      where: str, span: str = 'the analysed segments', field: str = 'effort',
                      unit: str = 'N m', min_run: int = MIN_RUN,
                      min_fraction: float = MIN_FRACTION) -> None:
    """
    Refuse a plant input that is clipped (saturated) in ``u``.

    ``u``: (N, n) torque per joint, or a sequence of such stretches (see :func:`clipping`);
    ``where`` names the data (e.g. 'bag: /joint_states'), ``span`` the stretch analysed,
    ``field`` and ``unit`` the quantity. Raises :class:`EstimationError` naming the most
    clipped joint, its level, the share of samples and the longest run.

    Parameters
    ----------
    u : ndarray, shape (N, n), or sequence of them
        Plant input (torque [N m]) per joint, or stretches of it.
    joint_names : sequence of str
        Names of the n joints, for the message.
    where : str
        What the data are (e.g. 'bag: /joint_states').
    span : str, optional
        The stretch analysed, for the message.
    field : str, optional
        Name of the quantity, for the message.
    unit : str, optional
        Unit of the quantity, for the message.
    min_run : int, optional
        Fewest consecutive samples at an extreme value that count as a run.
    min_fraction : float, optional
        Smallest share of all samples in such runs for a side to be clipped.

    Raises
    ------
    EstimationError
        A joint's input is clipped.
    ValueError
        ``joint_names`` does not match the number of channels of ``u``.

    """
    stats = clipping(u, min_run=min_run, min_fraction=min_fraction)
    if len(stats) != len(joint_names):
        raise ValueError(f'{len(joint_names)=} does not match the {len(stats)} channels of u')
    bad = [(s.fraction, j, s) for j, s in enumerate(stats) if s.clipped]
    if not bad:
        return
    _, j, s = max(bad)
    raise EstimationError(f'{where} {field}[{joint_names[j]}] is clipped at {s.level(unit)} '
                          f'in {100 * s.fraction:.2g} % of the samples of {span} (runs up to '
                          f'{s.longest_run} samples); expected an unsaturated plant input '
                          f'— lower the excitation amplitude')


def check_band(freq_hz: np.ndarray | Sequence[float], fs: float, *, where: str) -> None:
    """
    Refuse analysed frequencies at or above the Nyquist frequency.

    Refuse analysed frequencies at or above the Nyquist frequency ``fs / 2`` (or not
    positive): such lines alias in data sampled at ``fs`` Hz.

    Parameters
    ----------
    freq_hz : array_like
        The analysed frequencies [Hz].
    fs : float
        Sample rate of the data [Hz].
    where : str
        What the frequencies belong to, for the message.

    Raises
    ------
    EstimationError
        No frequency, a sample rate that is not a positive number, a frequency that is not
        positive and finite, or one at or above fs / 2.

    """
    f = np.asarray(freq_hz, dtype=float).reshape(-1)
    if f.size == 0:
        raise EstimationError(f'{where}: no frequencies to analyse')
    if not (np.isfinite(fs) and fs > 0):
        raise EstimationError(f'{where}: sample rate {fs=} must be a positive number of Hz')
    lo, hi = float(np.min(f)), float(np.max(f))
    if not (np.all(np.isfinite(f)) and lo > 0):
        raise EstimationError(f'{where}: frequencies {lo:g}..{hi:g} Hz; expected positive, '
                              f'finite frequencies')
    nyquist = 0.5 * fs
    if hi >= nyquist:
        n_above = int(np.count_nonzero(f >= nyquist))
        raise EstimationError(f'{where}: band {lo:.4g}-{hi:.4g} Hz reaches the Nyquist '
                              f'frequency {nyquist:.4g} Hz of the recording (sampled at '
                              f'{fs:.4g} Hz; {n_above} of {f.size} lines at or above it); '
                              f'expected every line below fs/2 — record faster or lower the '
                              f'band')


def check_periods(n_periods: int, *, need: int = 2, where: str, hint: str = '') -> None:
    """
    Refuse fewer than ``need`` whole steady-state periods.

    Refuse fewer than ``need`` whole steady-state periods (averaging over periods and the
    noise estimate need at least two). ``hint`` is appended to the message (e.g. how to get
    more data).

    Parameters
    ----------
    n_periods : int
        Number of whole steady-state periods available.
    need : int, optional
        Fewest periods accepted.
    where : str
        What the periods belong to, for the message.
    hint : str, optional
        Appended to the message; default none.

    Raises
    ------
    EstimationError
        ``n_periods`` < ``need``.

    """
    if n_periods < need:
        raise EstimationError(f'{where}: {n_periods} whole steady-state period'
                              f'{"" if n_periods == 1 else "s"}; expected at least {need}'
                              f'{f" — {hint}" if hint else ""}')


def check_whole_period(drift: float, period_samples: int, *, where: str,
                       max_drift: float = MAX_DRIFT) -> None:
    """
    Refuse a multisine whose period is not a whole number of samples.

    Refuse a multisine whose true period is ``period_samples + drift`` samples with
    |drift| > ``max_drift``: whole-period DFTs of it leak into the neighbouring lines (the
    excitation was generated on another clock than the one the joint states are sampled on).

    Parameters
    ----------
    drift : float
        Difference of the true period from ``period_samples`` [samples per period].
    period_samples : int
        Period of the multisine in whole samples.
    where : str
        What the multisine belongs to, for the message.
    max_drift : float, optional
        Largest |drift| accepted [samples per period].

    Raises
    ------
    EstimationError
        |drift| > ``max_drift``.

    """
    if abs(drift) > max_drift:
        raise EstimationError(f'{where}: the period is {period_samples + drift:.2f} samples, '
                              f'not a whole number (off by {abs(drift):.2f} samples per period, '
                              f'at most {max_drift:g} allowed): whole-period DFTs would leak; '
                              f'expected a period of whole samples — resample the recording to '
                              f"the excitation's clock, or give the excitation if detection "
                              f'misread it (--chirp, --multisine-period)')


def missing_rows(*series: np.ndarray) -> np.ndarray:
    """
    Mark the samples missing from the given series.

    (N,) True where a sample is missing: NaN in any column of the (N, n) ``series`` that
    holds data elsewhere (a column that is NaN throughout is an interface the robot does
    not publish, not a gap).

    Parameters
    ----------
    *series : ndarray, shape (N, n) or (N,)
        Signals on the same N samples (e.g. position, velocity, effort); at least one.

    Returns
    -------
    ndarray of bool, shape (N,)
        True at the samples a gap removed.

    """
    out = np.zeros(np.asarray(series[0]).shape[0], dtype=bool)
    for x in series:
        bad = ~np.isfinite(np.asarray(x, dtype=float))
        if not bad.any():
            continue        # the usual case, at a quarter of the cost of the row reductions
        if bad.ndim == 1:
            bad = bad[:, None]
        present = ~np.all(bad, axis=0)
        out |= np.any(bad[:, present], axis=1)
    return out


def check_remaining(n_used: int, n_dropped: int, *, need: int, what: str, where: str,
                    dropped_at: Sequence[tuple[float, float]] = (), hint: str = '') -> None:
    """
    Refuse when too few periods remain after dropping those gaps touched.

    Refuse when fewer than ``need`` ``what`` (e.g. 'periods') remain after dropping
    ``n_dropped`` that gaps touched; the message says when the first dropped ones were.

    Parameters
    ----------
    n_used : int
        Number of periods (or lines) left without missing samples.
    n_dropped : int
        Number dropped because a gap touched them.
    need : int
        Fewest accepted.
    what : str
        What is counted (e.g. 'periods'), for the message.
    where : str
        What the data belong to, for the message.
    dropped_at : sequence of tuple of float, optional
        (start, end) [s] of the dropped ones; the first four are named in the message.
    hint : str, optional
        Appended to the message; default none.

    Raises
    ------
    EstimationError
        ``n_used`` < ``need``.

    """
    if n_used >= need:
        return
    at = ', '.join(f'{a:.3f}..{b:.3f} s' for a, b in list(dropped_at)[:4])
    more = ' ...' if len(dropped_at) > 4 else ''
    raise EstimationError(f'{where}: {n_used} {what} without missing samples remain of '
                          f'{n_used + n_dropped} ({n_dropped} dropped for gaps'
                          f'{f" at {at}{more}" if at else ""}); expected at least {need}'
                          f'{f" — {hint}" if hint else ""}')


def check_covers(t_first: float, t_last: float, t_start: float, t_end: float, *,
                 where: str, dt: float = 0.0, hint: str = '') -> None:
    """
    Refuse a segment that the recorded span does not cover.

    Refuse a segment [t_start, t_end] that the recorded span [t_first, t_last] (sample
    times, spacing ``dt``) does not cover; half a sample of slack at either end.

    Parameters
    ----------
    t_first, t_last : float
        Times of the first and last recorded sample [s].
    t_start, t_end : float
        Start and end of the segment [s].
    where : str
        What the segment is, for the message.
    dt : float, optional
        Sample spacing [s]; the last sample covers until ``t_last + dt``. Default 0: no
        slack.
    hint : str, optional
        Appended to the message; default none.

    Raises
    ------
    EstimationError
        The segment starts before or ends after the recorded span.

    """
    slack = 0.5 * dt
    if t_start < t_first - slack or t_end > t_last + dt + slack:
        raise EstimationError(f'{where}: segment {t_start:.3f}..{t_end:.3f} s but the data '
                              f'cover {t_first:.3f}..{t_last:.3f} s; expected the whole '
                              f'segment{f" — {hint}" if hint else ""}')


def check_rate(fs: float, design_fs: float, *, where: str, rtol: float = 1e-3) -> None:
    """
    Refuse data sampled at another rate than the design's.

    Refuse data sampled at ``fs`` when the design counts samples at ``design_fs``
    (e.g. /joint_states decimated after the experiment): periods would not line up.
    """
    if not abs(fs - design_fs) <= rtol * design_fs:
        raise EstimationError(f'{where}: designed for {design_fs:.6g} Hz sampling but the '
                              f'recording is sampled at {fs:.6g} Hz; expected the design rate '
                              f'(periods are counted in samples)')


# --------------------------------------------------------------------------- recordings

JOINT_STATES = '/joint_states'   # docs/CONTRACT.md §3: where effort (u) comes from
EXPERIMENT = '/frf/experiment'   # where the segment descriptors come from


def _span_text(rec, seg) -> str:
    return (f'segment {seg.t_start:.3f}..{seg.t_end:.3f} s'
            + ''.join(f' {k} {seg.info[k]}' for k in ('realisation', 'experiment', 'iteration')
                      if k in seg.info))


def _covered(rec) -> str:
    return f'the data cover {rec.t[0]:.3f}..{rec.t[-1]:.3f} s'


def check_multisine_segments(rec, segments) -> list:
    """
    Check the descriptor multisine segments of a recording.

    Band, sample rate and whole steady-state periods of descriptor multisine segments
    (``info`` keys of :func:`frf_ident.core.excitation.multisine_procedure.multisine_procedure`);
    returns the analysed (steady-state) effort of each segment, (N_i, n) arrays, for the
    clipping check.
    """
    info = segments[0].info
    dp = info['design_params']
    where = f'{EXPERIMENT} multisine design'
    check_band(np.asarray(dp['harmonics']) * dp['f0'], rec.fs, where=where)
    n_per, n_tr = info['period_samples'], info['transient_periods']
    check_rate(rec.fs, n_per * dp['f0'], where=where)
    n_p = 1 + max(s.info['realisation'] for s in segments)
    # a segment stopped at its uncertainty target holds fewer periods than designed
    # (its end descriptor says how many): those it holds must all be there
    n_all = sum(int(s.info['periods']) for s in segments
                if s.info['experiment'] == segments[0].info['experiment'])
    if n_all < 2:
        check_periods(n_all, need=2, where=f'{where} ({n_p} realisation of {n_all} '
                      f'period)', hint='nothing to average; record more periods')
    parts = []
    for s in segments:
        n_q = int(s.info['periods'])
        sl = rec.slice(s.t_start, s.t_end)
        n_avail = max(0, sl.stop - sl.start)
        have = max(0, n_avail - n_tr * n_per) // n_per
        check_periods(min(have, n_q), need=n_q,
                      where=f'multisine {_span_text(rec, s)} ({n_tr} transient period(s) of '
                            f'{n_per} samples first)',
                      hint=f'{_covered(rec)}; a time range must include the whole segment')
        i0 = sl.start + n_tr * n_per
        parts.append(rec.effort[i0:i0 + n_q * n_per])
    return parts


def check_chirp_segments(rec, segments) -> list:
    """Band and coverage of the analysed chirp iteration's segments; returns their effort."""
    parts = []
    for s in segments:
        dp = s.info.get('design_params', {})
        band = list(s.info.get('freq_hz', [])) + [dp[k] for k in ('f_low', 'f_high') if k in dp]
        check_band(band, rec.fs, where=f'{EXPERIMENT} chirp design')
        check_covers(rec.t[0], rec.t[-1], s.t_start, s.t_end, dt=rec.dt,
                     where=f'chirp {_span_text(rec, s)}',
                     hint='a time range must include the whole sweep')
        parts.append(rec.effort[rec.slice(s.t_start, s.t_end)])
    return parts


def check_descriptor_recording(rec) -> None:
    """
    Run every check of a recording with /frf/experiment descriptors.

    Every check of a recording with /frf/experiment descriptors: the multisine segments and
    the last chirp iteration (the ones
    :func:`frf_ident.core.estimation.described.estimate_recording` analyses), then clipping
    of the effort in each design's analysed samples.
    """
    ms = [s for s in rec.segments if s.info.get('design') == 'multisine']
    ch = [s for s in rec.segments if s.info.get('design') == 'chirp']
    designs = []
    if ms:
        designs.append(('multisine', check_multisine_segments(rec, ms)))
    if ch:
        last = max(s.info['iteration'] for s in ch)
        designs.append((f'chirp iteration {last}',
                        check_chirp_segments(rec, [s for s in ch
                                                   if s.info['iteration'] == last])))
    for name, parts in designs:
        check_not_clipped(parts, joint_names=rec.joint_names, where=JOINT_STATES,
                          span=f'the {name} segments')
