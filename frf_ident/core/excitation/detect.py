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
Detect the excitation in a measured signal: periodic multisine or exponential chirp.

For data recorded by other tools (a robot's own bag, a CSV/MAT import) the experiment
descriptors of ``/frf/experiment`` are missing; these detectors recover the design from the
signal itself (pure numpy/scipy, no bag or ROS imports).

- :func:`detect_multisine` — period (autocorrelation peak, the smallest lag that matches),
  the block of whole periods (where consecutive periods agree), excited DFT lines and whether
  they are odd multiples of f0 (Saupe & Knoblach 2015, Sec. 4).
- :func:`detect_chirp` — exponential chirp f(t) = exp(a0 t + a1) (eq. 16): instantaneous
  frequency from zero crossings (with hysteresis) and a robust log-linear fit; band
  [f_low, f_high] and the active interval [t0, t1] from a least-squares on-/offset fit.
- :func:`detect_excitation` — tries both, returns whichever was found.

Signals are ``(N,)`` arrays sampled uniformly at ``fs``; ``(N, n)`` arrays are reduced to the
channel with the largest RMS (all channels of a MIMO experiment share the design). NaN marks
missing samples (gaps in a recording): they are bridged linearly for the search and never
count against the periodicity of the data around them.

:func:`excitation_source` decides which signal of a recording the excitation is detected on
(the commanded velocity reference when there is one, else the torque); the estimators and the
importer both use it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from frf_ident.core.excitation.sweep_law import (fit_sweep_laws, half_cycles, LAW_MARGIN,
                                                 robust_law_fit)
from frf_ident.errors import EstimationError
import numpy as np
from scipy import fft as sfft
from scipy import signal

__all__ = ['MIN_FINITE', 'ChirpDetection', 'MultisineDetection', 'detect_chirp',
           'detect_excitation', 'detect_multisine', 'excitation_source', 'multisine_at_period',
           'period_drift']

#: share of finite samples a signal needs: a reference that is commanded less often than
#: this is not the excitation source, and detection refuses sparser signals
MIN_FINITE = 0.5


# --------------------------------------------------------------------------- results

@dataclass
class MultisineDetection:
    """
    A periodic (multisine) excitation found in a signal.

    Parameters
    ----------
    fs : float
        Sample rate [Hz].
    period_samples : int
        Samples per period P.
    n_periods : int
        Whole periods in the periodic block.
    start : int
        Index of the first sample of the periodic block.
    f0 : float
        Fundamental fs / P [Hz].
    harmonics : ndarray of int
        Excited DFT lines h (frequency h * f0), sorted.
    odd : bool
        True when every excited line is an odd multiple of f0.
    correlation : float
        Normalised autocorrelation at lag P (1 = identical periods).
    line_level_db : float
        Weakest excited line over the median non-excited line [dB].
    channel : int, optional
        Column of a 2-D input that was analysed (default 0).
    drift : float, optional
        How far the true period exceeds ``period_samples`` [samples] (measured from the
        phase of the excited lines between the first and last period; 0 for a period of
        whole samples).

    Attributes
    ----------
    kind : str
        Always 'multisine' (not a constructor parameter).

    """

    fs: float
    period_samples: int
    n_periods: int
    start: int
    f0: float
    harmonics: np.ndarray
    odd: bool
    correlation: float
    line_level_db: float
    channel: int = 0
    drift: float = 0.0
    kind: str = field(default='multisine', init=False)

    @property
    def freq_hz(self) -> np.ndarray:
        """Excited frequencies h * f0 [Hz]."""
        return self.harmonics * self.f0

    @property
    def period(self) -> float:
        """Period duration [s]."""
        return self.period_samples / self.fs

    @property
    def stop(self) -> int:
        """Index one past the last sample of the periodic block."""
        return self.start + self.n_periods * self.period_samples

    def describe(self) -> str:
        """
        One sentence a person can check against the design.

        Returns
        -------
        str
            Period, number of whole periods, start, excited lines, line level and period
            correlation.

        """
        f = self.freq_hz
        lines = (f'{f.size} excited lines {f[0]:.3g}-{f[-1]:.3g} Hz, '
                 + ('all odd multiples of f0' if self.odd else 'not all odd multiples of f0'))
        return (f'{"odd " if self.odd else ""}multisine: period {self.period_samples} samples '
                f'({self.period:.6g} s, f0 = {self.f0:.6g} Hz), {self.n_periods} whole periods '
                f'from sample {self.start} (t = {self.start / self.fs:.3f} s), {lines} '
                f'(weakest line {self.line_level_db:.0f} dB above the rest, '
                f'period correlation {self.correlation:.3f})')

    def to_dict(self) -> dict[str, Any]:
        """
        JSON-ready summary.

        Returns
        -------
        dict
            Every field (``harmonics`` as a list) plus ``freq_hz``, the excited frequencies
            [Hz].

        """
        return {'kind': self.kind, 'fs': self.fs, 'period_samples': self.period_samples,
                'n_periods': self.n_periods, 'start': self.start, 'f0': self.f0,
                'harmonics': self.harmonics.tolist(), 'freq_hz': self.freq_hz.tolist(),
                'odd': self.odd, 'correlation': self.correlation,
                'line_level_db': self.line_level_db, 'channel': self.channel,
                'drift': self.drift}


@dataclass
class ChirpDetection:
    """
    An exponential chirp f(t) = exp(a0 t + a1) on [t0, t1] (eq. 16) found in a signal.

    Times are seconds from the first sample (index 0 is t = 0).

    Parameters
    ----------
    fs : float
        Sample rate [Hz].
    f_low, f_high : float
        Instantaneous frequency at t0 and t1 [Hz] (f_low > f_high for a down-sweep).
    t0, t1 : float
        Start and end of the active chirp [s].
    a0, a1 : float
        Eq. 16 coefficients (a0 = sweep rate [1/s]).
    n_half_cycles : int
        Half cycles used in the fit (inliers).
    fit_residual : float
        Standard deviation of ln f around the fit (relative frequency error).
    channel : int, optional
        Column of a 2-D input that was analysed (default 0).

    Attributes
    ----------
    kind : str
        Always 'chirp' (not a constructor parameter).

    """

    fs: float
    f_low: float
    f_high: float
    t0: float
    t1: float
    a0: float
    a1: float
    n_half_cycles: int
    fit_residual: float
    channel: int = 0
    kind: str = field(default='chirp', init=False)

    @property
    def duration(self) -> float:
        return self.t1 - self.t0

    @property
    def start(self) -> int:
        """Index of the first sample of the chirp."""
        return int(round(self.t0 * self.fs))

    @property
    def stop(self) -> int:
        """Index one past the last sample of the chirp."""
        return int(round(self.t1 * self.fs)) + 1

    def frequency(self, t: np.ndarray | float) -> np.ndarray:
        """
        Instantaneous frequency exp(a0 t + a1) [Hz] (eq. 16).

        Parameters
        ----------
        t : float or array_like
            Time [s] from the first sample.

        Returns
        -------
        ndarray
            Frequency [Hz], shaped as ``t``.

        """
        return np.exp(self.a0 * np.asarray(t, dtype=float) + self.a1)

    def describe(self) -> str:
        """
        One sentence a person can check against the design.

        Returns
        -------
        str
            Band, decades, active interval, sweep rate and quality of the fit.

        """
        decades = abs(np.log10(self.f_high / self.f_low))
        return (f'exponential chirp {self.f_low:.3g}-{self.f_high:.3g} Hz '
                f'({decades:.2f} decades) from t0 = {self.t0:.3f} s to t1 = {self.t1:.3f} s '
                f'({self.duration:.3g} s), sweep rate a0 = {self.a0:.4g} 1/s, fitted on '
                f'{self.n_half_cycles} half cycles with {100 * self.fit_residual:.2g} % '
                f'frequency scatter')

    def to_dict(self) -> dict[str, Any]:
        """
        JSON-ready summary.

        Returns
        -------
        dict
            Every field of the detection.

        """
        return {'kind': self.kind, 'fs': self.fs, 'f_low': self.f_low, 'f_high': self.f_high,
                't0': self.t0, 't1': self.t1, 'a0': self.a0, 'a1': self.a1,
                'n_half_cycles': self.n_half_cycles, 'fit_residual': self.fit_residual,
                'channel': self.channel}


# --------------------------------------------------------------------------- input checks

def excitation_source(reference: np.ndarray | None, effort: np.ndarray
                      ) -> tuple[np.ndarray, str]:
    """
    Return the signal to detect the excitation on and its name.

    The velocity reference r when it was commanded (finite in at least ``MIN_FINITE`` of the
    samples; NaN where no command was held, e.g. before the first one or in a gap) and moves
    on some joint, else the torque u (the plant input, which carries the excitation too).

    Parameters
    ----------
    reference
        (N, n) velocity reference or None.
    effort
        (N, n) motor torque.

    Returns
    -------
    tuple
        ((N, n) array, 'velocity reference' | 'torque').

    """
    if reference is not None:
        r = np.asarray(reference, dtype=float)
        finite = np.isfinite(r)
        if r.size and np.mean(finite) >= MIN_FINITE:
            spread = [np.std(r[finite[:, j], j]) if np.any(finite[:, j]) else 0.0
                      for j in range(r.shape[1])]
            if max(spread, default=0.0) > 0:
                return r, 'velocity reference'
    return np.asarray(effort, dtype=float), 'torque'


def _bridge(x: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """``x`` with the invalid samples linearly interpolated (held at the ends)."""
    if np.all(valid):
        return x
    idx = np.arange(x.size)
    return np.interp(idx, idx[valid], x[valid])


def _periodic_fill(x: np.ndarray, valid: np.ndarray, p: int) -> np.ndarray:
    """
    Fill missing samples from the same phase of other periods.

    ``x`` with each missing sample replaced by the mean of the present samples at the same
    phase (index modulo ``p``) in the other periods: for a periodic signal its value.
    """
    if np.all(valid) or p < 1:
        return x
    n = x.size
    m = -(-n // p)
    xv = np.zeros(m * p)
    vv = np.zeros(m * p)
    xv[:n] = np.where(valid, x, 0.0)
    vv[:n] = valid
    count = vv.reshape(m, p).sum(axis=0)
    mean = xv.reshape(m, p).sum(axis=0) / np.maximum(count, 1.0)
    phase = np.arange(n) % p
    fill = ~valid & (count[phase] > 0)
    out = x.copy()
    out[fill] = mean[phase[fill]]
    return out


def _prepare(x: np.ndarray, fs: float, min_samples: int = 16
             ) -> tuple[np.ndarray, int, np.ndarray]:
    """
    Validate, pick the strongest channel, bridge NaN gaps, remove the median.

    Returns (x, channel, valid): ``valid`` marks the samples that were finite.
    """
    if not (np.isfinite(fs) and fs > 0):
        raise EstimationError(f'{fs=} must be a positive sample rate in Hz')
    x = np.asarray(x, dtype=float)
    if x.ndim not in (1, 2):
        raise EstimationError(f'signal must be (N,) or (N, n_channels), got {x.shape=}')
    if x.shape[0] < min_samples:
        raise EstimationError(f'signal has {x.shape[0]} samples; need at least {min_samples}')
    if np.any(np.isinf(x)):
        raise EstimationError(f'signal has {int(np.sum(np.isinf(x)))} infinite samples')
    channel = 0
    if x.ndim == 2:
        centred = x - np.nanmedian(x, axis=0) if np.any(np.isfinite(x)) else x
        with np.errstate(invalid='ignore'):
            rms = np.array([np.sqrt(np.mean(c[np.isfinite(c)] ** 2)) if np.any(np.isfinite(c))
                            else 0.0 for c in centred.T])
        channel = int(np.argmax(rms))
        x = x[:, channel]
    valid = np.isfinite(x)
    if np.mean(valid) < MIN_FINITE:
        raise EstimationError(f'signal has {int(np.sum(~valid))} non-finite (missing) of {x.size} '
                              f'samples; expected at least {100 * MIN_FINITE:.0f} % present')
    x = _bridge(x, valid)
    return x - np.median(x), channel, valid


# --------------------------------------------------------------------------- multisine

def _lag_correlation(x: np.ndarray, max_lag: int, valid: np.ndarray | None = None
                     ) -> np.ndarray:
    """
    Compute a Pearson-like autocorrelation per lag over the pairs of present samples.

    sum x[n] x[n+k] over the pairs (n, n+k) whose samples are both present (``valid``),
    normalised by the energies of both members of those pairs: 1 exactly for a noise-free
    periodic signal, whatever is missing. A bridged gap never enters: a gap longer than a
    period made the true period lose to a multiple of it whose overlap happened to miss the
    gap more.
    """
    n = x.size
    whole = valid is None or bool(np.all(valid))
    xm = x if whole else x * valid
    nfft = sfft.next_fast_len(2 * n, real=True)

    def xcorr(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """sum_n a[n] b[n + k] for k = 0 .. max_lag."""
        return sfft.irfft(np.conj(sfft.rfft(a, nfft)) * sfft.rfft(b, nfft), nfft)[:max_lag + 1]
    acf = xcorr(xm, xm)
    if whole:
        cum = np.concatenate([[0.0], np.cumsum(x ** 2)])
        k = np.arange(max_lag + 1)
        norm = np.sqrt(cum[n - k] * (cum[n] - cum[k]))
    else:
        e2, v = xm ** 2, valid.astype(float)
        norm = np.sqrt(np.clip(xcorr(e2, v), 0.0, None) * np.clip(xcorr(v, e2), 0.0, None))
    return acf / np.maximum(norm, 1e-300)


def _period_candidate(r: np.ndarray, min_correlation: float, max_lag: int
                      ) -> tuple[int, float]:
    """
    Smallest lag up to ``max_lag`` whose autocorrelation peak is close to the best one.

    ``r`` may reach a few lags beyond ``max_lag`` so that a peak at ``max_lag`` itself (a
    record of exactly two periods) is a peak. Returns (0, best value) if there is none.
    """
    below = np.flatnonzero(r < 0)
    if below.size == 0:
        return 0, float('nan')
    lag_min = int(below[0])
    peaks, props = signal.find_peaks(r[lag_min:], height=min_correlation)
    inside = peaks + lag_min <= max_lag
    peaks, heights = peaks[inside], props['peak_heights'][inside]
    if peaks.size == 0:
        return 0, float(np.max(r[lag_min:max_lag + 1])) if max_lag >= lag_min else float('nan')
    first = int(np.flatnonzero(heights >= heights.max() - 0.05 * (1.0 - min_correlation))[0])
    lag = int(peaks[first]) + lag_min
    return lag, float(r[lag])


def _moving_mean(v: np.ndarray, w: int) -> np.ndarray:
    """Centred moving mean over ``w`` samples (shorter windows at the ends)."""
    if w <= 1:
        return v
    kernel = np.ones(w)
    return np.convolve(v, kernel, mode='same') / np.convolve(np.ones(v.size), kernel, mode='same')


def _periodic_block(x: np.ndarray, p: int, valid: np.ndarray | None = None
                    ) -> tuple[int, int]:
    """
    (start, n_periods) of the whole periods in the longest run where x[n + P] matches x[n].

    rho[n] = mean (x[n+P] - x[n])^2 over P/16 samples, divided by the mean of x[n]^2 + x[n+P]^2
    over a whole period (constant for a periodic signal): 0 for identical periods, about 1
    for unrelated signals or noise alone, noise / (signal + noise) in a noisy steady state.
    The run must carry signal (idle parts match trivially); its edges are then refined to
    the sample (:func:`_refine_edges`). Comparisons that involve a missing sample (``valid``
    false) are left out of the means; where a whole window is missing the run goes on (a gap
    says nothing against periodicity).
    """
    w = max(1, p // 16)
    e2 = (x[p:] - x[:-p]) ** 2
    both = np.ones(e2.size) if valid is None else (valid[p:] & valid[:-p]).astype(float)
    if valid is not None:
        _compare_past_gaps(x, valid, p, e2, both)
    e2 = e2 * both
    seen = _moving_mean(both, w)
    ee = _moving_mean(e2, w) / np.maximum(seen, 1e-12)
    xx = _moving_mean(x[p:] ** 2 + x[:-p] ** 2, p)
    active = xx > 0.05 * np.quantile(xx, 0.9)
    rho = ee / np.maximum(xx, 1e-300)
    measured = seen > 1e-9
    sel = active & measured
    ref = float(np.quantile(rho[sel], 0.25)) if np.any(sel) else 1.0
    ok = active & ((rho < min(0.5 * (1.0 + ref), max(3.0 * ref, 0.05))) | ~measured)
    a, b = _longest_run(ok)
    if b <= a:
        return 0, 0
    smooth_a = a
    a, b = _refine_edges(e2, a, b, w, floor=1e-12 * float(np.mean(x ** 2)))
    # the data repeat on [a, b + P): the whole periods are taken flush with its end, so
    # what is left over lies at the start, where a start-up transient decays (a block from
    # a dropped the last steady period and kept a part of the transient instead). A start
    # found at a change of variance is exact to a few samples; one that is not may be up to
    # half a smoothing window late
    slack = 3 if a != smooth_a else w // 2
    if a <= slack:                 # periodic from the first sample: the grid starts there
        n_periods = min((b - a + p + slack) // p, (x.size - a) // p)
        return int(a), int(n_periods)
    # a start-up transient before a: the whole periods are taken flush with the end of the
    # data that repeat, [a, b + P), so what is left over lies at the start, where the
    # transient decays (a block from a dropped the last steady period and kept a part of the
    # transient instead)
    end = min(b + p, x.size)
    n_periods = min((end - a + slack) // p, end // p)
    return int(end - n_periods * p), int(n_periods)


def _compare_past_gaps(x: np.ndarray, valid: np.ndarray, p: int, e2: np.ndarray,
                       both: np.ndarray) -> None:
    """
    Compare a present sample whose partner one period on is missing with a later period.

    In place: where x[n] is present but x[n + P] lies in a gap, e2[n] becomes
    (x[n + k P] - x[n])^2 of the first later period k >= 2 present there and both[n] 1. A
    start-up transient right before a gap is then still seen (compared with nothing, it
    had joined the periodic block and its leakage came out as excited lines).
    """
    idx = np.flatnonzero((both == 0) & valid[:e2.size])
    for k in range(2, x.size // p + 1):
        j = idx + k * p
        idx = idx[j < x.size]
        j = j[j < x.size]
        if idx.size == 0:
            return
        hit = valid[j]
        e2[idx[hit]] = (x[j[hit]] - x[idx[hit]]) ** 2
        both[idx[hit]] = 1.0
        idx = idx[~hit]


def _refine_edges(e2: np.ndarray, a: int, b: int, w: int, *,
                  floor: float) -> tuple[int, int]:
    """
    Move the edges of a run to variance change points.

    Move the edges [a, b) of the smoothed run to the sample where the variance of the
    period difference e changes (maximum-likelihood change point within +-w samples); an edge
    stays where it is unless the variance outside is at least three times the inside one.
    ``floor`` keeps rounding errors of a noise-free signal from counting as variance. A run
    that reaches the end of the data keeps its end (nothing after it to compare with; a
    start-up transient at the beginning is a change inside the data and is found).
    Isolated outliers (a held command where one was dropped) are median-filtered away first:
    only a sustained change of variance moves an edge.
    """
    lo, hi = max(0, a - w), min(e2.size, a + w)
    k = _variance_change(_despike(e2[lo:hi]), floor, inside_after=True)
    a_new = a if k is None else lo + k
    lo, hi = max(0, b - w), min(e2.size, b + w)
    k = _variance_change(_despike(e2[lo:hi]), floor, inside_after=False) \
        if b < e2.size else None
    b_new = b if k is None else lo + k
    return (a_new, b_new) if b_new > a_new else (a, b)


def _despike(e2: np.ndarray, k: int = 5) -> np.ndarray:
    """Return the running median over ``k`` samples (outliers of up to k // 2 samples removed)."""
    return signal.medfilt(e2, k) if e2.size >= k else e2


def _variance_change(e2: np.ndarray, floor: float, *, inside_after: bool) -> int | None:
    """
    Find the index where the variance of e2 changes.

    Index k splitting e2 into two parts of different mean (Gaussian variance change point),
    or None if the outside part is not clearly (3x) larger than the inside part.
    """
    n = e2.size
    if n < 4:
        return None
    c = np.concatenate([[0.0], np.cumsum(e2)])
    k = np.arange(1, n)
    v1 = np.maximum(c[k] / k, floor)
    v2 = np.maximum((c[n] - c[k]) / (n - k), floor)
    cost = k * np.log(v1) + (n - k) * np.log(v2)
    best = int(k[np.argmin(cost)])
    inside, outside = (v2, v1) if inside_after else (v1, v2)
    j = best - 1
    return best if outside[j] > 3.0 * inside[j] else None


def _longest_run(mask: np.ndarray) -> tuple[int, int]:
    """Return [a, b) of the longest run of True (0, 0 if none)."""
    if not np.any(mask):
        return 0, 0
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    i = int(np.argmax(ends - starts))
    return int(starts[i]), int(ends[i])


def _excited_lines(block: np.ndarray, min_line_db: float,
                   dynamic_range_db: float) -> tuple[np.ndarray, float]:
    """Lines of the period-averaged DFT far above the median line. Returns (bins, level_db)."""
    spec = sfft.rfft(block, axis=1).mean(axis=0)
    power = np.abs(spec[1:]) ** 2  # without DC
    floor = np.median(power)
    thr = max(floor * 10 ** (min_line_db / 10), power.max() * 10 ** (-dynamic_range_db / 10))
    bins = np.flatnonzero(power > thr) + 1
    rest = np.delete(power, bins - 1)
    rest_level = np.median(rest) if rest.size else 0.0
    level = 10 * np.log10(power[bins - 1].min() / max(rest_level, power.max() * 1e-30)) \
        if bins.size else float('nan')
    return bins, float(level)


def detect_multisine(x: np.ndarray, fs: float, *, min_periods: int = 2,
                     min_correlation: float = 0.3, min_line_db: float = 20.0,
                     dynamic_range_db: float = 80.0) -> MultisineDetection:
    """
    Find a periodic multisine in ``x`` sampled at ``fs``.

    The period P is the smallest lag at which the normalised autocorrelation peaks (at least
    ``min_correlation`` and within reach of the highest peak), checked against its
    neighbours so consecutive periods match best; the periodic block is the longest stretch in
    which x[n + P] equals x[n] within the steady-state noise; excited lines are the bins of the
    period-averaged DFT more than ``min_line_db`` above the median bin (and within
    ``dynamic_range_db`` of the strongest). If the lines share a common factor g, the period
    is P / g.

    Raises :class:`EstimationError` (one line) if no ``min_periods`` whole periods are found.

    Parameters
    ----------
    x : ndarray, shape (N,) or (N, n)
        The signal; of a 2-D signal the channel with the largest RMS is analysed. NaN marks
        missing samples.
    fs : float
        Sample rate [Hz].
    min_periods : int, optional
        Fewest whole periods the periodic block must hold.
    min_correlation : float, optional
        Smallest normalised autocorrelation of a period candidate.
    min_line_db : float, optional
        How far [dB] an excited line must stand above the median DFT line.
    dynamic_range_db : float, optional
        Lines more than this [dB] below the strongest one are not excited lines.

    Returns
    -------
    MultisineDetection
        Period, periodic block, excited lines and quality of the detection.

    """
    x, channel, valid = _prepare(x, fs)
    n = x.size
    max_lag = n // max(2, int(min_periods))
    if max_lag < 4:
        raise EstimationError(f'signal of {n} samples too short for {min_periods=} periods')
    r = _lag_correlation(x, min(n - 1, max_lag + 2), valid)
    p, corr = _period_candidate(r, min_correlation, max_lag)
    if p == 0:
        if np.isfinite(corr) and corr >= min_correlation:
            raise EstimationError(
                f'no whole periods: the autocorrelation rises to {corr:.2f} towards the '
                f'longest lag searched ({max_lag} samples, {max_lag / fs:.4g} s = 1/'
                f'{max(2, int(min_periods))} of the {n} samples) without a peak; a period, if '
                f'any, is longer: expected at least {min_periods=} whole periods in the data '
                f'(give a longer --t-range or --multisine-period)')
        best = f'{corr:.2f}' if np.isfinite(corr) else 'none'
        raise EstimationError(f'no periodicity: best autocorrelation {best} beyond the main '
                              f'lobe is below {min_correlation=} (lags up to {max_lag} samples)')
    bridged = x
    x = _periodic_fill(bridged, valid, p)
    start, n_per = _periodic_block(x, p, valid)
    if n_per >= 2:
        q = _refine_period(x[start:start + n_per * p + 2], p)
        if q != p:
            p = q
            x = _periodic_fill(bridged, valid, p)
            start, n_per = _periodic_block(x, p, valid)
    if n_per < min_periods:
        raise EstimationError(f'period {p} samples ({p / fs:.4g} s) found but only {n_per} '
                              f'whole periods repeat; need {min_periods=}')
    block = x[start:start + n_per * p].reshape(n_per, p)
    bins, level = _excited_lines(block, min_line_db, dynamic_range_db)
    if bins.size == 0:
        raise EstimationError(f'period {p} samples found but no DFT line stands '
                              f'{min_line_db=} dB above the rest')
    drift = period_drift(block, bins)
    g = int(np.gcd.reduce(bins))
    if g > 1 and p % g == 0:
        p, bins, n_per, drift = p // g, bins // g, n_per * g, drift / g
    return MultisineDetection(float(fs), int(p), int(n_per), int(start), float(fs) / p,
                              bins.astype(np.int64), bool(np.all(bins % 2 == 1)),
                              float(r[min(p, r.size - 1)]), level, channel, drift)


def multisine_at_period(x: np.ndarray, fs: float, period: float, *, min_periods: int = 2,
                        band: tuple[float, float] | None = None, min_line_db: float = 20.0,
                        dynamic_range_db: float = 80.0) -> MultisineDetection:
    """
    Detect a multisine of known period.

    A multisine of known ``period`` [s] in ``x``: no autocorrelation search, so it works
    on data too short for :func:`detect_multisine` (two periods suffice).

    A period that is not a whole number of samples (e.g. rounded when printed) is snapped to
    the integer lag within 2 samples of ``period * fs`` at which the data repeat best;
    the periodic block and the excited lines are found as in :func:`detect_multisine`, the
    lines restricted to ``band`` = (f_low, f_high) [Hz] when given. Raises
    :class:`EstimationError` if fewer than ``min_periods`` whole periods repeat or no line is
    excited in the band.

    Parameters
    ----------
    x : ndarray, shape (N,) or (N, n)
        The signal; of a 2-D signal the channel with the largest RMS is analysed. NaN marks
        missing samples.
    fs : float
        Sample rate [Hz].
    period : float
        The multisine period [s].
    min_periods : int, optional
        Fewest whole periods that must repeat.
    band : tuple of float, optional
        (f_low, f_high) [Hz]: keep only the excited lines inside; default: all.
    min_line_db : float, optional
        How far [dB] an excited line must stand above the median DFT line.
    dynamic_range_db : float, optional
        Lines more than this [dB] below the strongest one are not excited lines.

    Returns
    -------
    MultisineDetection
        The periodic block and excited lines at the (snapped) period.

    """
    if not (np.isfinite(period) and period > 0):
        raise EstimationError(f'{period=} must be a positive duration in seconds')
    x, channel, valid = _prepare(x, fs, min_samples=1)
    p0 = int(round(period * fs))
    if p0 < 4 or x.size // p0 < min_periods:
        raise EstimationError(f'{period=:g} s ({p0} samples) leaves {x.size // max(p0, 1)} '
                              f'whole periods in {x.size} samples ({x.size / fs:.4g} s); '
                              f'expected at least {min_periods=}')
    whole = abs(period * fs - p0) <= 1e-3        # given to the sample: keep it as is
    p = p0 if whole or x.size // (p0 + 2) < 2 else _refine_period(x, p0)
    x = _periodic_fill(x, valid, p)
    start, n_per = _periodic_block(x, p, valid)
    if n_per < min_periods:
        raise EstimationError(f'{period=:g} s ({p} samples): only {n_per} whole periods '
                              f'repeat in the data; expected at least {min_periods=}')
    block = x[start:start + n_per * p].reshape(n_per, p)
    bins, level = _excited_lines(block, min_line_db, dynamic_range_db)
    if band is not None:
        f = bins * fs / p
        bins = bins[(f >= band[0]) & (f <= band[1])]
    if bins.size == 0:
        raise EstimationError(f'{period=:g} s: no DFT line stands {min_line_db=} dB above the '
                              f'rest' + (f' in {band=} Hz' if band is not None else ''))
    a, b = block[:-1].ravel(), block[1:].ravel()
    corr = float(a @ b / max(np.sqrt((a @ a) * (b @ b)), 1e-300))
    return MultisineDetection(float(fs), int(p), int(n_per), int(start), float(fs) / p,
                              bins.astype(np.int64), bool(np.all(bins % 2 == 1)), corr, level,
                              channel, period_drift(block, bins))


def period_drift(block: np.ndarray, bins: np.ndarray) -> float:
    """
    By how many samples the true period exceeds the ``block``'s row length P.

    ``block`` (n_periods, P) holds consecutive periods. A period of P + d samples shifts each
    period d samples later on the grid: line h of the last period lags the first by the phase
    2 pi h (n - 1) d / P. d is the weighted least-squares slope of those phases over h, the
    phases unwrapped around a first fit on the lowest quarter of the lines. 0 with fewer
    than two periods or no lines.

    Parameters
    ----------
    block : ndarray, shape (n_periods, P)
        Consecutive periods of the signal, one per row.
    bins : ndarray of int
        Excited DFT lines h of a period of P samples.

    Returns
    -------
    float
        Drift d [samples per period]: the true period is P + d samples.

    """
    n, P = block.shape
    if n < 2 or bins.size == 0:
        return 0.0
    X0 = np.fft.rfft(block[0])[bins]
    XL = np.fft.rfft(block[-1])[bins]
    w = np.abs(X0 * XL)
    if not np.any(w > 0):
        return 0.0
    phi = -np.angle(XL * np.conj(X0))                 # 2 pi h D / P, D = (n - 1) d
    h = bins.astype(float)
    low = h <= np.quantile(h, 0.25)
    slope = float(np.sum(w[low] * h[low] * phi[low]) / max(np.sum(w[low] * h[low] ** 2),
                                                           1e-300))
    phi = phi + 2 * np.pi * np.round((slope * h - phi) / (2 * np.pi))
    slope = float(np.sum(w * h * phi) / max(np.sum(w * h ** 2), 1e-300))
    return slope * P / (2 * np.pi) / (n - 1)


def _refine_period(x: np.ndarray, p: int, reach: int = 2) -> int:
    """Integer lag near ``p`` with the smallest mean squared difference of shifted copies."""
    best, best_err = p, np.inf
    for k in range(max(1, p - reach), p + reach + 1):
        if k >= x.size:
            break
        d = x[k:] - x[:-k]
        err = float(np.mean(d ** 2) / max(np.mean(x[k:] ** 2 + x[:-k] ** 2), 1e-300))
        if err < best_err - 1e-15:
            best, best_err = k, err
    return best


# --------------------------------------------------------------------------- chirp

def _onset(x: np.ndarray, model: np.ndarray, lo: int, hi: int, fit: slice,
           valid: np.ndarray) -> int:
    """
    Index k in [lo, hi] minimising sum_{n<k} x^2 + sum_{n>=k} (x - A cos - B sin)^2.

    ``model`` is (2, N) cos/sin of the fitted chirp phase; A, B are least-squares fitted on
    ``fit`` (whole cycles inside the chirp). Matching the whole waveform makes the onset
    independent of the chirp's starting phase and robust to noise. Missing samples
    (``valid`` false) count in neither sum nor the fit.
    """
    w = valid[fit]
    coef, *_ = np.linalg.lstsq(model[:, fit][:, w].T, x[fit][w], rcond=None)
    m = coef @ model[:, lo:hi]
    seg, v = x[lo:hi], valid[lo:hi]
    off = np.concatenate([[0.0], np.cumsum(seg ** 2 * v)])          # x^2 before k
    on = np.concatenate([[0.0], np.cumsum((seg - m) ** 2 * v)])     # residual from k on
    cost = off + (on[-1] - on)
    return lo + int(np.argmin(cost))


def _cycles_back(phase: np.ndarray, valid: np.ndarray, i: int, cycles: float) -> int:
    """
    Return the index ``cycles`` cycles of present samples before ``i``.

    The phase advance of the missing samples is not counted, so a search window reaches
    across a gap to as many cycles of data as without one. 0 when the data end first.
    """
    step = np.abs(np.diff(phase[:i + 1])) * valid[1:i + 1]
    have = np.cumsum(step[::-1])
    k = int(np.searchsorted(have, 2 * np.pi * cycles))
    return max(0, i - k - 1)


def _chirp_extent(x: np.ndarray, fs: float, a0: float, a1: float, t_first: float,
                  t_last: float, valid: np.ndarray) -> tuple[int, int]:
    """Start index and last index of the chirp around the fitted half cycles [t_first, t_last]."""
    n = x.size
    t = np.arange(n) / fs
    ph = 2 * np.pi * np.exp(a1) * np.expm1(a0 * t) / a0 if a0 != 0 else 2 * np.pi * np.exp(a1) * t
    model = np.stack([np.cos(ph), np.sin(ph)])
    f_first, f_last = np.exp(a0 * np.array([t_first, t_last]) + a1)
    p_first, p_last = int(np.ceil(fs / f_first)), int(np.ceil(fs / f_last))
    i_first = min(max(int(np.floor(t_first * fs)), 0), n - 1)
    i_last = min(max(int(np.ceil(t_last * fs)), 0), n - 1)
    i0 = _onset(x, model, _cycles_back(ph, valid, i_first, 2.0), min(n, i_first + p_first),
                slice(i_first, min(n, i_first + 2 * p_first)), valid)
    j = n - 1 - i_last
    rev = _onset(x[::-1], model[:, ::-1], _cycles_back(ph[::-1], valid[::-1], j, 2.0),
                 min(n, j + p_last), slice(j, min(n, j + 2 * p_last)), valid[::-1])
    return i0, n - rev


def detect_chirp(x: np.ndarray, fs: float, *, min_ratio: float = 1.5,
                 max_scatter: float = 0.08, min_inliers: float = 0.7,
                 hysteresis: float = 0.3) -> ChirpDetection:
    """
    Find an exponential chirp f(t) = exp(a0 t + a1) (eq. 16) in ``x`` sampled at ``fs``.

    Half cycles between zero crossings (hysteresis ``hysteresis`` times the 99th percentile of
    |x|) give f = 1 / (2 duration) at their mid times; a robust fit of ln f over t gives a0, a1.
    t0 and t1 are the on- and offset of the fitted waveform A cos(phase) + B sin(phase)
    (least squares, searched two periods outside the first and last fitted half cycles),
    f_low = f(t0), f_high = f(t1). It is a chirp when at least ``min_inliers`` of
    the half cycles follow the fit with relative scatter below ``max_scatter`` and the band
    spans a ratio of at least ``min_ratio``.

    Raises :class:`EstimationError` (one line) otherwise.

    Parameters
    ----------
    x : ndarray, shape (N,) or (N, n)
        The signal; of a 2-D signal the channel with the largest RMS is analysed. NaN marks
        missing samples.
    fs : float
        Sample rate [Hz].
    min_ratio : float, optional
        Smallest frequency ratio the fitted half cycles must span.
    max_scatter : float, optional
        Largest relative scatter of the half-cycle frequencies around the fit.
    min_inliers : float, optional
        Smallest share of half cycles that must follow the fit.
    hysteresis : float, optional
        Zero-crossing hysteresis as a share of the 99th percentile of |x|.

    Returns
    -------
    ChirpDetection
        Band, active interval, eq. 16 coefficients and quality of the fit.

    """
    x, channel, valid = _prepare(x, fs)
    h = hysteresis * float(np.quantile(np.abs(x), 0.99))
    if h <= 0:
        raise EstimationError('no chirp: the signal is constant')
    t_mid, f = half_cycles(x, fs, h)
    if t_mid.size < 10:
        raise EstimationError(f'no chirp: only {t_mid.size} half cycles above the '
                              f'hysteresis level {h:.3g}')
    best, other = fit_sweep_laws(t_mid, f)
    if best.law != 'exponential' and best.scatter < LAW_MARGIN * other.scatter \
            and best.inliers >= min_inliers:
        raise EstimationError(
            f'a {best.describe()}, not an exponential chirp f(t) = exp(a0 t + a1) (eq. 16; '
            f'that law leaves {100 * other.scatter:.2g} % frequency scatter): the chirp '
            f'estimator needs the exponential law')
    a0, a1, keep, scatter = robust_law_fit(t_mid, f, 'exponential')
    frac = float(keep.mean())
    tk = t_mid[keep]
    ratio = float(np.exp(abs(a0) * (tk[-1] - tk[0]))) if tk.size > 1 else 1.0
    if frac < min_inliers or scatter > max_scatter or ratio < min_ratio:
        raise EstimationError(
            f'no exponential chirp: {100 * frac:.0f} % of {t_mid.size} half cycles follow '
            f'ln f = a0 t + a1 with {100 * scatter:.2g} % scatter over a frequency ratio '
            f'{ratio:.3g} (need {100 * min_inliers:.0f} %, < {100 * max_scatter:.2g} %, '
            f'>= {min_ratio:g})')
    i0, i1 = _chirp_extent(x, fs, a0, a1, float(tk[0]), float(tk[-1]), valid)
    t0, t1 = i0 / fs, (i1 - 1) / fs
    return ChirpDetection(float(fs), float(np.exp(a0 * t0 + a1)), float(np.exp(a0 * t1 + a1)),
                          float(t0), float(t1), a0, a1, int(keep.sum()), scatter, channel)


# --------------------------------------------------------------------------- both

def detect_excitation(x: np.ndarray, fs: float, **kwargs: Any
                      ) -> MultisineDetection | ChirpDetection:
    """
    Detect a periodic multisine, else an exponential chirp, in ``x`` sampled at ``fs``.

    The result's ``kind`` ('multisine' or 'chirp') says which was found and ``describe()``
    says what. ``kwargs`` may hold ``min_periods`` for the multisine detector. Raises
    :class:`EstimationError` with one line giving both reasons if neither is found.

    Parameters
    ----------
    x : ndarray, shape (N,) or (N, n)
        The signal; of a 2-D signal the channel with the largest RMS is analysed. NaN marks
        missing samples.
    fs : float
        Sample rate [Hz].
    **kwargs
        ``min_periods`` (int, default 2) for :func:`detect_multisine`; other keys are ignored.

    Returns
    -------
    MultisineDetection or ChirpDetection
        The multisine if one is found, else the chirp.

    """
    try:
        return detect_multisine(x, fs, min_periods=kwargs.get('min_periods', 2))
    except EstimationError as exc:
        why_ms = str(exc)
    try:
        return detect_chirp(x, fs)
    except EstimationError as exc:
        why_chirp = str(exc)
    n = np.asarray(x).shape[0] if np.ndim(x) else 0
    raise EstimationError(f'no multisine or exponential chirp found in {n} samples at '
                          f'{fs=:g} Hz: {why_ms}; {why_chirp}')
