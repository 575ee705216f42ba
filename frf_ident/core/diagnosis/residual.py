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
Time-domain evidence: the motor-side inverse-dynamics residual and its regression.

For the flexible joint (eqs. 20-22) every motor-side torque the model lacks (Coulomb and
viscous friction, torque ripple) appears exactly in

    f = u - (Jm a_m + b_v v_m + K (q_m - q_o) + D (v_m - v_o)),

where the link states q_o, v_o follow from the *measured* motor motion through the stable
link-side equation M_o ddq_o = K (q_m - q_o) + D (v_m - v_o) - g. For a (numerically) rigid
axis this reduces to f = u - (Jm + Jo) a - b_v v. Both sides are low-pass filtered (zero
phase) before the regression f ~ c0 + Fc sgn(v) + dFv v [+ dJ a] + ripple harmonics.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math

from frf_ident.core.model.params import RobotParams
import numba
import numpy as np
from scipy import signal
from scipy.ndimage import median_filter
from scipy.optimize import brentq

# re-exported: benchmarks/ripple_threshold.py reads the scan's constants from here
from .thresholds import (FC_HZ, RIPPLE_CELL_FACTOR, RIPPLE_FALSE_ALARM,  # noqa: F401
                         RIPPLE_LEVEL_DOF, RIPPLE_LEVEL_WINDOW, RIPPLE_MIN_CYCLES)


def lowpass(x: np.ndarray, fs: float, fc: float) -> np.ndarray:
    """Filter with a zero-phase 4th-order Butterworth low-pass along axis 0."""
    return signal.sosfiltfilt(_lowpass_sos(fs, fc), x, axis=0)


def _lowpass_sos(fs: float, fc: float) -> np.ndarray:
    """Return the sections of :func:`lowpass` (one pass)."""
    return signal.butter(4, min(fc, 0.45 * fs), fs=fs, output='sos')


def effective_samples(n: int, fs: float, fc: float) -> float:
    """
    Return how many independent samples n samples of white noise keep after :func:`lowpass`.

    A signal of noise bandwidth B holds 2 B independent samples per second. The zero-phase
    Butterworth passes white noise with B = integral of |H(f)|^4 (forward and backward), about
    0.9 fc for the 4th order, so n 2 B / fs (at least 10).

    Parameters
    ----------
    n : int
        Number of samples.
    fs, fc : float
        Sample rate and cut-off of :func:`lowpass` [Hz].

    Returns
    -------
    float

    """
    f, h = signal.sosfreqz(_lowpass_sos(fs, fc), worN=8192, fs=fs)
    bw = float(np.trapezoid(np.abs(h) ** 4, f))
    return max(n * 2 * bw / fs, 10.0)


