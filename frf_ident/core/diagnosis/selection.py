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
Select regressor groups by F test and held-out error; fit and held-out blocks; standard errors.

The statistics of the time-series diagnosis (:mod:`.timeseries`): forward selection by F test
at the data's own noise, backward elimination on held-out blocks, the block split and the
block-bootstrap-free standard errors from the spread between blocks.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

from .thresholds import ALPHA, BLOCK_S, EDGE, HOLD_EVERY, SE_BLOCK_TAUS


def by_group(coef: np.ndarray, groups: dict[str, np.ndarray], chosen: list[str]
             ) -> dict[str, np.ndarray]:
    """Return the joint fit's coefficients ``coef`` split into the groups ``chosen``."""
    out, k0 = {}, 0
    for k in chosen:
        w = groups[k].shape[1]
        out[k] = coef[k0:k0 + w]
        k0 += w
    return out


def lstsq(cols: list[np.ndarray], y: np.ndarray) -> tuple[np.ndarray, float]:
    if not cols:
        return np.zeros(0), float(y @ y)
    X = np.column_stack(cols)
    c, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ c
    return c, float(r @ r)


def f_test(rss0: float, rss1: float, q: int, p: int, n_eff: float) -> float:
    """
    Return the log p-value of the F test that q added regressors reduce rss0 to rss1.

    The residual is low-passed: its N samples hold only ``n_eff`` independent ones
    (:func:`.residual.effective_samples`), and a regressor as slow as the residual picks up
    N / n_eff times a sample's noise variance per coefficient. ``rss1 / (n_eff - p)`` is that
    variance, so the plain F ratio has the F(q, n_eff - p) distribution under the null
    (test/core/diagnosis/test_diagnosis.py checks the false-alarm rate by Monte Carlo).

    Parameters
    ----------
    rss0, rss1 : float
        Residual sums of squares without and with the q regressors (all N samples).
    q : int
        Number of added regressors.
    p : int
        Number of regressors of the larger model.
    n_eff : float
        Effective number of independent samples.

    Returns
    -------
    float
        log p (0 when the regressors do not reduce the residual).

    """
    dof = max(n_eff - p, 1.0)
    F = ((rss0 - rss1) / q) / max(rss1 / dof, 1e-300)
    return float(stats.f.logsf(F, q, dof)) if F > 0 else 0.0


def select_groups(groups: dict[str, np.ndarray], y: np.ndarray, fit: np.ndarray,
                  val: np.ndarray, n_eff: float, forced: list[str] | tuple[str, ...] = ()
                  ) -> tuple[list[str], dict[str, dict]]:
    """
    Select regressor groups by F test and held-out error.

    Forward selection by F test (p < ALPHA at ``n_eff`` effective samples) on top of the
    ``forced`` groups, then removal of every other group whose absence does not worsen the
    held-out residual, repeated without the removed groups until none is removed (stepwise
    regression: a group that only stood in for another one no longer keeps it out). Returns
    the selected names and per candidate {'p', 'share', 'held_out_gain'} for the report.
    """
    chosen: list[str] = list(forced)
    info: dict[str, dict] = {k: {'p': 0.0, 'share': 0.0, 'forced': True} for k in forced}
    yf = y[fit]
    tot = float((yf - yf.mean()) @ (yf - yf.mean())) or 1e-300
    dropped: set[str] = set()
    while True:
        _forward(groups, yf, fit, n_eff, chosen, dropped, info, tot)
        removed = _backward(groups, y, fit, val, chosen, forced, info)
        # stepwise: a group dropped on held-out data may have kept out another that the
        # forward pass now admits (a one-off sinusoid standing in for the friction)
        if not removed:
            return chosen, info
        dropped |= set(removed)


def _forward(groups, yf, fit, n_eff, chosen, dropped, info, tot):
    """Add to ``chosen`` the groups (not in ``dropped``) that pass the F test, best first."""
    while True:
        _, rss0 = lstsq([groups[k][fit] for k in chosen], yf)
        # ranked by log p, then (where log p underflows too, a link's weight against a
        # friction-free model) by the Bayesian information criterion on effective samples
        best, bp = None, (math.log(ALPHA), math.inf)
        for k, x in groups.items():
            if k in chosen or k in dropped or (k.startswith('gravity:') and any(
                    c.startswith('gravity:') for c in chosen)):
                continue
            cols = [groups[c][fit] for c in chosen] + [x[fit]]
            _, rss1 = lstsq(cols, yf)
            q = x.shape[1]
            p_tot = sum(groups[c].shape[1] for c in chosen) + q
            lp = f_test(rss0, rss1, q, p_tot, n_eff)
            info.setdefault(k, {})
            info[k].update(p=math.exp(lp), share=(rss0 - rss1) / tot)
            key = (lp, n_eff * math.log(max(rss1, 1e-300)) + p_tot * math.log(n_eff))
            if key < bp:
                best, bp = k, key
        if best is None:
            return
        chosen.append(best)


