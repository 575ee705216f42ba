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
Closed-loop velocity controller: PI with torque limit and anti-windup (Fig. 2 of the paper).

The same compiled PI step runs inside the batch simulation and in the controller node, so the
node graph and the offline runner compute identical torques.

Optional filters (issue #51, ``frf-ident tune``): per axis a chain of second-order sections
[b0, b1, b2, 1, a1, a2] (scipy's ``sos`` layout, transposed direct form II) on the measured
velocity in front of the PI: u = PI(r - F y). The loop gain is C P with C = PI F, as for a
filter on the torque setpoint, while the PI's anti-windup stays exact and the reference is not
filtered; it is where a ros2_control chain puts it (chained_filter_controller on the state
interface in front of pid_controller). Without filters (the default, zero sections) the
torques are bit for bit those of the PI alone.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.model.schema import check_sections, controller_filters, controller_gains
import numba
import numpy as np

__all__ = ['closed_loop_step', 'controller_from_dict', 'filter_measurement', 'PIVelocity',
           'pi_step', 'sos_step']


@numba.njit(cache=True, fastmath=True, inline='always')
def sos_step(x, sos, zf, i):
    """
    Filter one sample of axis ``i`` through its second-order sections.

    Transposed direct form II per section s: y = b0 x + z0, z0 = b1 x - a1 y + z1,
    z1 = b2 x - a2 y, then x = y for the next section. Compiled with numba.

    Parameters
    ----------
    x : float
        Input sample.
    sos : ndarray, shape (n, n_sections, 6)
        [b0, b1, b2, 1, a1, a2] per axis and section.
    zf : ndarray, shape (n, n_sections, 2)
        Filter states; updated in place.
    i : int
        The axis.

    Returns
    -------
    float
        The filtered sample (``x`` itself without sections).

    """
    for s in range(sos.shape[1]):
        y = sos[i, s, 0] * x + zf[i, s, 0]
        zf[i, s, 0] = sos[i, s, 1] * x - sos[i, s, 4] * y + zf[i, s, 1]
        zf[i, s, 1] = sos[i, s, 2] * x - sos[i, s, 5] * y
        x = y
    return x


@numba.njit(cache=True, fastmath=True)
def filter_measurement(y, sos, zf, out):
    """
    Filter a measured velocity sample of every axis; a non-finite entry passes unfiltered.

    Parameters
    ----------
    y : ndarray, shape (n,)
        Measured velocities.
    sos, zf : ndarray
        As :func:`sos_step`.
    out : ndarray, shape (n,)
        Output, written in place (a non-finite y leaves that axis' filter state untouched).

    Returns
    -------
    None
        The result is ``out``.

    """
    for i in range(y.shape[0]):
        out[i] = sos_step(y[i], sos, zf, i) if math.isfinite(y[i]) else y[i]


@numba.njit(cache=True, fastmath=True, inline='always')
def pi_step(e, integ, kp, ki, ff, k, ulim, dt, u):
    """
    Compute one velocity PI step with torque limit and back-calculation anti-windup.

    Per axis: I += ki e dt, then u = kp e + I + ff[k]; when u saturates, I is set so u sits
    at the limit. Compiled with numba; works in place.

    Parameters
    ----------
    e : ndarray, shape (n,)
        Velocity error r - y [rad/s].
    integ : ndarray, shape (n,)
        Integral state I [N m]; updated in place.
    kp, ki : ndarray, shape (n,)
        Proportional and integral gains.
    ff : ndarray, shape (K, n)
        Feed-forward torque table [N m].
    k : int
        Row of ``ff`` to add.
    ulim : ndarray, shape (n,)
        Torque limit, positive [N m].
    dt : float
        Sample time in s.
    u : ndarray, shape (n,)
        Output: the torque command [N m], written in place.

    Returns
    -------
    None
        The results are ``u`` and ``integ``.

    """
    for i in range(e.shape[0]):
        integ[i] += ki[i] * e[i] * dt
        v = kp[i] * e[i] + integ[i] + ff[k, i]
        if v > ulim[i]:
            integ[i] -= v - ulim[i]
            v = ulim[i]
        elif v < -ulim[i]:
            integ[i] -= v + ulim[i]
            v = -ulim[i]
        u[i] = v


@numba.njit(cache=True, fastmath=True, inline='always')
def closed_loop_step(r, k, q, v, has_plan, kpos, qplan, sos, zf, integ, kp, ki, ff, ulim, dt,
                     e, u, out_r):
    """
    Compute one sample of the velocity loop every simulated plant closes (ours and MuJoCo's).

    The reference r[k] gets the position plan's feedback, r_k + kpos (qplan_k - q_k), where
    ``has_plan`` (as the excitation node does for moves) and is written to out_r[k]; the
    measured velocity ``v`` passes the controller's second-order sections (``sos`` with no
    sections: no filter); then :func:`pi_step` gives the torque command ``u``.

    Parameters
    ----------
    r, qplan : ndarray, shape (K, n)
        Velocity reference [rad/s] and planned position [rad] per sample.
    k : int
        The sample.
    q, v : ndarray, shape (n,)
        Measured position [rad] and velocity [rad/s] at the sample.
    has_plan : bool
        Whether ``qplan`` feeds back.
    kpos : ndarray, shape (n,)
        Position feedback gain [1/s].
    sos, zf : ndarray
        Second-order sections (n, n_sections, 6) and their state; updated in place.
    integ, kp, ki, ff, ulim, dt, u
        As :func:`pi_step`.
    e : ndarray, shape (n,)
        Scratch: the velocity error.
    out_r : ndarray, shape (K, n)
        The reference used, row k written.

    Returns
    -------
    None
        The results are ``u``, ``out_r[k]``, ``integ`` and ``zf``.

    """
    for i in range(q.shape[0]):
        ref = r[k, i]
        if has_plan:
            ref += kpos[i] * (qplan[k, i] - q[i])
        out_r[k, i] = ref
        if sos.shape[1] > 0:
            e[i] = ref - sos_step(v[i], sos, zf, i)
        else:
            e[i] = ref - v[i]
    pi_step(e, integ, kp, ki, ff, k, ulim, dt, u)


@dataclass
class PIVelocity:
    """
    Velocity PI u = kp (r - y) + ki int (r - y) dt + ff, limited to +-torque_limit.

    The controller K of the closed loop (Fig. 2). Anti-windup by back-calculation: while
    saturated the integral is held so that u sits exactly at the limit. With filters, y is
    the filtered measurement F y (module doc).

    Parameters
    ----------
    kp : array_like, shape (n,)
        Proportional gains, >= 0 [N m s/rad].
    ki : float or array_like, shape (n,)
        Integral gains, >= 0 [N m/rad].
    torque_limit : float or array_like, shape (n,)
        Torque limits, > 0 [N m].
    dt : float
        Sample time in s.
    integral : array_like, shape (n,), optional
        Controller state [N m], e.g. the holding (gravity) torque so the loop starts at rest;
        default zero.
    sos : array_like, shape (n, n_sections, 6), optional
        Filters on the measured velocity (module doc), discrete at ``dt``; an axis with fewer
        sections than another is padded with pass-through sections [1, 0, 0, 1, 0, 0].
        Default none.
    filter_state : array_like, shape (n, n_sections, 2), optional
        The filters' states; default zero (the robot at rest).

    Raises
    ------
    ValueError
        A gain is negative, a torque limit not positive, or a filter not usable
        (:func:`frf_ident.core.model.schema.check_sections`).

    """

    kp: np.ndarray
    ki: np.ndarray
    torque_limit: np.ndarray
    dt: float
    integral: np.ndarray = field(default=None)  # type: ignore[assignment]
    sos: np.ndarray = field(default=None)  # type: ignore[assignment]
    filter_state: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        self.kp = np.atleast_1d(np.asarray(self.kp, dtype=float))
        n = self.kp.size
        self.ki = np.broadcast_to(np.asarray(self.ki, dtype=float), (n,)).copy()
        self.torque_limit = np.broadcast_to(np.asarray(self.torque_limit, dtype=float),
                                            (n,)).copy()
        if np.any(self.kp < 0) or np.any(self.ki < 0):
            raise ValueError(f'controller gains must be >= 0, got kp={self.kp}, ki={self.ki}')
        if np.any(self.torque_limit <= 0):
            raise ValueError(f'{self.torque_limit=} must be positive')
        if self.integral is None:
            self.integral = np.zeros(n)
        self.integral = np.asarray(self.integral, dtype=float).copy()
        self.sos = np.zeros((n, 0, 6)) if self.sos is None else \
            np.ascontiguousarray(self.sos, dtype=float).copy()
        if self.sos.ndim != 3 or self.sos.shape[0] != n or self.sos.shape[2] != 6:
            raise ValueError(f'sos: expected shape ({n}, n_sections, 6), got {self.sos.shape}')
        for i in range(n):
            problem = check_sections(self.sos[i])
            if problem is not None:
                raise ValueError(f'filters of axis {i}: {problem}')
        self.filter_state = np.zeros(self.sos.shape[:2] + (2,)) if self.filter_state is None \
            else np.ascontiguousarray(self.filter_state, dtype=float).copy()
        if self.filter_state.shape != self.sos.shape[:2] + (2,):
            raise ValueError(f'filter_state: expected shape {self.sos.shape[:2] + (2,)}, got '
                             f'{self.filter_state.shape}')

    @property
    def n_sections(self) -> int:
        """Return the number of filter sections per axis (0: the PI alone)."""
        return self.sos.shape[1]

    @property
    def n_axes(self) -> int:
        """Return the number of axes n."""
        return self.kp.size

    def reset(self, holding_torque: np.ndarray | None = None) -> None:
        """
        Reset the integral state (and the filters' states to rest).

        Parameters
        ----------
        holding_torque : array_like, shape (n,), optional
            New integral state [N m] (e.g. gravity); default zero.

        """
        self.integral = np.zeros(self.n_axes) if holding_torque is None else \
            np.asarray(holding_torque, dtype=float).copy()
        self.filter_state = np.zeros_like(self.filter_state)

    def step(self, reference: np.ndarray, measured: np.ndarray,
             feedforward: np.ndarray | None = None) -> np.ndarray:
        """
        Compute one control step: the torque command for reference r and measurement y.

        Parameters
        ----------
        reference : array_like, shape (n,)
            Velocity reference r [rad/s].
        measured : array_like, shape (n,)
            Measured velocity y [rad/s].
        feedforward : array_like, shape (n,), optional
            Torque added before the limit [N m]; default zero.

        Returns
        -------
        ndarray, shape (n,)
            Torque command u [N m], within +-torque_limit; ``integral`` is updated. An axis
            whose error or feedforward is not finite gets its integral torque alone (no P
            action, no integration; its filters hold their state).

        """
        y = np.asarray(measured, dtype=float)
        if self.sos.shape[1]:
            yf = np.empty(self.n_axes)
            filter_measurement(np.ascontiguousarray(y.reshape(self.n_axes)), self.sos,
                               self.filter_state, yf)
            y = yf
        e = np.asarray(reference, dtype=float) - y
        ff = np.zeros(self.n_axes) if feedforward is None else np.asarray(feedforward, float)
        # a measurement that is no number (the PI is compiled with fastmath, which assumes
        # none): that axis gets no P action and no integration, so it keeps the integral
        # torque that held its load; never a NaN torque, never a saturated one by accident
        bad = ~(np.isfinite(e) & np.isfinite(ff))
        if bad.any():
            e, ff = np.where(bad, 0.0, e), np.where(bad, 0.0, ff)
        u = np.empty(self.n_axes)
        pi_step(e, self.integral, self.kp, self.ki, ff.reshape(1, -1), 0, self.torque_limit,
                self.dt, u)
        return u

    def copy(self) -> 'PIVelocity':
        """
        Return a deep copy of the controller (gains, limits and state).

        Returns
        -------
        PIVelocity
            The copy.

        """
        return PIVelocity(self.kp.copy(), self.ki.copy(), self.torque_limit.copy(), self.dt,
                          self.integral.copy(), self.sos.copy(), self.filter_state.copy())


def controller_from_dict(d: dict[str, Any], robot: RobotParams) -> PIVelocity:
    """
    Return the model file's velocity controller (torque limits from the axes).

    The ``controller`` section of a loaded model file (docs/CONTRACT.md §5), its gains checked
    by :func:`frf_ident.core.model.schema.controller_gains` and its filters (an extension,
    docs/model_file.md) by :func:`frf_ident.core.model.schema.controller_filters`; the
    integral starts at the gravity load of the zero pose.
    """
    kp, ki = controller_gains(d, robot)
    ctrl = PIVelocity(kp, ki, robot.torque_limits(), robot.dt, sos=controller_filters(d, robot))
    ctrl.reset(robot.gravity_load(np.zeros(robot.n_axes)))
    return ctrl
