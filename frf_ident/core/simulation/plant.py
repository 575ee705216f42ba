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
Flexible-joint robot plant (Saupe & Knoblach 2015, eqs. 1, 2, 20-22) and its simulation.

Per axis i, motor position q_m, link position q_o, deflection dq = q_m - q_o (eq. 20):

    Jm  ddq_m = tau_m + tau_ripple(q_m) - tau_fc(dq_m) - b_v dq_m - tau_s(dq)
                - d (dq_m - dq_o)                                                  (eq. 21)
    M_o ddq_o = tau_s(dq) + d (dq_m - dq_o) - tau_g                                (eq. 22)

with Coulomb friction tau_fc = Fc sgn(dq_m) (eq. 1), the deflection-dependent spring tau_s of
eq. 2 (k1 up to the breakpoint bs, k2 beyond), an optional backlash dead zone of total width
``backlash`` in front of the spring, position-periodic torque ripple
sum a sin(s q_m + phase), a constant link-side gravity torque plus configuration-dependent
gravity terms G sin(sum_j q_o,j + phi) (a link's weight about its own joint, or summed over the
joints it depends on for a coupled arm), an input delay and a torque limit.
``M_o`` is the link inertia matrix: diagonal ``link_inertia`` plus optional symmetric coupling,
which makes the MIMO FRF non-diagonal and reciprocal. An axis' optional ``second_mode`` carries
part of its link inertia on a spring and damper behind the link (linear, in :func:`state_space`).

Measurement: motor position, optionally quantised by the encoder resolution; velocity either the
true motor velocity or, like a real drive, the difference of quantised positions over one sample;
additive Gaussian noise on velocity and torque. Everything is switchable and seeded.

Integration (exponential integrator, compiled with numba): the linear two-mass dynamics
(k1, d, viscous friction, coupling) are propagated exactly by precomputed matrix exponentials,
for the delayed zero-order-held command of a digital controller (exact for any delay) and for a
feed-forward torque interpolated quadratically on a stage grid of 2 ``substeps`` points per
sample (continuous-time excitations). Only the nonlinear residual torques (eq. 2 spring beyond
k1, backlash, ripple) use an exponential Heun step, and Coulomb friction a set-valued
velocity projection after each substep (a motor at rest sticks exactly while the drive stays
below Fc). Linear runs therefore match the analytic FRFs of
:mod:`frf_ident.core.simulation.analytic` to rounding. The error of the nonlinear part falls
with the substeps m as m^-2 for the smooth torques (stiffening spring, ripple) and as m^-1
where the dynamics switch inside a substep (stick-slip transitions, backlash contacts):
``python -m benchmarks discretisation`` measures it per effect against the noise a record has.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any

from frf_ident.core.model.params import AxisParams, RobotParams
from frf_ident.core.simulation.controller import closed_loop_step
import numba
import numpy as np
from scipy import linalg

# columns of the per-axis parameter matrix used by the kernels
JM, K1, K2, BS, DAMP, BV, FC, BL, GRAV, ULIM, NPARAM = range(11)


# --- packing for the compiled kernels ---------------------------------------------------------

@dataclass
class _Packed:
    prm: np.ndarray       # (n, NPARAM)
    ad: np.ndarray        # (nx, nx) state transition over one substep (nx = 4n + 2 modes)
    ga: np.ndarray        # (nx, n) input matrices for the stage values at start,
    gm: np.ndarray        # ... middle and end of a substep (quadratic interpolation)
    gb: np.ndarray
    gw: np.ndarray        # (nx, 2n) residual torques (motor side, link side), held
    cg: np.ndarray        # (nx,) effect of the constant gravity torque over one substep
    nonlinear: bool       # any residual torque (nonlinear spring, backlash, ripple)
    gold: np.ndarray      # (m, nx, n) held command, delayed: part of substep s under the older
    gnew: np.ndarray      # ... command u[k + offsets[s, 0, i]] and under the newer one
    ra: np.ndarray        # (n, R) ripple amplitudes
    rs: np.ndarray        # (n, R) spatial frequencies
    rp: np.ndarray        # (n, R) phases
    gamp: np.ndarray      # (n, G) gravity amplitudes G
    gph: np.ndarray       # (n, G) gravity phases phi
    gsel: np.ndarray      # (n, G, n) 1 where joint j's link position enters term g of axis i
    offsets: np.ndarray   # (m, 2, n) int: sample offsets of the older / newer command
    nbuf: int
    enc: np.ndarray       # (n,) encoder resolution
    vnoise: np.ndarray    # (n,)
    tnoise: np.ndarray    # (n,)


