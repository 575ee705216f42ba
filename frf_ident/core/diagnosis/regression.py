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
Regress the motor-side residual of one axis, and scan it for a torque ripple.

:func:`regress_axis` fits f ~ c0 + Fc sgn(v) + dFv v [+ dJ a] + ripple harmonics to the
inverse-dynamics residual of :mod:`.residual`, with t statistics and partial R^2 per term;
:func:`find_ripple` scans the residual for a sinusoid in the motor position (a ripple, a
cogging torque) against the false-alarm level :func:`ripple_threshold` calibrates.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math

import numpy as np
from scipy.ndimage import median_filter
from scipy.optimize import brentq

from .residual import effective_samples, lowpass
from .thresholds import (FC_HZ, RIPPLE_CELL_FACTOR, RIPPLE_FALSE_ALARM, RIPPLE_LEVEL_DOF,
                         RIPPLE_LEVEL_WINDOW, RIPPLE_MIN_CYCLES)

__all__ = ['find_ripple', 'regress_axis', 'Regression', 'ripple_range', 'ripple_threshold']


@dataclass
class Regression:
    """Result of the motor-side residual regression of one axis."""

    coef: dict[str, float]
    tstat: dict[str, float]
    partial_r2: dict[str, float]
    ripple: list[dict[str, float]] = field(default_factory=list)
    ripple_peak_ratio: float = 0.0
    ripple_threshold: float = math.inf
    rms_residual: float = 0.0
    rms_effort: float = 0.0
    n_eff: float = 0.0
    q0: float = 0.0          # mean position of the regressed samples [rad]
    travel: float = 0.0      # their position range [rad]
    #: spatial-frequency resolution of the ripple scan [1/rad]: 2 pi / the scanned travel
    ripple_resolution: float = math.inf


def _ls(X: np.ndarray, y: np.ndarray, n_eff: float):
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    res = y - X @ coef
    # rss / (n_eff - p) is already the noise variance a slow regressor picks up per
    # coefficient (N / n_eff times a sample's): no second N / n_eff factor (f_test, timeseries)
    dof = max(n_eff - X.shape[1], 1.0)
    cov = float(res @ res) / dof * np.linalg.pinv(X.T @ X)
    se = np.sqrt(np.maximum(np.diag(cov), 1e-300))
    return coef, coef / se, res