def coulomb_and_ripple(robot: RobotParams, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """
    Return the torque the model's Coulomb friction and torque ripple take, per axis.

    Fc sgn(v) minus the ripple sum A sin(s q + phase): the part of a model's inverse dynamics
    that :func:`inverse_dynamics_residual` (linear) leaves out.

    Parameters
    ----------
    robot : RobotParams
        The model.
    q, v : ndarray, shape (N, n)
        Motor positions [rad] and velocities [rad/s].

    Returns
    -------
    ndarray, shape (N, n)

    """
    out = np.array([a.coulomb_friction for a in robot.axes]) * np.sign(v)
    for i, a in enumerate(robot.axes):
        for r in a.torque_ripple:
            out[:, i] -= r['amplitude'] * np.sin(r['spatial_frequency'] * q[:, i]
                                                 + r.get('phase', 0.0))
    return out


def is_rigid(robot: RobotParams, fs: float) -> bool:
    """Return true when every axis' locked resonance lies far above the Nyquist frequency."""
    return all(math.sqrt(a.stiffness * (1 / a.motor_inertia + 1 / a.link_inertia)) / (2 * math.pi)
               > 2 * fs for a in robot.axes)


def delayed_effort(u: np.ndarray, delay: np.ndarray, dt: float) -> np.ndarray:
    """
    Return the zero-order-held command as it acts after an input delay.

    The torque acting over sample interval k is u held from ``t_k - delay``: for a delay of
    d = m + r samples (integer m, fraction r) the interval average is
    (1 - r) u[k - m] + r u[k - m - 1]; before the record starts the first command is held.

    Parameters
    ----------
    u : ndarray, shape (N, n)
        Commanded torque per sample and axis.
    delay : array_like, shape (n,)
        Input delay per axis [s] (>= 0).
    dt : float
        Sample time [s].

    Returns
    -------
    ndarray, shape (N, n)
        The acting torque per sample interval.

    """
    u = np.asarray(u, dtype=float)
    out = u.copy()
    for i, d in enumerate(np.asarray(delay, dtype=float) / dt):
        if d <= 0:
            continue
        m, r = int(math.floor(d)), d - math.floor(d)
        pad = np.concatenate([np.full(m + 1, u[0, i]), u[:, i]])
        n = u.shape[0]
        out[:, i] = (1 - r) * pad[1:n + 1] + r * pad[:n]
    return out


@numba.njit(cache=True, inline='always')
def _affine(m, n, x, u, out):
    """Write ``m x + n u`` into ``out``."""
    for r in range(m.shape[0]):
        acc = 0.0
        for c in range(x.shape[0]):
            acc += m[r, c] * x[c]
        for c in range(u.shape[0]):
            acc += n[r, c] * u[c]
        out[r] = acc


@numba.njit(cache=True)
def _discrete_response(ad, bd, cd, dd, u, x0):
    """
    Return the output of x[k+1] = ad x[k] + bd u[k], y[k] = cd x[k] + dd u[k] from x[0] = x0.

    What ``scipy.signal.dlsim`` computes, compiled: its loop over the samples in Python
    took 2.4 s for the 354,000 samples of the demo bag, three times per diagnosis.
    """
    x = x0.copy()
    xn = np.empty(ad.shape[0])
    y = np.empty((u.shape[0], cd.shape[0]))
    for k in range(u.shape[0]):
        _affine(cd, dd, x, u[k], y[k])
        _affine(ad, bd, x, u[k], xn)
        x[:] = xn
    return y


def inverse_dynamics_residual(q: np.ndarray, v: np.ndarray, u: np.ndarray, dt: float,
                              robot: RobotParams, link_position: np.ndarray | None = None
                              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Compute the motor-side residual torque of the model from the measured motion.

    Motor-side residual torque of the model, evaluated between samples (k + 1/2) where the
    zero-order-held torque u[k] acts, delayed by the axes' ``time_delay``
    (:func:`delayed_effort`; against an undelayed model a 1-2 ms delay biases the friction the
    residual is regressed on). Returns (f, q_half, v_half, a_half), each (N-1, n).
    With ``link_position`` (a link-side encoder) the deflection is measured, not simulated.
    """
    n = robot.n_axes
    u = delayed_effort(u, [a.time_delay for a in robot.axes], dt)
    qh = 0.5 * (q[1:] + q[:-1])
    vh = 0.5 * (v[1:] + v[:-1])
    ah = np.diff(v, axis=0) / dt
    jm = np.array([a.motor_inertia for a in robot.axes])
    bv = np.array([a.viscous_friction for a in robot.axes])
    k = np.array([a.stiffness for a in robot.axes])
    d = np.array([a.damping for a in robot.axes])
    if link_position is not None:
        qo = 0.5 * (link_position[1:] + link_position[:-1])
        vo = np.gradient(qo, dt, axis=0)
        f = u[:-1] - (jm * ah + bv * vh + k * (qh - qo) + d * (vh - vo))
    elif is_rigid(robot, 1 / dt):
        # motor and link move together: the link inertia matrix (with its off-diagonal
        # coupling, RobotParams.link_coupling) adds to the motor inertias
        f = u[:-1] - (jm * ah + ah @ robot.link_inertia_matrix() + bv * vh)
    else:
        mo = robot.link_inertia_matrix()
        moi = np.linalg.inv(mo)
        K, D = np.diag(k), np.diag(d)
        z, eye = np.zeros((n, n)), np.eye(n)
        A = np.block([[z, eye], [-moi @ K, -moi @ D]])
        B = np.block([[z, z, z], [moi @ K, moi @ D, -moi]])
        # the model's link-side load (constant plus gravity terms) at the link positions,
        # taken as the motor positions: the deflection is far below the terms' angular scale
        g = robot.gravity_load(qh)
        sysd = signal.cont2discrete((A, B, np.eye(2 * n), np.zeros((2 * n, 3 * n))), dt,
                                    method='foh')
        w = np.hstack([qh, vh, g])
        x0 = np.concatenate([qh[0] - g[0] / k, vh[0]])
        xs = _discrete_response(*(np.ascontiguousarray(m) for m in sysd[:4]),
                                np.ascontiguousarray(w), x0)
        qo, vo = xs[:, :n], xs[:, n:]
        f = u[:-1] - (jm * ah + bv * vh + k * (qh - qo) + d * (vh - vo))
    return f, qh, vh, ah


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
