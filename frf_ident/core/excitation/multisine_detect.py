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
Detect a periodic multisine in a measured signal (Saupe & Knoblach 2015, Sec. 4).

- :func:`detect_multisine` — period (autocorrelation peak, the smallest lag that matches),
  the block of whole periods (where consecutive periods agree), excited DFT lines and whether
  they are odd multiples of f0.
- :func:`multisine_at_period` — the same for a known period (two periods suffice).
- :func:`period_drift` — by how many samples the true period exceeds the whole-sample one.

Missing samples (NaN) are filled from the same phase of other periods once the period is
known.
"""
from __future__ import annotations

from frf_ident.core.excitation.detect_input import prepare_signal
from frf_ident.core.excitation.detection_results import MultisineDetection
from frf_ident.core.excitation.periodic_block import periodic_block
from frf_ident.errors import EstimationError
import numpy as np
from scipy import fft as sfft
from scipy import signal

__all__ = ['detect_multisine', 'multisine_at_period', 'period_drift']


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
    x, channel, valid = prepare_signal(x, fs)
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
    start, n_per = periodic_block(x, p, valid)
    if n_per >= 2:
        q = _refine_period(x[start:start + n_per * p + 2], p)
        if q != p:
            p = q
            x = _periodic_fill(bridged, valid, p)
            start, n_per = periodic_block(x, p, valid)
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
    x, channel, valid = prepare_signal(x, fs, min_samples=1)
    p0 = int(round(period * fs))
    if p0 < 4 or x.size // p0 < min_periods:
        raise EstimationError(f'{period=:g} s ({p0} samples) leaves {x.size // max(p0, 1)} '
                              f'whole periods in {x.size} samples ({x.size / fs:.4g} s); '
                              f'expected at least {min_periods=}')
    whole = abs(period * fs - p0) <= 1e-3        # given to the sample: keep it as is
    p = p0 if whole or x.size // (p0 + 2) < 2 else _refine_period(x, p0)
    x = _periodic_fill(x, valid, p)
    start, n_per = periodic_block(x, p, valid)
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