def _pack(params: RobotParams) -> _Packed:
    n = params.n_axes
    prm = np.zeros((n, NPARAM))
    n_rip = max([len(a.torque_ripple) for a in params.axes] + [1])
    ra, rs, rp = np.zeros((n, n_rip)), np.zeros((n, n_rip)), np.zeros((n, n_rip))
    dt, m = params.dt, int(params.substeps)
    n_g = max([len(a.gravity) for a in params.axes] + [1])
    gamp, gph, gsel = np.zeros((n, n_g)), np.zeros((n, n_g)), np.zeros((n, n_g, n))
    for i, a in enumerate(params.axes):
        for j, g in enumerate(a.gravity):
            gamp[i, j] = float(g['amplitude'])
            gph[i, j] = float(g.get('phase', 0.0))
            gsel[i, j, a.gravity_joints(params.joint_names, j)] = 1.0
        prm[i, JM] = a.motor_inertia
        prm[i, K1] = a.stiffness
        nonlinear = a.stiffness_k2 is not None and a.stiffness_breakpoint is not None
        prm[i, K2] = a.stiffness_k2 if nonlinear else a.stiffness
        prm[i, BS] = a.stiffness_breakpoint if nonlinear else 0.0
        prm[i, DAMP] = a.damping
        prm[i, BV] = a.viscous_friction
        prm[i, FC] = a.coulomb_friction
        prm[i, BL] = a.backlash
        prm[i, GRAV] = a.gravity_torque
        prm[i, ULIM] = a.torque_limit
        for j, rip in enumerate(a.torque_ripple):
            ra[i, j] = float(rip['amplitude'])
            rs[i, j] = float(rip['spatial_frequency'])
            rp[i, j] = float(rip.get('phase', 0.0))
    ad, ga, gm, gb, gw = _substep_matrices(params, dt / m)
    offsets, gold, gnew = _delayed_hold_matrices(params)
    nbuf = int(-offsets.min()) + 2
    nonlinear = bool(np.any(ra != 0) or np.any(prm[:, BL] > 0) or np.any(gamp != 0)
                     or np.any((prm[:, BS] > 0) & (prm[:, K2] != prm[:, K1])))
    cg = gw[:, n:] @ (-prm[:, GRAV])
    return _Packed(prm, ad, ga, gm, gb, gw, cg, nonlinear, gold, gnew, ra, rs, rp, gamp, gph,
                   gsel, offsets, nbuf,
                   np.array([a.encoder_resolution for a in params.axes]),
                   np.array([a.velocity_noise for a in params.axes]),
                   np.array([a.torque_noise for a in params.axes]))


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


def _delayed_hold_matrices(params: RobotParams):
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


def _substep_matrices(params: RobotParams, h: float):
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


# --- compiled kernels -------------------------------------------------------------------------

@numba.njit(cache=True, fastmath=True, error_model='numpy', inline='always')
def _spring(e, k1, k2, bs):
    """Deflection-dependent spring torque (eq. 2)."""
    if bs > 0.0 and abs(e) > bs:
        return math.copysign(k2 * (abs(e) - bs) + k1 * bs, e)
    return k1 * e


