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
Closed-form frequency responses of the linear flexible-joint robot (analytic truth).

- :func:`two_mass_frf` — SISO dq_m / tau_m of eqs. 20-22 (linear):
  (Jo s^2 + d s + k1) / (s (Jm Jo s^2 + (Jm + Jo)(d s + k1)))   (+ viscous friction)
- :func:`robot_frf` — MIMO continuous-time tau_m -> dq_m with link inertial coupling and the
  axes' second modes (:func:`second_mode_stiffness`)
- :func:`~frf_ident.core.simulation.linear.state_space` (the plant's linear part) — linear
  state-space model (A, B, C) of the robot, used by :func:`robot_frf_sampled`
- :func:`robot_frf_sampled` — the exact FRF of the sampled plant as the simulation realises it:
  zero-order-hold input, input delay, velocity sampled (or differentiated encoder position)
- :func:`closed_loop_frfs` — r -> u and r -> y through the velocity PI controller
"""
from __future__ import annotations

from typing import Sequence

from frf_ident.core.model.params import RobotParams
from frf_ident.core.simulation.linear import state_space
import numpy as np
from scipy import linalg

__all__ = ['closed_loop_frfs', 'link_chain_frf', 'robot_frf', 'robot_frf_sampled',
           'second_mode_stiffness', 'two_mass_frf']


def two_mass_frf(freq_hz: np.ndarray, motor_inertia: float, link_inertia: float,
                 stiffness: float, damping: float, viscous_friction: float = 0.0) -> np.ndarray:
    """
    Return the linear two-mass FRF dq_m / tau_m of eqs. 20-22 (continuous time).

    (Jo s^2 + d s + k1) / (s (Jm Jo s^2 + (Jm + Jo)(d s + k1))) without viscous friction;
    the Section 6 plant has an antiresonance near 5.0 Hz and a resonance near 11.6 Hz.

    Parameters
    ----------
    freq_hz : array_like
        Frequencies in Hz.
    motor_inertia : float
        Jm in kg m^2.
    link_inertia : float
        Jo in kg m^2.
    stiffness : float
        k1 in N m/rad.
    damping : float
        d in N m s/rad.
    viscous_friction : float, optional
        Motor-side viscous friction b_v in N m s/rad.

    Returns
    -------
    ndarray of complex
        The FRF in rad/s per N m, same shape as ``freq_hz``.

    """
    s = 2j * np.pi * np.asarray(freq_hz, dtype=float)
    jm, jo, bv = motor_inertia, link_inertia, viscous_friction
    z = damping * s + stiffness
    num = jo * s ** 2 + z
    # (Jm s^2 + bv s + Z - Z^2 / (Jo s^2 + Z)) q_m = tau_m,  dq_m = s q_m
    return s * num / ((jm * s ** 2 + bv * s) * num + z * jo * s ** 2)


def _link_stiffness_terms(params: RobotParams):
    n = params.n_axes
    jm = np.diag([a.motor_inertia for a in params.axes])
    bv = np.diag([a.viscous_friction for a in params.axes])
    k = np.diag([a.stiffness for a in params.axes])
    d = np.diag([a.damping for a in params.axes])
    return n, jm, bv, k, d, params.rigid_link_inertia_matrix()


def second_mode_stiffness(params: RobotParams, s: np.ndarray) -> np.ndarray:
    """
    Return the dynamic stiffness each axis' second mode adds to its link, shape (n_freq, n).

    A mass J_e on a spring and damper Z_e = k_e + d_e s behind the link loads it with
    J_e s^2 Z_e / (J_e s^2 + Z_e) (0 where an axis has no second mode).
    """
    s = np.asarray(s, dtype=complex)
    out = np.zeros((s.size, params.n_axes), dtype=complex)
    for i, a in enumerate(params.axes):
        terms = a.second_mode_terms()
        if terms is not None:
            je, ke, de = terms
            ze = ke + de * s
            out[:, i] = je * s ** 2 * ze / (je * s ** 2 + ze)
    return out


def robot_frf(params: RobotParams, freq_hz: np.ndarray) -> np.ndarray:
    """
    Return the MIMO continuous FRF tau_m -> dq_m of the linearised robot.

    (Jm s^2 + Bv s + Z - Z (L(s) + Z)^-1 Z) q_m = tau with Z = K + D s, P = s q_m / tau, and
    the link's dynamic stiffness L(s) = M_r s^2 plus each second mode's
    (:func:`second_mode_stiffness`; M_r the rigid link inertia, M_o without the modes'
    inertia; L = M_o s^2 without second modes). Symmetric (reciprocal) for a symmetric link
    inertia matrix.

    Parameters
    ----------
    params : RobotParams
        The robot (k1, d, viscous friction, link inertia and coupling, second modes;
        nonlinear terms are ignored).
    freq_hz : array_like, shape (n_freq,)
        Frequencies in Hz.

    Returns
    -------
    ndarray of complex, shape (n, n, n_freq)
        P[i, j]: motor velocity of axis i per motor torque of axis j.

    """
    freq_hz = np.asarray(freq_hz, dtype=float).reshape(-1)
    n, jm, bv, k, d, mr = _link_stiffness_terms(params)
    s = 2j * np.pi * freq_hz
    return link_chain_frf(np.diag(jm), np.diag(bv), np.diag(k), np.diag(d), mr,
                          second_mode_stiffness(params, s), freq_hz)


def link_chain_frf(jm: np.ndarray, bv: np.ndarray, k: np.ndarray, d: np.ndarray,
                   rigid_link: np.ndarray, mode_stiffness: np.ndarray, freq_hz: np.ndarray
                   ) -> np.ndarray:
    """
    Return the MIMO FRF tau_m -> dq_m of :func:`robot_frf` from its arrays (fits call it).

    Parameters
    ----------
    jm, bv, k, d : ndarray, shape (n,)
        Motor inertia, viscous friction, stiffness, damping per axis (SI).
    rigid_link : ndarray, shape (n, n)
        The link inertia matrix without the second modes' inertia [kg m^2].
    mode_stiffness : ndarray of complex, shape (n_freq, n)
        :func:`second_mode_stiffness` at the lines (zeros without second modes).
    freq_hz : ndarray, shape (n_freq,)
        Frequencies in Hz.

    Returns
    -------
    ndarray of complex, shape (n, n, n_freq)
        P[i, j]: motor velocity of axis i per motor torque of axis j.

    """
    n = jm.size
    sf = (2j * np.pi * np.asarray(freq_hz, dtype=float))[:, None, None]
    eye = np.eye(n)
    link = rigid_link * sf ** 2 + eye * mode_stiffness[:, None, :]
    z = eye * (k + d * sf)
    dyn = eye * (jm * sf ** 2 + bv * sf) + z - z @ np.linalg.solve(link + z, z)
    return np.moveaxis(sf * np.linalg.inv(dyn), 0, -1)


def _zoh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretisation via the augmented matrix exponential."""
    nx, nu = B.shape
    M = np.zeros((nx + nu, nx + nu))
    M[:nx, :nx] = A * dt
    M[:nx, nx:] = B * dt
    E = linalg.expm(M)
    return E[:nx, :nx], E[:nx, nx:]


def _delayed_zoh_input(A: np.ndarray, B: np.ndarray, dt: float, delay: float
                       ) -> tuple[np.ndarray, np.ndarray, int]:
    """ZOH with an input delay tau = (n_d + frac) dt: x+ = Ad x + B0 u[k-n_d] + B1 u[k-n_d-1]."""
    nd = int(np.floor(delay / dt + 1e-12))
    frac = delay - nd * dt
    Ad, B_dt = _zoh(A, B, dt)
    # over [0, frac) the older command acts, over [frac, dt) the newer one
    Ad_rest, B_rest = _zoh(A, B, dt - frac) if frac > 0 else (Ad, B_dt)
    Ad_frac, B_frac = _zoh(A, B, frac) if frac > 0 else (np.eye(A.shape[0]), np.zeros_like(B))
    B_new = B_rest
    B_old = Ad_rest @ B_frac
    return Ad, np.stack([B_new, B_old]), nd


def robot_frf_sampled(params: RobotParams, freq_hz: np.ndarray, *,
                      output: str = 'velocity', delays: np.ndarray | None = None,
                      inputs: Sequence[int] | None = None) -> np.ndarray:
    """
    Return the exact FRF from sampled torque (zero-order hold) to sampled output.

    This is what a digital controller sees and what the simulation realises, at the
    sample time ``params.dt``.

    Parameters
    ----------
    params : RobotParams
        The robot (its linear part).
    freq_hz : array_like, shape (n_freq,)
        Frequencies in Hz.
    output : {'velocity', 'encoder'}, optional
        ``'velocity'``: the sampled motor velocity; ``'encoder'``: the difference of motor
        positions over one sample divided by dt.
    delays : array_like, shape (n,), optional
        Input delay per axis in s; default the axes' ``time_delay``.
    inputs : sequence of int, optional
        Only these input axes (columns), in this order; default all.

    Returns
    -------
    ndarray of complex, shape (n, n_inputs, n_freq)
        P[i, j]: output of axis i per torque of axis ``inputs[j]`` (n_inputs = n by default).

    Raises
    ------
    ValueError
        ``output`` is neither 'velocity' nor 'encoder'.

    """
    freq_hz = np.asarray(freq_hz, dtype=float)
    dt = params.dt
    A, B, Cv, Cq = state_space(params)
    n = params.n_axes
    if delays is None:
        delays = np.array([a.time_delay for a in params.axes])
    if output not in ('velocity', 'encoder'):
        raise ValueError(f"{output=} must be 'velocity' or 'encoder'")
    inputs = range(n) if inputs is None else inputs
    z = np.exp(2j * np.pi * freq_hz * dt)
    out = np.empty((n, len(inputs), freq_hz.size), dtype=complex)
    nx = A.shape[0]
    for col, j in enumerate(inputs):
        Ad, Bs, nd = _delayed_zoh_input(A, B[:, j:j + 1], dt, float(delays[j]))
        # every line at once: (z I - Ad) x = (B0 + B1 / z) z^-nd
        bz = (Bs[0][None] + Bs[1][None] / z[:, None, None]) * (z ** (-nd))[:, None, None]
        x = np.linalg.solve(z[:, None, None] * np.eye(nx) - Ad, bz)[..., 0]
        if output == 'velocity':
            y = x @ Cv.T
        else:
            y = (x @ Cq.T) * ((1 - 1 / z) / dt)[:, None]
        out[:, col, :] = y.T
    return out


def closed_loop_frfs(P: np.ndarray, freq_hz: np.ndarray, kp: np.ndarray, ki: np.ndarray,
                     dt: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the closed-loop FRFs r -> u and r -> y for the discrete velocity PI around P.

    The PI is discretised as the simulation runs it (integral updated before use):
    K(z) = kp + ki dt z / (z - 1), the loop of the paper's Fig. 2.

    Parameters
    ----------
    P : ndarray, shape (n, n, n_freq)
        Plant FRF tau_m -> dq_m (e.g. :func:`robot_frf_sampled`).
    freq_hz : array_like, shape (n_freq,)
        Frequencies in Hz.
    kp, ki : ndarray, shape (n,)
        Proportional and integral gains per axis.
    dt : float
        Controller sample time in s.

    Returns
    -------
    S_u : ndarray, shape (n, n, n_freq)
        r -> u, (I + K P)^-1 K.
    T : ndarray, shape (n, n, n_freq)
        r -> y, P S_u.

    """
    freq_hz = np.asarray(freq_hz, dtype=float)
    n = P.shape[0]
    z = np.exp(2j * np.pi * freq_hz * dt)
    Su = np.empty_like(P)
    T = np.empty_like(P)
    for i, zi in enumerate(z):
        K = np.diag(kp + ki * dt * zi / (zi - 1))
        Su[:, :, i] = np.linalg.solve(np.eye(n) + K @ P[:, :, i], K)
        T[:, :, i] = P[:, :, i] @ Su[:, :, i]
    return Su, T
