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
The frequency law of a recorded sine sweep: linear or exponential, and its band.

The instantaneous frequency of a sweep is read from its half cycles (zero crossings with
hysteresis, :func:`half_cycles`); a robust fit of f(t) = c0 + c1 t (linear sweep) and of
ln f(t) = a0 t + a1 (exponential chirp, Saupe & Knoblach 2015 eq. 16) says which law the
signal follows (:func:`fit_sweep_laws`). :func:`sweep_mismatch` compares a given or detected
exponential chirp with what the signal does: a sweep estimated with the wrong law puts each
analysis frequency at the wrong time, and the FRF comes out wrong without any other sign.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ['LAW_MARGIN', 'MAX_MISMATCH', 'SweepFit', 'fit_sweep_laws', 'half_cycles',
           'robust_law_fit', 'sweep_mismatch']

#: a law explains a sweep better than the other when its frequency scatter is below this
#: share of the other's: a linear 15 -> 2 Hz sweep has 0.3 % scatter around its line and
#: 6.9 % around the best exponential law; an exponential chirp the reverse (ratio > 10)
LAW_MARGIN = 0.5

#: largest median relative deviation of the recorded half-cycle frequencies from a given
#: chirp's law: the half-cycle scatter of a clean chirp is < 1 %, of one at 20 dB SNR
#: about 3 %; a law off by 10 % places the analysis excerpts visibly off the sweep
MAX_MISMATCH = 0.1