@numba.njit(cache=True, fastmath=True, error_model='numpy', inline='always')
def _residual(x, prm, ra, rs, rp, gamp, gph, gsel, sc, row):
    """
    Nonlinear residual torques beyond the linear model (k1, d) at flat state x.

    Writes sc[row, :n] = motor side ripple - (tau_s - k1 dq) - (tau_d - d dv) and
    sc[row, n:2n] = link side (tau_s - k1 dq) + (tau_d - d dv), with tau_s of eq. 2 behind the
    backlash dead zone and the transmission damping acting only in contact, minus the
    configuration-dependent gravity G sin(sum_j q_o,j + phi) on the link side. The constant
    gravity torque is an input (see _exp_substep). Kernels index preallocated rows instead of
    slicing, as array views cost reference counting in the hot loop.
    """
    n = prm.shape[0]
    for i in range(n):
        qm = x[i]
        dq = qm - x[2 * n + i]
        res = 0.0
        e = dq
        bl = prm[i, BL]
        if bl > 0.0:
            half = 0.5 * bl
            if dq > half:
                e = dq - half
            elif dq < -half:
                e = dq + half
            else:
                e = 0.0
                res = -prm[i, DAMP] * (x[n + i] - x[3 * n + i])
        res += _spring(e, prm[i, K1], prm[i, K2], prm[i, BS]) - prm[i, K1] * dq
        rip = 0.0
        for j in range(ra.shape[1]):
            a = ra[i, j]
            if a != 0.0:
                rip += a * math.sin(rs[i, j] * qm + rp[i, j])
        grav = 0.0
        for j in range(gamp.shape[1]):
            g = gamp[i, j]
            if g != 0.0:
                arg = gph[i, j]
                for c in range(n):
                    if gsel[i, j, c] != 0.0:
                        arg += x[2 * n + c]
                grav += g * math.sin(arg)
        sc[row, i] = rip - res
        sc[row, n + i] = res - grav


# rows of the kernels' scratch array
_UO, _UN, _FA, _FM, _FB, _LIN, _XP, _W1, _W2, _NSCRATCH = range(10)


@numba.njit(cache=True, fastmath=True, error_model='numpy', inline='always')
def _exp_substep(x, s, sc, has_ff, prm, ad, gold, gnew, ga, gm, gb, gw, cg, ra, rs, rp,
                 gamp, gph, gsel, nonlinear, h):
    """
    One substep of the exponential integrator, then Coulomb friction.

    Linear part exact: x+ = Ad x + Go uo + Gn un + cg for the delayed zero-order-held command
    (older / newer value, rows _UO/_UN of sc), plus Ga fa + Gm fm + Gb fb for a feed-forward
    torque quadratic through its values at start, middle and end of the substep; cg the
    constant gravity load. Nonlinear residual torques w(x) by the exponential Heun
    (trapezoidal) rule: x+ = lin + Gw (w(x) + w(x*)) / 2 with the predictor x* = lin + Gw w(x).
    """
    nx = x.shape[0]
    n = prm.shape[0]
    for r in range(nx):
        acc = cg[r]
        for c in range(nx):
            acc += ad[r, c] * x[c]
        for c in range(n):
            acc += gold[s, r, c] * sc[_UO, c] + gnew[s, r, c] * sc[_UN, c]
        if has_ff:
            for c in range(n):
                acc += ga[r, c] * sc[_FA, c] + gm[r, c] * sc[_FM, c] + gb[r, c] * sc[_FB, c]
        sc[_LIN, r] = acc
    if nonlinear:
        _residual(x, prm, ra, rs, rp, gamp, gph, gsel, sc, _W1)
        for r in range(nx):
            acc = sc[_LIN, r]
            for c in range(2 * n):
                acc += gw[r, c] * sc[_W1, c]
            sc[_XP, r] = acc
        _residual(sc[_XP], prm, ra, rs, rp, gamp, gph, gsel, sc, _W2)
        for r in range(nx):
            acc = sc[_LIN, r]
            for c in range(2 * n):
                acc += 0.5 * gw[r, c] * (sc[_W1, c] + sc[_W2, c])
            x[r] = acc
    else:
        for r in range(nx):
            x[r] = sc[_LIN, r]
    # Coulomb friction (eq. 1) as a set-valued force: the friction impulse over the substep is
    # at most Fc h; if that suffices to stop the motor it sticks (the instant of the switch
    # inside the substep is not located: first order in h across stick-slip transitions).
    for i in range(n):
        fc = prm[i, FC]
        if fc > 0.0:
            dvmax = fc * h / prm[i, JM]
            v = x[n + i]
            vnew = 0.0 if abs(v) <= dvmax else v - math.copysign(dvmax, v)
            x[i] += 0.5 * h * (vnew - v)
            x[n + i] = vnew