def _backward(groups, y, fit, val, chosen, forced, info) -> list[str]:
    """
    Remove from ``chosen`` every group whose absence does not worsen the held-out error.

    One at a time, the one whose absence helps most first; returns the removed names.
    """
    yf = y[fit]

    def held(names):
        """Return the held-out residual energy of the groups ``names`` refitted jointly."""
        c, _ = lstsq([groups[k][fit] for k in names], yf)
        if not names:
            r = y[val]
        else:
            r = y[val] - np.column_stack([groups[k][val] for k in names]) @ c
        return float(r @ r)
    removed = []
    while True:
        # the group whose absence helps the held-out data most goes first, then the rest are
        # judged again without it (two collinear groups each look useless next to the other)
        with_k = held(chosen)
        for k in chosen:
            without = held([c for c in chosen if c != k])
            info[k]['held_out_gain'] = (without - with_k) / max(without, 1e-300)
        worst = min((k for k in chosen if k not in forced),
                    key=lambda k: info[k]['held_out_gain'], default=None)
        if worst is None or info[worst]['held_out_gain'] > 0:
            return removed
        chosen.remove(worst)
        removed.append(worst)


def block_samples(fs: float) -> int:
    """Return the length of a fit / held-out block [samples]: BLOCK_S, at least 8."""
    # rounded: a rate taken from float timestamps (249.99999999999977 Hz for 4 ms) must not
    # cut a sample off every block, and the two halves of one record then differ in blocks
    return max(int(round(BLOCK_S * fs)), 8)


