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
phase) before the regression f ~ c0 + Fc sgn(v) + dFv v [+ dJ a] + ripple harmonics
(:mod:`.regression`).
"""
from __future__ import annotations

import math

from frf_ident.core.model.params import RobotParams
import numba
import numpy as np
from scipy import signal


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
    return bool(np.all(_locked_above(robot, fs)))


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


def _locked_above(robot: RobotParams, fs: float) -> np.ndarray:
    """Return per axis whether its locked resonance lies far above the Nyquist frequency."""
    return np.array([math.sqrt(a.stiffness * (1 / a.motor_inertia + 1 / a.link_inertia))
                     / (2 * math.pi) > 2 * fs for a in robot.axes])


def _elastic_residual(u: np.ndarray, qh: np.ndarray, vh: np.ndarray, ah: np.ndarray,
                      dt: float, robot: RobotParams) -> np.ndarray:
    """
    Return the residual of a model with elastic axes, its rigid axes' links on their motors.

    The link states of the elastic axes E follow from the link-side equation driven by the
    measured motor motion; an axis whose locked resonance lies far above the Nyquist frequency
    (rigid, R) has its link on the motor (q_o = q_m): its spring would make the discretised
    link equation stiff beyond double precision (a rigid MJCF joint's view next to an elastic
    one). Rows E: M_EE a_oE + M_ER a_mR + K_E (q_oE - q_mE) + D_E (v_oE - v_mE) + g_E = 0.
    The transmission torque of an elastic axis is its spring's and damper's, of a rigid one
    the link side's M_RR a_mR + M_RE a_oE + g_R. Without rigid axes this is the link-side
    equation of the module docstring.
    """
    jm = np.array([a.motor_inertia for a in robot.axes])
    bv = np.array([a.viscous_friction for a in robot.axes])
    k = np.array([a.stiffness for a in robot.axes])
    d = np.array([a.damping for a in robot.axes])
    rig = _locked_above(robot, 1 / dt)
    el = np.flatnonzero(~rig)
    ri = np.flatnonzero(rig)
    m = robot.link_inertia_matrix()
    moi = np.linalg.inv(m[np.ix_(el, el)])
    K, D = np.diag(k[el]), np.diag(d[el])
    ne = el.size
    z, eye, zr = np.zeros((ne, ne)), np.eye(ne), np.zeros((ne, ri.size))
    mer = m[np.ix_(el, ri)]
    A = np.block([[z, eye], [-moi @ K, -moi @ D]])
    B = np.block([[z, z, z, zr], [moi @ K, moi @ D, -moi, -moi @ mer]])
    # the model's link-side load (constant plus gravity terms) at the link positions,
    # taken as the motor positions: the deflection is far below the terms' angular scale
    g = robot.gravity_load(qh)
    sysd = signal.cont2discrete((A, B, np.eye(2 * ne), np.zeros((2 * ne, 3 * ne + ri.size))),
                                dt, method='foh')
    w = np.hstack([qh[:, el], vh[:, el], g[:, el], ah[:, ri]])
    x0 = np.concatenate([qh[0, el] - g[0, el] / k[el], vh[0, el]])
    xs = _discrete_response(*(np.ascontiguousarray(x) for x in sysd[:4]),
                            np.ascontiguousarray(w), x0)
    qo, vo = qh.copy(), vh.copy()
    qo[:, el], vo[:, el] = xs[:, :ne], xs[:, ne:]
    f = u - (jm * ah + bv * vh)
    f[:, el] -= k[el] * (qh[:, el] - qo[:, el]) + d[el] * (vh[:, el] - vo[:, el])
    if ri.size:
        ao = (k[el] * (qh[:, el] - qo[:, el]) + d[el] * (vh[:, el] - vo[:, el])
              - g[:, el] - ah[:, ri] @ mer.T) @ moi.T
        f[:, ri] -= ah[:, ri] @ m[np.ix_(ri, ri)].T + ao @ mer + g[:, ri]
    return f


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
        f = _elastic_residual(u[:-1], qh, vh, ah, dt, robot)
    return f, qh, vh, ah