@numba.njit(cache=True, fastmath=True, error_model='numpy', inline='always')
def _advance(x, buf, k, offsets, nbuf, uff, has_ff, m, dt, prm, ad, gold, gnew, ga, gm, gb, gw,
             cg, ra, rs, rp, gamp, gph, gsel, nonlinear, sc):
    """
    Advance the plant over one sample [t_k, t_k+dt).

    Advance the plant over [t_k, t_k+dt): delayed zero-order-held commands from the ring
    buffer plus an optional feed-forward torque on the stage grid uff[2 m k ... 2 m k + 2 m].
    The total torque is limited to +-torque_limit (the feed-forward is cut where it would
    exceed the limit together with the command).
    """
    n = prm.shape[0]
    h = dt / m
    # ring-buffer rows without an integer division per read: offsets lie in (-nbuf, 0]
    kb = k % nbuf
    for s in range(m):
        for i in range(n):
            lim = prm[i, ULIM]
            ra_ = kb + offsets[s, 0, i]
            rb_ = kb + offsets[s, 1, i]
            if ra_ < 0:
                ra_ += nbuf
            if rb_ < 0:
                rb_ += nbuf
            a = min(max(buf[ra_, i], -lim), lim)
            b = min(max(buf[rb_, i], -lim), lim)
            sc[_UO, i] = a
            sc[_UN, i] = b
            if has_ff:
                base = 2 * m * k + 2 * s
                sc[_FA, i] = min(max(a + uff[base, i], -lim), lim) - a
                sc[_FM, i] = min(max(b + uff[base + 1, i], -lim), lim) - b
                sc[_FB, i] = min(max(b + uff[base + 2, i], -lim), lim) - b
        _exp_substep(x, s, sc, has_ff, prm, ad, gold, gnew, ga, gm, gb, gw, cg, ra, rs, rp,
                     gamp, gph, gsel, nonlinear, h)


@numba.njit(cache=True, fastmath=True, error_model='numpy', inline='always')
def _measure(x, qprev, enc, from_encoder, dt, vn, k, qout, vout):
    """Encode position (quantised) and velocity (true or by differentiation) plus noise vn[k]."""
    n = qout.shape[0]
    for i in range(n):
        q = x[i]
        if enc[i] > 0.0:
            q = enc[i] * math.floor(q / enc[i] + 0.5)
        qout[i] = q
        if from_encoder:
            vout[i] = (q - qprev[i]) / dt + vn[k, i]
        else:
            vout[i] = x[n + i] + vn[k, i]


# Without numba's reference counting (_nrt=False; the scratch arrays come from the caller):
# the helpers inlined into the sample loop took and released a reference to each of their
# ~20 array arguments per sample, atomic operations that dominated the run in `perf`. The
# signals are bit-identical; the speed is `python -m benchmarks --markdown simulation`.
@numba.njit(cache=True, fastmath=True, error_model='numpy', _nrt=False)
def _simulate(x, qprev, integ, buf, r, u_ext, uff, has_ff, kp, ki, ulim_ctrl, closed, sos, zf,
              m, dt, offsets, nbuf, prm, ad, gold, gnew, ga, gm, gb, gw, cg, ra, rs, rp, gamp, gph,
              gsel, nonlinear, enc, from_encoder, vnoise, tnoise, qplan, kpos, has_plan, out_q,
              out_v, out_u, out_x, keep_x, out_r, sc, work):
    """
    Run N samples. Closed loop: u = PI(r - y) + u_ext; open loop: u = u_ext (ZOH).

    The closed loop's sample is :func:`~frf_ident.core.simulation.controller.closed_loop_step`
    (shared with the MuJoCo plant): ``sos`` (n, n_sections, 6) and its state ``zf`` filter the
    measured velocity in front of the PI (no sections, no filter); with a position plan
    (``has_plan``) the velocity reference gets position feedback, r_k <- r_k + kpos (qplan_k -
    q_k), as the excitation node does for moves; out_r holds the reference actually used.

    ``sc`` (_NSCRATCH, nx) and ``work`` (4, n) are scratch arrays of the caller's (nx the
    state's length, 4 n plus two per second mode).
    ``uff`` adds a torque on the integrator's stage grid (continuous excitations). Fills
    out_q, out_v, out_u (measured effort = commanded torque at the sample + torque noise) and
    out_x (true states, N x 4 x n) where ``keep_x``. State arrays are updated in place so runs
    can be chained.
    """
    n = r.shape[1]
    N = r.shape[0]
    qm, vm, e, u = work[0], work[1], work[2], work[3]
    for k in range(N):
        _measure(x, qprev, enc, from_encoder, dt, vnoise, k, qm, vm)
        for i in range(n):
            qprev[i] = qm[i]
        if closed:
            closed_loop_step(r, k, qm, vm, has_plan, kpos, qplan, sos, zf, integ, kp, ki,
                             u_ext, ulim_ctrl, dt, e, u, out_r)
        else:
            for i in range(n):
                u[i] = min(max(u_ext[k, i], -ulim_ctrl[i]), ulim_ctrl[i])
        kb = k % nbuf
        for i in range(n):
            buf[kb, i] = u[i]
            applied = u[i]
            if has_ff:
                applied += uff[2 * m * k, i]
            applied = min(max(applied, -prm[i, ULIM]), prm[i, ULIM])
            out_q[k, i] = qm[i]
            out_v[k, i] = vm[i]
            out_u[k, i] = applied + tnoise[k, i]
            if keep_x:
                for s in range(4):
                    out_x[k, s, i] = x[s * n + i]
        _advance(x, buf, k, offsets, nbuf, uff, has_ff, m, dt, prm, ad, gold, gnew, ga, gm, gb,
                 gw, cg, ra, rs, rp, gamp, gph, gsel, nonlinear, sc)