def split_blocks(n: int, fs: float, fc: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the fit and held-out masks of interleaved blocks.

    Fit and held-out masks: the record cut into blocks of BLOCK_S, every HOLD_EVERY-th
    held out (interleaved, so held-out data cover the same configurations as the fit instead
    of extrapolating to the end of a short trajectory), a guard of half a filter period
    dropped at every block boundary and EDGE of the record at both ends.
    """
    blk = block_samples(fs)
    k = np.arange(n)
    held = (k // blk) % HOLD_EVERY == HOLD_EVERY - 1
    guard = int(0.5 * fs / fc)
    near = np.zeros(n, bool)
    for b in range(blk, n, blk):
        near[max(b - guard, 0):b + guard] = True
    e = int(EDGE * n)
    near[:e] = near[n - e:] = True
    return ~held & ~near, held & ~near


def correlation_time(e: np.ndarray, rows: np.ndarray) -> float:
    """
    Return the integrated correlation time [samples] of a residual known on ``rows``.

    1 + 2 sum of its autocorrelation up to the first lag where it is no longer positive; the
    autocorrelation at lag k averages e_t e_t+k over the pairs of rows both in ``rows``.
    """
    x = np.where(rows, e, 0.0)
    m = rows.astype(float)
    size = 1 << int(2 * rows.size - 1).bit_length()
    acf = np.fft.irfft(np.abs(np.fft.rfft(x, size)) ** 2, size)[:rows.size]
    pairs = np.fft.irfft(np.abs(np.fft.rfft(m, size)) ** 2, size)[:rows.size]
    r = acf / np.maximum(np.round(pairs), 1.0)
    r = r / r[0] if r[0] > 0 else r
    stop = np.flatnonzero(r[1:] <= 0)
    k = int(stop[0]) + 1 if stop.size else rows.size
    return float(1.0 + 2.0 * r[1:k].sum())


def block_standard_errors(groups: dict[str, np.ndarray], chosen: list[str], y: np.ndarray,
                          fit: np.ndarray, fs: float) -> dict[str, np.ndarray]:
    """
    Return block-robust (CR2) standard errors of the jointly fitted groups.

    The covariance of the joint least-squares fit of the groups ``chosen`` is the sandwich
    (X'X)^-1 (sum_b X_b' A_b e_b e_b' A_b X_b) (X'X)^-1 over the blocks b of the fit rows
    (as long as the held-out blocks of :func:`split_blocks`), e_b the block's residuals and
    A_b = (I - H_bb)^-1/2 with H_bb the block's part of the hat matrix: the bias-reduced
    cluster-robust estimator CR2 (Bell & McCaffrey 2002), unbiased for independent
    homoscedastic noise however few the blocks. A block is BLOCK_S long, or SE_BLOCK_TAUS
    times the residual's integrated correlation time (:func:`correlation_time`) where that is
    longer (a misfit that drifts over the motion), but at most a third of the record: so the
    sandwich takes the residual as it is, coloured, and with whatever misfit the model still
    has within a block, where a formula for white noise would not
    (docs/diagnosis/crosschecks.md, "Standard errors"). The error of the amplitude
    hypot(a_sin, a_cos) of a sin / cos pair is its spread under the pair's normal distribution.

    Parameters
    ----------
    groups : dict of str to ndarray, shape (N, k)
        The regressor groups (low-passed columns).
    chosen : list of str
        The groups fitted jointly.
    y : ndarray, shape (N,)
        The low-passed residual.
    fit : ndarray of bool, shape (N,)
        The rows fitted on.
    fs : float
        Sample rate [Hz] (the blocks are BLOCK_S long).

    Returns
    -------
    dict of str to ndarray
        Per group the standard error of each quantity it reports: its coefficient (one
        column) or the amplitude of each sin / cos pair; NaN for all when fewer than 3 blocks
        hold fit rows.

    """
    if not chosen or not fit.any():
        return {k: np.full(max(groups[k].shape[1] // 2, 1), math.nan) for k in chosen}
    X = np.column_stack([groups[k][fit] for k in chosen])
    bread = np.linalg.pinv(X.T @ X)
    coef = bread @ (X.T @ y[fit])
    e = y[fit] - X @ coef
    full = np.zeros(y.size)
    full[fit] = e
    blk = max(block_samples(fs),
              min(int(math.ceil(SE_BLOCK_TAUS * correlation_time(full, fit))), y.size // 3))
    ids = (np.arange(y.size) // blk)[fit]
    used = np.unique(ids)
    if used.size < 3:
        return {k: np.full(max(groups[k].shape[1] // 2, 1), math.nan) for k in chosen}
    cov = cluster_covariance(X, e, ids, bread)
    out = {}
    for k, ix in by_group(np.arange(coef.size), groups, chosen).items():
        if ix.size == 1:
            out[k] = np.sqrt(np.maximum(cov[ix, ix], 0.0))
        else:
            # amplitudes: the spread of hypot(a_sin, a_cos) over draws from the pair's normal
            # distribution (not the delta method, which misses an ill-determined phase)
            out[k] = np.array([np.std(np.hypot(*_normal_draws(coef[p], cov[np.ix_(p, p)])))
                               for p in ix.reshape(-1, 2)])
    return out


def cluster_covariance(X: np.ndarray, e: np.ndarray, ids: np.ndarray, bread: np.ndarray
                       ) -> np.ndarray:
    """
    Return the bias-reduced cluster-robust (CR2) covariance of a least-squares fit.

    bread (sum_b X_b' A_b e_b e_b' A_b X_b) bread over the clusters b of ``ids``, A_b =
    (I - H_bb)^-1/2 with H_bb the cluster's part of the hat matrix (Bell & McCaffrey 2002):
    unbiased for independent noise however few the clusters.

    Parameters
    ----------
    X : ndarray, shape (N, p)
        The regressors (columns) of the fitted rows.
    e : ndarray, shape (N,)
        The residuals of the fit.
    ids : ndarray, shape (N,)
        The cluster (block) of each row.
    bread : ndarray, shape (p, p)
        (X'X)^-1, or its pseudo-inverse.

    Returns
    -------
    ndarray, shape (p, p)
        The covariance of the coefficients.

    """
    # H_bb = A A' with A = X_b (X'X)^-1/2: its nonzero eigenvalues are the squared singular
    # values of A (at most one per column), so (I - H_bb)^-1/2 e_b costs O(n_b p^2)
    lam, vec = np.linalg.eigh(bread)
    half = (vec * np.sqrt(np.maximum(lam, 0.0))) @ vec.T
    meat = np.zeros_like(bread)
    # the rows of each cluster in their order, one sort instead of a mask per cluster
    order = np.argsort(ids, kind='stable')
    starts = np.flatnonzero(np.r_[True, np.diff(ids[order]) != 0])
    for rows in np.split(order, starts[1:]):
        xb, eb = X[rows], e[rows]
        u, sv, _ = np.linalg.svd(xb @ half, full_matrices=False)
        # an eigenvalue of I - H_bb near 0 is a block the fit rests on alone
        gain = 1.0 / np.sqrt(np.maximum(1.0 - sv ** 2, 1e-12)) - 1.0
        score = xb.T @ (eb + u @ (gain * (u.T @ eb)))
        meat += np.outer(score, score)
    return bread @ meat @ bread


def _normal_draws(mean: np.ndarray, cov: np.ndarray, n: int = 4000) -> np.ndarray:
    """Return ``n`` fixed draws (2, n) of the normal distribution (mean, cov) of a pair."""
    w, u = np.linalg.eigh(cov)
    z = np.random.default_rng(0).standard_normal((2, n))
    return mean[:, None] + u @ (np.sqrt(np.maximum(w, 0.0))[:, None] * z)
