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
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.model.schema import controller_gains
import numba
import numpy as np

__all__ = ['controller_from_dict', 'PIVelocity', 'pi_step']


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


@dataclass
class PIVelocity:
    """
    Velocity PI u = kp (r - y) + ki int (r - y) dt + ff, limited to +-torque_limit.

    The controller K of the closed loop (Fig. 2). Anti-windup by back-calculation: while
    saturated the integral is held so that u sits exactly at the limit.

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

    Raises
    ------
    ValueError
        A gain is negative or a torque limit not positive.

    """

    kp: np.ndarray
    ki: np.ndarray
    torque_limit: np.ndarray
    dt: float
    integral: np.ndarray = field(default=None)  # type: ignore[assignment]

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

    @property
    def n_axes(self) -> int:
        """Return the number of axes n."""
        return self.kp.size

    def reset(self, holding_torque: np.ndarray | None = None) -> None:
        """
        Reset the integral state.

        Parameters
        ----------
        holding_torque : array_like, shape (n,), optional
            New integral state [N m] (e.g. gravity); default zero.

        """
        self.integral = np.zeros(self.n_axes) if holding_torque is None else \
            np.asarray(holding_torque, dtype=float).copy()

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
            action, no integration).

        """
        e = np.asarray(reference, dtype=float) - np.asarray(measured, dtype=float)
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
                          self.integral.copy())


def controller_from_dict(d: dict[str, Any], robot: RobotParams) -> PIVelocity:
    """
    Return the model file's velocity controller (torque limits from the axes).

    The ``controller`` section of a loaded model file (docs/CONTRACT.md §5), its gains checked
    by :func:`frf_ident.core.model.schema.controller_gains`; the integral starts at the
    gravity load of the zero pose.
    """
    kp, ki = controller_gains(d, robot)
    ctrl = PIVelocity(kp, ki, robot.torque_limits(), robot.dt)
    ctrl.reset(robot.gravity_load(np.zeros(robot.n_axes)))
    return ctrl