def ripple_threshold(n_cells: float, n_level: int, alpha: float = RIPPLE_FALSE_ALARM) -> float:
    """
    Return the scan ratio that noise alone exceeds with probability ``alpha``.

    Each ratio is an exponential periodogram value over a local level that is itself a
    sample median: with the level exact the threshold would be ln(M / alpha), but a median of
    K exponentials scatters by about 1 / sqrt(K), which fattens the tail by
    exp(x^2 / 2K) at the ratios that matter (x ~ 15-20: a factor 10-100). The tail of one ratio
    is the median's moment-generating function, exactly (Renyi's representation of the order
    statistics of exponentials):

        P(ratio > x) = prod_{j < r} (K - j) / (K - j + x / ln 2),  r = (K + 1) / 2,

    and the maximum over the scan is that of RIPPLE_CELL_FACTOR x ``n_cells`` independent
    values: P(max > x) = 1 - exp(-c M P(ratio > x)).

    Parameters
    ----------
    n_cells : float
        Resolution cells scanned, M = (s_max - s_min) / (2 pi / travel).
    n_level : int
        Grid points of the running median (the level's window, 4x oversampled).
    alpha : float, optional
        False-alarm probability of the whole scan.

    Returns
    -------
    float
        The threshold on the peak ratio.

    """
    k = max(int(round(RIPPLE_LEVEL_DOF * n_level / RIPPLE_LEVEL_WINDOW)), 3)
    j = np.arange((k + 1) // 2)
    target = -math.log1p(-alpha) / (RIPPLE_CELL_FACTOR * max(n_cells, 1.0))

    def log_tail(x: float) -> float:
        return float(np.sum(np.log((k - j) / (k - j + x / math.log(2))))) - math.log(target)
    hi = 2.0 * math.log(1.0 / target) + 10.0
    while log_tail(hi) > 0:
        hi *= 2.0
    return float(brentq(log_tail, 0.0, hi))


def ripple_range(q: np.ndarray, mask: np.ndarray) -> tuple[float, float]:
    """
    Return the range of spatial frequencies [1/rad] the recorded motion resolves.

    Spatial frequencies [1/rad] the recorded motion resolves: from RIPPLE_MIN_CYCLES
    cycles over the travel in ``mask`` up to the sample limit 0.9 pi / (95th percentile of
    the position step per sample), i.e. a ripple period of 2.2 samples at the usual speed
    (at exactly 2 samples the sine regressor vanishes and the scan statistic degenerates).
    """
    qm = q[mask]
    span = float(np.ptp(qm)) if qm.size else 0.0
    if span <= 0:
        return 0.0, 0.0
    steps = np.abs(np.diff(q))[mask[1:] & mask[:-1]]
    dq = float(np.percentile(steps, 95)) if steps.size else 0.0
    s_max = 0.9 * math.pi / dq if dq > 0 else 0.0
    return RIPPLE_MIN_CYCLES * 2 * math.pi / span, s_max


def find_ripple(f: np.ndarray, q: np.ndarray, mask: np.ndarray, *,
                alpha: float = RIPPLE_FALSE_ALARM) -> tuple[float, float, float]:
    """
    Scan the residual for the spatial frequency of a torque ripple.

    Spatial frequency [1/rad] whose sin/cos in motor position explain most of the residual
    f, scanned over :func:`ripple_range` with 4x oversampling of the resolution 2 pi / travel.

    Returns (s, peak ratio, threshold): the peak power over the local noise level of the scan
    (running median / ln 2, the mean of an exponentially distributed periodogram) and the level
    that noise alone exceeds with probability ``alpha`` (:func:`ripple_threshold`). s = 0
    when the motion resolves no range.
    """
    qm, fm = q[mask], f[mask] - np.mean(f[mask]) if mask.any() else f[mask]
    s_min, s_max = ripple_range(q, mask)
    if s_min <= 0 or s_max <= 2 * s_min:
        return 0.0, 0.0, math.inf
    span = float(np.ptp(qm))
    res = 2 * math.pi / span
    # spatial periodogram by gridding: the residual summed in position bins of a quarter of
    # the shortest resolvable period's step, then one zero-padded FFT (4x oversampled in s);
    # the peak is refined below on the samples themselves
    width = math.pi / s_max / 4
    idx = ((qm - qm.min()) / width).astype(np.int64)
    binned = np.bincount(idx, weights=fm, minlength=int(idx.max()) + 1)
    nfft = 1 << int(math.ceil(math.log2(4 * binned.size)))
    spec = np.fft.rfft(binned, nfft)
    s_all = 2 * math.pi * np.arange(spec.size) / (nfft * width)
    sel = (s_all >= s_min) & (s_all <= s_max)
    grid = s_all[sel]
    if grid.size < 16:
        return 0.0, 0.0, math.inf
    pw = np.abs(spec[sel]) ** 2
    # local noise level: running median over +-80 grid points (+-20 resolution cells); the
    # first and last half windows take the level of the first / last full window, so a peak
    # at the edge of the range is not measured against copies of itself
    w = min(RIPPLE_LEVEL_WINDOW, 2 * (grid.size // 2) - 1)
    h = w // 2
    level = median_filter(pw, size=w, mode='nearest')
    level[:h] = level[h]
    level[grid.size - h:] = level[grid.size - h - 1]
    level = level / math.log(2)
    ratio = pw / np.maximum(level, 1e-300)
    i = int(np.argmax(ratio))
    fine = np.linspace(grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)], 41)
    pf = [(fm @ np.cos(s * qm)) ** 2 + (fm @ np.sin(s * qm)) ** 2 for s in fine]
    return (float(fine[int(np.argmax(pf))]), float(ratio[i]),
            ripple_threshold((s_max - s_min) / res, w, alpha))


def regress_axis(f: np.ndarray, q: np.ndarray, v: np.ndarray, a: np.ndarray, u: np.ndarray,
                 mask: np.ndarray, fs: float, *, fc: float = FC_HZ, v_eps: float = 0.0,
                 with_inertia: bool = False, nuisance: np.ndarray | None = None,
                 ripple: bool = True, ripple_mask: np.ndarray | None = None) -> Regression:
    """
    Regress the residual f of one axis on [1, sgn(v), v, (a), (nuisance), ripple sin/cos].

    All columns are low-pass filtered like f (fc [Hz]); samples with |v| < v_eps (sticking,
    where the Coulomb force is undetermined) and outside ``mask`` are left out. t statistics
    use the effective sample count of the filtered data (:func:`effective_samples`), so under
    white noise |t| > 1.96 has probability 0.05 (test/core/diagnosis/test_diagnosis.py).
    """
    sg = np.sign(lowpass(v, fs, fc))
    cols = {'offset': np.ones_like(v), 'coulomb_friction': sg, 'viscous_friction': v}
    if with_inertia:
        cols['inertia'] = a
    if nuisance is not None:
        for j in range(nuisance.shape[1]):
            cols[f'nuisance_{j}'] = nuisance[:, j]
    m = mask & (np.abs(lowpass(v, fs, fc)) > v_eps)
    # edges of the filter around sign changes carry the undetermined stick phase
    ch = np.flatnonzero(np.diff(sg) != 0)
    guard = int(0.5 * fs / fc)
    for c in ch:
        m[max(c - guard, 0):c + guard + 1] = False
    ff = lowpass(f, fs, fc)
    n_eff = effective_samples(int(m.sum()), fs, fc)
    rip: list[dict[str, float]] = []
    peak, thr, resolution = 0.0, math.inf, math.inf
    if ripple:
        # the scan sees the residual low-passed only at 0.45 fs: a ripple reaches up to the
        # sample limit, above the regression's fc
        X0 = np.column_stack([lowpass(c, fs, fc) for c in cols.values()])
        c0, *_ = np.linalg.lstsq(X0[m], ff[m], rcond=None)
        wide = lowpass(f, fs, 0.45 * fs) - np.column_stack(list(cols.values())) @ c0
        scanned = m if ripple_mask is None else ripple_mask
        s, peak, thr = find_ripple(wide, q, scanned)
        s_min = ripple_range(q, scanned)[0]
        if s_min > 0:
            resolution = s_min / RIPPLE_MIN_CYCLES
        if s > 0:
            cols['ripple_sin'] = np.sin(s * q)
            cols['ripple_cos'] = np.cos(s * q)
    names = list(cols)
    X = np.column_stack([lowpass(c, fs, fc) for c in cols.values()])
    Xm, ym = X[m], ff[m]
    # a regressor without variation in the selected data (e.g. sgn(v) on a constant
    # velocity) is dropped
    keep = [j for j in range(len(names)) if names[j] == 'offset' or np.std(Xm[:, j]) > 1e-12]
    coef, t, res = _ls(Xm[:, keep], ym, n_eff)
    cf = {names[j]: float(coef[i]) for i, j in enumerate(keep)}
    ts = {names[j]: float(t[i]) for i, j in enumerate(keep)}
    # shares of what the offset and nuisance regressors (gravity) leave unexplained
    base = [i for i, j in enumerate(keep) if names[j] == 'offset' or names[j].startswith('nuis')]
    cb, *_ = np.linalg.lstsq(Xm[:, keep][:, base], ym, rcond=None)
    rb = ym - Xm[:, keep][:, base] @ cb
    tot = float(rb @ rb) or 1e-300
    pr2: dict[str, float] = {}
    groups = {'coulomb_friction': ['coulomb_friction'], 'viscous_friction': ['viscous_friction'],
              'torque_ripple': ['ripple_sin', 'ripple_cos'], 'inertia': ['inertia']}
    for g, members in groups.items():
        idx = [i for i, j in enumerate(keep) if names[j] in members]
        if not idx:
            continue
        rest = [i for i in range(len(keep)) if i not in idx]
        c2, *_ = np.linalg.lstsq(Xm[:, keep][:, rest], ym, rcond=None)
        r2 = ym - Xm[:, keep][:, rest] @ c2
        pr2[g] = float((r2 @ r2 - res @ res) / tot)
    if 'ripple_sin' in cf:
        amp = math.hypot(cf['ripple_sin'], cf['ripple_cos'])
        tr = math.hypot(ts['ripple_sin'], ts['ripple_cos'])
        # f = u - model = -(ripple torque): the ripple is the negated harmonic
        rip = [{'amplitude': amp, 'spatial_frequency': s,
                'phase': math.atan2(-cf['ripple_cos'], -cf['ripple_sin']), 't': tr}]
    return Regression(cf, ts, pr2, rip, peak, thr, float(np.sqrt(np.mean(res ** 2))),
                      float(np.std(lowpass(u, fs, fc)[m])), n_eff,
                      ripple_resolution=resolution)
