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
part of its link inertia on a spring and damper behind the link (linear, in
:func:`~frf_ident.core.simulation.linear.state_space`).

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

This module is the plant's Python API (:class:`FlexibleJointPlant`, :class:`SimResult`,
:func:`static_deflection`). The linear part and its exact discretisation are in
:mod:`frf_ident.core.simulation.linear`, the parameters packed for the kernels in
:mod:`frf_ident.core.simulation.packed`, the compiled sample loop in
:mod:`frf_ident.core.simulation.kernels`.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any

from frf_ident.core.model.params import AxisParams, RobotParams
from frf_ident.core.simulation.kernels import NSCRATCH, simulate, step_one
from frf_ident.core.simulation.packed import pack, ULIM
import numpy as np


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
        self._packed = pack(self.params)
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
        self._scratch = np.zeros((NSCRATCH, self.x.size))
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
        simulate(self.x, self.qprev, integ, self.buf, r, u_ext, uff, has_ff, kp, ki, ulim,
                 closed, sos, zf, int(self.params.substeps), self.dt, p.offsets, p.nbuf, p.prm,
                 p.ad,
                 p.gold, p.gnew, p.ga, p.gm, p.gb, p.gw, p.cg, p.ra, p.rs, p.rp, p.gamp, p.gph,
                 p.gsel, p.nonlinear,
                 p.enc, bool(self.params.velocity_from_encoder), vn, tn, qplan, kpos, has_plan,
                 out_q, out_v, out_u, out_x, keep_states, out_r,
                 np.zeros((NSCRATCH, self.x.size)), np.zeros((4, n)))
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
        step_one(self.x, self.qprev, self.buf, u, p.offsets, p.nbuf, int(self.params.substeps),
                 self.dt, p.prm, p.ad, p.gold, p.gnew, p.ga, p.gm, p.gb, p.gw, p.cg, p.ra, p.rs,
                 p.rp, p.gamp, p.gph, p.gsel, p.nonlinear, p.enc,
                 bool(self.params.velocity_from_encoder), vn, self._scratch, q, v)
        self.k += 1
        return q, v, u + tn[0]
