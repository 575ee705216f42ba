"""
Closed-loop velocity controller: PI with torque limit and anti-windup (Fig. 2 of the paper).

The same compiled PI step runs inside the batch simulation and in the controller node, so the
node graph and the offline runner compute identical torques.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np


@numba.njit(cache=True, fastmath=True)
def pi_step(e, integ, kp, ki, ff, k, ulim, dt, u):
    """
    Velocity PI with torque limit and back-calculation anti-windup (per axis, in place).

    u = kp e + I + ff[k], I += ki e dt; when u saturates, I is set so u sits at the limit.
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

    Anti-windup by back-calculation: while saturated the integral is held so that u sits
    exactly at the limit. ``integral`` is the controller state (N m), initialised to the
    holding torque (e.g. gravity) so the loop starts at rest.
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
        return self.kp.size

    def reset(self, holding_torque: np.ndarray | None = None) -> None:
        self.integral = np.zeros(self.n_axes) if holding_torque is None else \
            np.asarray(holding_torque, dtype=float).copy()

    def step(self, reference: np.ndarray, measured: np.ndarray,
             feedforward: np.ndarray | None = None) -> np.ndarray:
        """One control step: torque command for velocity reference r and measured velocity y."""
        e = np.asarray(reference, dtype=float) - np.asarray(measured, dtype=float)
        ff = np.zeros(self.n_axes) if feedforward is None else np.asarray(feedforward, float)
        u = np.empty(self.n_axes)
        pi_step(e, self.integral, self.kp, self.ki, ff.reshape(1, -1), 0, self.torque_limit,
                self.dt, u)
        return u

    def copy(self) -> 'PIVelocity':
        return PIVelocity(self.kp.copy(), self.ki.copy(), self.torque_limit.copy(), self.dt,
                          self.integral.copy())