@numba.njit(cache=True, fastmath=True, error_model='numpy', _nrt=False)
def _step_one(x, qprev, buf, u, offsets, nbuf, m, dt, prm, ad, gold, gnew, ga, gm, gb, gw, cg,
              ra, rs, rp, gamp, gph, gsel, nonlinear, enc, from_encoder, vnoise, sc, q, v):
    """
    Advance one sample for a command given from outside (plug-in step).

    One sample of :func:`_simulate` for a command u given from outside (plug-in step):
    the start position becomes qprev, u enters the delay buffer, the plant advances and the
    measurement at the end of the sample goes to q, v. The buffer is left rebased (latest
    command last), as :meth:`FlexibleJointPlant._rebase_buffer` leaves it.
    """
    n = u.shape[0]
    _measure(x, qprev, enc, False, dt, vnoise, 0, q, v)
    for i in range(n):
        qprev[i] = q[i]
        buf[0, i] = u[i]
    _advance(x, buf, 0, offsets, nbuf, buf, False, m, dt, prm, ad, gold, gnew, ga, gm, gb, gw,
             cg, ra, rs, rp, gamp, gph, gsel, nonlinear, sc)
    for r in range(nbuf - 1):
        for i in range(n):
            buf[r, i], buf[r + 1, i] = buf[r + 1, i], buf[r, i]
    _measure(x, qprev, enc, from_encoder, dt, vnoise, 0, q, v)


# --- Python API -------------------------------------------------------------------------------

