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
Linear part of the flexible-joint plant: its state space and the exact discretisation.

The linear two-mass dynamics of eqs. 20-22 (k1, d, viscous friction, link coupling, second
modes) as x' = A x + B tau (:func:`state_space`), and their exact propagation by matrix
exponentials over one integrator substep: for a feed-forward torque interpolated quadratically
(:func:`substep_matrices`) and for the zero-order-held command delayed by each axis' input
delay (:func:`delayed_hold_matrices`). The compiled kernels of
:mod:`frf_ident.core.simulation.kernels` apply these matrices.
"""
from __future__ import annotations

import math

from frf_ident.core.model.params import RobotParams
import numpy as np
from scipy import linalg


def state_space(params: RobotParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Linear state space x' = A x + B tau of eqs. 20-22 (k1, d, viscous friction, coupling).

    x = [q_m, v_m, q_o, v_o] (blocks of n), then [q_e, v_e] (blocks of one per axis with a
    ``second_mode``, in axis order): the mode's inertia J_e sits on a spring k_e and damper d_e
    behind its link, and the link's rigid inertia (:meth:`RobotParams.rigid_link_inertia_matrix`)
    keeps the rest,

        M_r ddq_o = k1 (q_m - q_o) + d (v_m - v_o) - k_e (q_o - q_e) - d_e (v_o - v_e)
        J_e ddq_e = k_e (q_o - q_e) + d_e (v_o - v_e)

    Returns (A, B, C_velocity, C_position).
    """
    params.refuse_urdf_terms('the linear model')
    n = params.n_axes
    modes = [(i, a.second_mode_terms()) for i, a in enumerate(params.axes)
             if a.second_mode is not None]
    ne = len(modes)
    jmi = np.diag([1.0 / a.motor_inertia for a in params.axes])
    bv = np.diag([a.viscous_friction for a in params.axes])
    k = np.diag([a.stiffness for a in params.axes])
    d = np.diag([a.damping for a in params.axes])
    moi = np.linalg.inv(params.rigid_link_inertia_matrix())
    z, eye = np.zeros((n, n)), np.eye(n)
    A = np.zeros((4 * n + 2 * ne, 4 * n + 2 * ne))
    A[:4 * n, :4 * n] = np.block([
        [z, eye, z, z],
        [-jmi @ k, -jmi @ (d + bv), jmi @ k, jmi @ d],
        [z, z, z, eye],
        [moi @ k, moi @ d, -moi @ k, -moi @ d],
    ])
    vo = slice(3 * n, 4 * n)
    for j, (i, (je, ke, de)) in enumerate(modes):
        qe, ve = 4 * n + j, 4 * n + ne + j
        A[qe, ve] = 1.0
        for col, gain in ((2 * n + i, -ke), (qe, ke), (3 * n + i, -de), (ve, de)):
            A[vo, col] += moi[:, i] * gain              # the mode's reaction on the links
            A[ve, col] -= gain / je
    B = np.zeros((A.shape[0], n))
    B[n:2 * n] = jmi
    C = np.zeros((n, A.shape[0]))
    Cv, Cq = C.copy(), C
    Cv[:, n:2 * n] = eye
    Cq[:, :n] = eye
    return A, B, Cv, Cq


def link_torque_input(params: RobotParams) -> np.ndarray:
    """Return the input matrix of a link-side torque per axis in :func:`state_space` (nx, n)."""
    n = params.n_axes
    nx = 4 * n + 2 * sum(a.second_mode is not None for a in params.axes)
    out = np.zeros((nx, n))
    out[3 * n:4 * n] = np.linalg.inv(params.rigid_link_inertia_matrix())
    return out


def _hold_response(A: np.ndarray, b: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray]:
    """(e^{A tau}, int_0^tau e^{A s} ds b) by one augmented matrix exponential."""
    nx = A.shape[0]
    M = np.zeros((nx + 1, nx + 1))
    M[:nx, :nx] = A * tau
    M[:nx, nx] = b * tau
    E = linalg.expm(M)
    return E[:nx, :nx], E[:nx, nx]


def delayed_hold_matrices(params: RobotParams):
    """
    Exact response to the zero-order-held command delayed by each axis' time_delay.

    Over substep s of sample k (times [s h, (s+1) h) after t_k) axis i sees the command
    u[k + floor((tau - delay_i)/dt)], which switches at most once, at a fraction phi of the
    substep: x+ gets Gold u_old + Gnew u_new with Gold = e^{A h (1-phi)} Gamma(phi h) b_i and
    Gnew = Gamma(h (1-phi)) b_i. Returns offsets (m, 2, n), Gold, Gnew (m, 4n, n).
    """
    A, B, _, _ = state_space(params)
    n, m, dt = params.n_axes, int(params.substeps), params.dt
    h = dt / m
    nx = A.shape[0]
    offsets = np.zeros((m, 2, n), dtype=np.int64)
    gold, gnew = np.zeros((m, nx, n)), np.zeros((m, nx, n))
    eps = 1e-9 * dt
    for s in range(m):
        for i, a in enumerate(params.axes):
            o_old = math.floor((s * h + eps - a.time_delay) / dt)
            o_new = math.floor(((s + 1) * h - eps - a.time_delay) / dt)
            phi = 0.0
            if o_new != o_old:
                phi = (a.time_delay + (o_old + 1) * dt - s * h) / h
            offsets[s, 0, i], offsets[s, 1, i] = o_old, o_new
            e_rest, g_rest = _hold_response(A, B[:, i], h * (1.0 - phi))
            _, g_first = _hold_response(A, B[:, i], h * phi)
            gold[s, :, i] = e_rest @ g_first
            gnew[s, :, i] = g_rest
    return offsets, gold, gnew


def substep_matrices(params: RobotParams, h: float):
    """
    Exact discretisation of the linear part over one substep h.

    Augmented exponential of [[A, Bu, 0, 0], [0, 0, I, 0], [0, 0, 0, I], [0, 0, 0, 0]] h gives
    the responses to an input a + b s + c s^2 / 2; rewritten for the values at s = 0, h/2, h.
    The residual torques enter like inputs: motor side through B, link side through the rigid
    link inertia's inverse (:func:`link_torque_input`).
    """
    A, B, _, _ = state_space(params)
    n = params.n_axes
    nx = A.shape[0]
    Bu = np.hstack([B, link_torque_input(params)])
    nu = 2 * n
    M = np.zeros((nx + 3 * nu, nx + 3 * nu))
    M[:nx, :nx] = A
    M[:nx, nx:nx + nu] = Bu
    M[nx:nx + nu, nx + nu:nx + 2 * nu] = np.eye(nu)
    M[nx + nu:nx + 2 * nu, nx + 2 * nu:] = np.eye(nu)
    E = linalg.expm(M * h)
    ad = E[:nx, :nx]
    e0, e1, e2 = (E[:nx, nx + j * nu:nx + (j + 1) * nu] for j in range(3))
    # u(s) = ua + beta s + gamma s^2 through (0, ua), (h/2, um), (h, ub); c = 2 gamma
    ga = e0 - 3.0 / h * e1 + 4.0 / h ** 2 * e2
    gm = 4.0 / h * e1 - 8.0 / h ** 2 * e2
    gb = -1.0 / h * e1 + 4.0 / h ** 2 * e2
    return (np.ascontiguousarray(ad), np.ascontiguousarray(ga[:, :n]),
            np.ascontiguousarray(gm[:, :n]), np.ascontiguousarray(gb[:, :n]),
            np.ascontiguousarray(e0))