def half_cycles(x: np.ndarray, fs: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Zero crossings with hysteresis ``h``: returns (mid times, frequencies) of half cycles.

    The state flips only when x passes +h or -h; each flip is dated by the linearly
    interpolated zero crossing just before it, so noise below h causes no chatter.

    Parameters
    ----------
    x : ndarray, shape (N,)
        The signal, median removed.
    fs : float
        Sample rate [Hz].
    h : float
        Hysteresis level (signal units).

    Returns
    -------
    tuple of ndarray
        Mid times [s from the first sample] and frequencies 1 / (2 duration) [Hz].

    """
    state = np.where(x > h, 1.0, np.where(x < -h, -1.0, np.nan))
    idx = np.flatnonzero(np.isfinite(state))
    if idx.size < 3:
        return np.zeros(0), np.zeros(0)
    s = state[idx]
    flips = idx[1:][s[1:] != s[:-1]]  # first sample beyond the threshold after a flip
    sign_change = np.flatnonzero(np.signbit(x[1:]) != np.signbit(x[:-1]))  # between i, i+1
    if flips.size < 3 or sign_change.size == 0:
        return np.zeros(0), np.zeros(0)
    j = np.searchsorted(sign_change, flips, side='left') - 1
    j = np.clip(j, 0, None)
    i = sign_change[j]
    frac = x[i] / (x[i] - x[i + 1])
    tz = (i + frac) / fs
    d = np.diff(tz)
    good = d > 0
    mid = 0.5 * (tz[1:] + tz[:-1])
    return mid[good], 0.5 / d[good]


def robust_law_fit(t: np.ndarray, f: np.ndarray, law: str, iterations: int = 5
                   ) -> tuple[float, float, np.ndarray, float]:
    """
    Fit a sweep law to half-cycle frequencies with MAD-based outlier rejection.

    Parameters
    ----------
    t, f : ndarray
        Half-cycle mid times [s] and frequencies [Hz].
    law : {'exponential', 'linear'}
        ln f = a0 t + a1, or f = c1 t + c0.
    iterations : int, optional
        Rounds of outlier rejection.

    Returns
    -------
    tuple
        (slope, intercept, inlier mask, standard deviation of the relative frequency
        error of the inliers).

    """
    v = np.log(f) if law == 'exponential' else f
    keep = np.ones(t.size, dtype=bool)
    a0 = a1 = 0.0
    rel = np.zeros(t.size)
    for _ in range(iterations):
        if keep.sum() < 3:
            break
        a0, a1 = np.polyfit(t[keep], v[keep], 1)
        fit = a0 * t + a1
        rel = v - fit if law == 'exponential' else (f - fit) / np.maximum(np.abs(fit), 1e-300)
        mad = 1.4826 * np.median(np.abs(rel[keep]))
        new = np.abs(rel) <= max(4.0 * mad, 0.01)
        if np.array_equal(new, keep):
            break
        keep = new
    res = rel[keep]
    return float(a0), float(a1), keep, float(np.std(res)) if res.size else float('inf')


@dataclass(frozen=True)
class SweepFit:
    """
    A sweep law fitted to half-cycle frequencies.

    Parameters
    ----------
    law : str
        'linear' (f = c1 t + c0) or 'exponential' (ln f = a0 t + a1).
    slope, intercept : float
        c1 [Hz/s], c0 [Hz] or a0 [1/s], a1.
    f_start, f_end : float
        Frequency at the first and last fitted half cycle [Hz].
    t_start, t_end : float
        Their times [s].
    scatter : float
        Standard deviation of the relative frequency error around the law.
    inliers : float
        Share of the half cycles that follow the law.

    """

    law: str
    slope: float
    intercept: float
    f_start: float
    f_end: float
    t_start: float
    t_end: float
    scatter: float
    inliers: float

    def describe(self) -> str:
        """
        One phrase a person can check against the experiment.

        Returns
        -------
        str
            e.g. 'linear sweep 15 -> 2 Hz over 0-260 s (0.3 % frequency scatter)'.

        """
        return (f'{self.law} sweep {self.f_start:.3g} -> {self.f_end:.3g} Hz over '
                f'{self.t_start:.4g}-{self.t_end:.4g} s ({100 * self.scatter:.2g} % frequency '
                f'scatter, {100 * self.inliers:.0f} % of the half cycles)')


def _fit(t: np.ndarray, f: np.ndarray, law: str) -> SweepFit:
    a0, a1, keep, scatter = robust_law_fit(t, f, law)
    tk = t[keep] if np.any(keep) else t
    ends = np.array([tk[0], tk[-1]])
    fe = np.exp(a0 * ends + a1) if law == 'exponential' else a0 * ends + a1
    return SweepFit(law, a0, a1, float(fe[0]), float(fe[1]), float(ends[0]), float(ends[1]),
                    scatter, float(np.mean(keep)))


def fit_sweep_laws(t: np.ndarray, f: np.ndarray) -> tuple[SweepFit, SweepFit]:
    """
    Fit both sweep laws; the one the half cycles follow better first.

    Parameters
    ----------
    t, f : ndarray
        Half-cycle mid times [s] and frequencies [Hz] (:func:`half_cycles`).

    Returns
    -------
    tuple of SweepFit
        (better, other): the law with the smaller scatter first.

    """
    fits = sorted((_fit(t, f, law) for law in ('exponential', 'linear')),
                  key=lambda s: s.scatter / max(s.inliers, 1e-3))
    return fits[0], fits[1]


def sweep_mismatch(x: np.ndarray, fs: float, law, t0: float, t1: float,
                   hysteresis: float = 0.3) -> tuple[float, SweepFit | None]:
    """
    Compare a sweep law with the half cycles a signal really has.

    Parameters
    ----------
    x : ndarray, shape (N,)
        The recorded excitation (NaN marks missing samples).
    fs : float
        Sample rate [Hz].
    law : callable
        Instantaneous frequency f(t) [Hz] of the given chirp, t [s] from the first sample.
    t0, t1 : float
        The chirp's active interval [s].
    hysteresis : float, optional
        Zero-crossing hysteresis as a share of the 99th percentile of |x| in [t0, t1].

    Returns
    -------
    tuple
        (median relative deviation of the half-cycle frequencies in [t0, t1] from ``law``,
        the better of the two laws fitted to them; (inf, None) when the interval holds no
        sweep (fewer than 10 half cycles)).

    """
    i0, i1 = max(0, int(t0 * fs)), min(x.size, int(np.ceil(t1 * fs)) + 1)
    seg = np.asarray(x[i0:i1], dtype=float)
    ok = np.isfinite(seg)
    if not np.any(ok):
        return float('inf'), None
    if not np.all(ok):                         # gaps bridged linearly
        k = np.arange(seg.size)
        seg = np.interp(k, k[ok], seg[ok])
    seg = seg - np.median(seg)
    if seg.size < 16:
        return float('inf'), None
    h = hysteresis * float(np.quantile(np.abs(seg), 0.99))
    t, f = half_cycles(seg, fs, h) if h > 0 else (np.zeros(0), np.zeros(0))
    if t.size < 10:
        return float('inf'), None
    t = t + i0 / fs
    dev = float(np.median(np.abs(f / np.asarray(law(t)) - 1.0)))
    return dev, fit_sweep_laws(t, f)[0]