@dataclass
class SimResult:
    """
    Sampled signals of a simulation run.

    Sampled signals of a simulation run, each (N, n): t (N,), q/v measured, u applied torque,
    states (N, 4, n) true [q_m, v_m, q_o, v_o] (None where the run was asked not to keep them).
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    states: np.ndarray | None
    reference: np.ndarray | None = None


def static_deflection(axis: AxisParams, load: float | None = None) -> float:
    """
    Return the spring deflection that carries the static link-side load.

    Spring deflection that carries the static link-side load (eq. 2 inverted, backlash
    added); ``load`` defaults to the constant ``gravity_torque``.
    """
    g = axis.gravity_torque if load is None else load
    if g == 0:
        return 0.0
    k1, bs = axis.stiffness, axis.stiffness_breakpoint
    if bs is not None and abs(g) > axis.stiffness * bs:
        e = bs + (abs(g) - k1 * bs) / axis.stiffness_k2
    else:
        e = abs(g) / k1
    return math.copysign(e + 0.5 * axis.backlash, g)


class FlexibleJointPlant:
    """
    Simulated robot, usable as a docs/CONTRACT.md §4 plant plug-in and for batch runs.

    ``step(torque)`` applies a motor torque for one sample (zero-order hold, through the input
    delay and torque limit) and returns the measurement (position, velocity, effort) at the end
    of the sample. :meth:`simulate` runs many samples at compiled speed, optionally with the
    velocity PI in the loop.
    """

    def __init__(self, config: dict | RobotParams | None = None) -> None:
        if isinstance(config, RobotParams):
            self.params = config
        else:
            from frf_ident.core.model.schema import default_robot, robot_from_dict
            self.params = robot_from_dict(config) if config else default_robot()
        self._packed = _pack(self.params)
        self.reset()

    @property
    def dt(self) -> float:
        return self.params.dt

    @property
    def joint_names(self) -> list[str]:
        return self.params.joint_names

    @property
    def n_axes(self) -> int:
        return self.params.n_axes

    @property
    def state(self) -> np.ndarray:
        """Return true state as a (4, n) view: rows q_m, v_m, q_o, v_o (second modes left out)."""
        return self.x[:4 * self.n_axes].reshape(4, self.n_axes)

    def equilibrium_torque(self, position: np.ndarray | None = None) -> np.ndarray:
        """
        Return the motor torque that holds the robot at rest against gravity.

        Parameters
        ----------
        position : array_like, shape (n,), optional
            Link positions [rad]; default all zero.

        Returns
        -------
        ndarray, shape (n,)
            Holding torque [N m] of every axis.

        """
        q = np.zeros(self.n_axes) if position is None else np.asarray(position, dtype=float)
        return self.params.gravity_load(q)

    def reset(self, seed: int | None = None, position: np.ndarray | None = None) -> None:
        """
        Back to rest at the static equilibrium under gravity.

        The noise generator continues (new noise in every run) unless ``seed`` is given.

        Parameters
        ----------
        seed : int, optional
            Restart the noise generator with this seed.
        position : array_like, shape (n,), optional
            Link positions [rad] of the rest state; default all zero.

        """
        n = self.n_axes
        q_link = np.zeros(n) if position is None else np.asarray(position, dtype=float)
        hold = self.equilibrium_torque(q_link)
        # flat [q_m, v_m, q_o, v_o, q_e, v_e] (state_space); see ``state``
        self.x = np.zeros(self._packed.ad.shape[0])
        self.x[2 * n:3 * n] = q_link
        modes = [i for i, a in enumerate(self.params.axes) if a.second_mode is not None]
        self.x[4 * n:4 * n + len(modes)] = q_link[modes]      # a second mode rests unloaded
        self.x[:n] = q_link + [static_deflection(a, g) for a, g in zip(self.params.axes, hold)]
        self.qprev = self.x[:n].copy()
        enc = self._packed.enc
        self.qprev = np.where(enc > 0, enc * np.floor(self.qprev / np.where(enc > 0, enc, 1)
                                                      + 0.5), self.qprev)
        self.buf = np.tile(hold, (self._packed.nbuf, 1))
        self._scratch = np.zeros((_NSCRATCH, self.x.size))
        self.k = 0
        if seed is not None or not hasattr(self, 'rng'):
            self.rng = np.random.default_rng(self.params.seed if seed is None else seed)

    def _noise(self, n_samples: int) -> tuple[np.ndarray, np.ndarray]:
        p = self._packed
        n = self.n_axes
        vn = self.rng.standard_normal((n_samples, n)) * p.vnoise if p.vnoise.any() \
            else np.zeros((n_samples, n))
        tn = self.rng.standard_normal((n_samples, n)) * p.tnoise if p.tnoise.any() \
            else np.zeros((n_samples, n))
        return vn, tn

    def simulate(self, *, reference: np.ndarray | None = None, torque: np.ndarray | None = None,
                 torque_fine: np.ndarray | None = None, controller: Any = None,
                 n_samples: int | None = None, position_plan: np.ndarray | None = None,
                 position_gain: float | np.ndarray = 0.0, keep_states: bool = True
                 ) -> SimResult:
        """
        Run samples from the current state.

        Closed loop (``controller`` given, a
        :class:`~frf_ident.core.simulation.controller.PIVelocity`, with its filters):
        u = PI(reference - F y) + torque. Open loop: u = torque (zero-order hold). ``torque_fine``
        is an extra torque on the integrator's stage grid, shape (2 m N + 1, n) with
        m = substeps, used for continuous-time excitations (e.g. the paper's open-loop example).
        ``position_plan`` (N, n): absolute measured positions to hold with ``position_gain``
        [1/s] of position feedback on the reference (closed loop only); the reference used is
        returned in ``SimResult.reference``. ``keep_states=False`` leaves the true states out
        (``SimResult.states`` None): the batch runs that read only the measurement skip
        writing N x 4 x n values.
        """
        n = self.n_axes
        lengths = [a.shape[0] for a in (reference, torque) if a is not None]
        if torque_fine is not None:
            lengths.append((torque_fine.shape[0] - 1) // (2 * self.params.substeps))
        N = n_samples if n_samples is not None else (lengths[0] if lengths else 0)
        if any(L != N for L in lengths):
            raise ValueError(f'input lengths {lengths} differ from {N=}')
        r = np.zeros((N, n)) if reference is None else np.ascontiguousarray(reference, float)
        u_ext = np.zeros((N, n)) if torque is None else np.ascontiguousarray(torque, float)
        has_ff = torque_fine is not None
        uff = np.ascontiguousarray(torque_fine, float) if has_ff else np.zeros((1, n))
        p = self._packed
        vn, tn = self._noise(N)
        out_q, out_v, out_u = np.empty((N, n)), np.empty((N, n)), np.empty((N, n))
        out_x = np.empty((N if keep_states else 1, 4, n))
        out_r = r.copy()
        has_plan = position_plan is not None
        qplan = np.ascontiguousarray(position_plan, float) if has_plan else np.zeros((1, n))
        kpos = np.broadcast_to(np.asarray(position_gain, float), (n,)).copy()
        if controller is not None:
            kp, ki, ulim, integ, closed = (controller.kp, controller.ki,
                                           np.minimum(controller.torque_limit,
                                                      self.params.torque_limits()),
                                           controller.integral, True)
            sos, zf = controller.sos, controller.filter_state
        else:
            kp = ki = np.zeros(n)
            ulim, integ, closed = self.params.torque_limits(), np.zeros(n), False
            sos, zf = np.zeros((n, 0, 6)), np.zeros((n, 0, 2))
        _simulate(self.x, self.qprev, integ, self.buf, r, u_ext, uff, has_ff, kp, ki, ulim,
                  closed, sos, zf, int(self.params.substeps), self.dt, p.offsets, p.nbuf, p.prm,
                  p.ad,
                  p.gold, p.gnew, p.ga, p.gm, p.gb, p.gw, p.cg, p.ra, p.rs, p.rp, p.gamp, p.gph,
                  p.gsel, p.nonlinear,
                  p.enc, bool(self.params.velocity_from_encoder), vn, tn, qplan, kpos, has_plan,
                  out_q, out_v, out_u, out_x, keep_states, out_r,
                  np.zeros((_NSCRATCH, self.x.size)), np.zeros((4, n)))
        t = (self.k + np.arange(N)) * self.dt
        self.k += N
        self._rebase_buffer(N)
        return SimResult(t, out_q, out_v, out_u, out_x if keep_states else None, out_r)

    def _rebase_buffer(self, n_done: int) -> None:
        """Keep the ring buffer indexed from sample 0 of the next run."""
        nbuf = self._packed.nbuf
        shift = n_done % nbuf
        if shift:
            self.buf = np.ascontiguousarray(np.roll(self.buf, -shift, axis=0))

    def step(self, torque: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Apply motor torque [N m] for one sample; return (position, velocity, effort).

        docs/CONTRACT.md §4: the returned measurement is taken at the end of the sample, the
        effort is the torque applied (after the torque limit) plus torque noise. Runs the same
        compiled kernels as :meth:`simulate` without its batch bookkeeping (the node hot path).
        """
        p = self._packed
        lim = p.prm[:, ULIM]
        u = np.clip(np.asarray(torque, dtype=float).reshape(self.n_axes), -lim, lim)
        vn, tn = self._noise(1)
        q, v = np.empty(self.n_axes), np.empty(self.n_axes)
        _step_one(self.x, self.qprev, self.buf, u, p.offsets, p.nbuf, int(self.params.substeps),
                  self.dt, p.prm, p.ad, p.gold, p.gnew, p.ga, p.gm, p.gb, p.gw, p.cg, p.ra, p.rs,
                  p.rp, p.gamp, p.gph, p.gsel, p.nonlinear, p.enc,
                  bool(self.params.velocity_from_encoder), vn, self._scratch, q, v)
        self.k += 1
        return q, v, u + tn[0]
