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
Where a signal repeats with a known period: the block of whole periods.

:func:`periodic_block` finds the longest run in which x[n + P] matches x[n] within the
steady-state noise, refines its edges to the sample where the variance of the period
difference changes, and returns the whole periods in it (start, count). Missing samples
never count against the periodicity of the data around them. Used by the multisine
detectors (:mod:`frf_ident.core.excitation.multisine_detect`).
"""
from __future__ import annotations

import numpy as np
from scipy import signal

__all__ = ['periodic_block']


def _moving_mean(v: np.ndarray, w: int) -> np.ndarray:
    """Centred moving mean over ``w`` samples (shorter windows at the ends)."""
    if w <= 1:
        return v
    kernel = np.ones(w)
    return np.convolve(v, kernel, mode='same') / np.convolve(np.ones(v.size), kernel, mode='same')


def periodic_block(x: np.ndarray, p: int, valid: np.ndarray | None = None
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
