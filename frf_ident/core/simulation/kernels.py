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
Compiled (numba) kernels of the flexible-joint plant's sample loop.

The exponential integrator of :mod:`frf_ident.core.simulation.plant`: the residual torques
beyond the linear model (eq. 2 spring beyond k1, backlash, ripple, configuration-dependent
gravity), one substep (exact linear part, exponential Heun step for the residual, Coulomb
friction as a velocity projection), one sample through the input delay, the measurement, and
the two entry points :func:`simulate` (many samples, optional PI in the loop) and
:func:`step_one` (one sample of a command given from outside). The helpers are inlined into
the entry points; their arguments are the arrays of :class:`~.packed.Packed`.
"""
from __future__ import annotations

import math

from frf_ident.core.simulation.controller import closed_loop_step
from frf_ident.core.simulation.packed import BL, BS, DAMP, FC, JM, K1, K2, ULIM
import numba


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
_UO, _UN, _FA, _FM, _FB, _LIN, _XP, _W1, _W2, NSCRATCH = range(10)


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
def simulate(x, qprev, integ, buf, r, u_ext, uff, has_ff, kp, ki, ulim_ctrl, closed, sos, zf,
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

    ``sc`` (NSCRATCH, nx) and ``work`` (4, n) are scratch arrays of the caller's (nx the
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
def step_one(x, qprev, buf, u, offsets, nbuf, m, dt, prm, ad, gold, gnew, ga, gm, gb, gw, cg,
             ra, rs, rp, gamp, gph, gsel, nonlinear, enc, from_encoder, vnoise, sc, q, v):
    """
    Advance one sample for a command given from outside (plug-in step).

    One sample of :func:`simulate` for a command u given from outside (plug-in step):
    the start position becomes qprev, u enters the delay buffer, the plant advances and the
    measurement at the end of the sample goes to q, v. The buffer is left rebased (latest
    command last), as the plant's ``FlexibleJointPlant._rebase_buffer`` leaves it.
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
