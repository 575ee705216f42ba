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
controller_node: the model file's velocity PI between /joint_states and the effort commands.

Subscribes /joint_states (y = velocity) and /velocity_controller/commands (r), publishes
/effort_controller/commands (u = PI(r, y), always within +-torque_limit: the PI saturates with
anti-windup, and non-finite references count as zero).

lockstep: true  -- references are consumed in order, one per joint-state sample: the excitation
                   node publishes them ahead, so each step costs one hop plant -> controller ->
                   plant. A joint state without its reference waits for it.
lockstep: false -- the latest reference is used (as ros2_control's forward controllers do),
                   for at most ``reference_timeout_s`` of joint-state time: a non-zero
                   reference that is not renewed within it (the excitation node died or
                   stalls) is dropped to zero, logged once, so the robot stops instead of
                   running on at the last velocity. The excitation node renews its reference
                   with every joint state while it runs and ends on zero.
Joint states with a stamp not newer than the last one are ignored (the idle re-send).
"""
from __future__ import annotations

from collections import deque
import math
from typing import Any, Optional, Sequence

from frf_ident import middleware as mw
from frf_ident.errors import FrfIdentInputError
from frf_ident.nodes import common as c
import numpy as np

#: free-running: joint-state time [s] a non-zero velocity reference is held without renewal
REFERENCE_TIMEOUT_S = 0.1


class HeldReference:
    """
    The latest velocity reference, dropped to zero when not renewed within a timeout.

    Time is the joint states' stamp time (the robot's clock), so a stalled reference source
    counts however the messages are delayed. It expires only once at least two joint states
    came without a renewal: a single late joint state (a jump of the stamps) never drops a
    reference that is renewed with every joint state. A jog by hand must be renewed at least
    every ``timeout_s`` (``ros2 topic pub -r 20``).

    Parameters
    ----------
    n : int
        Number of joints.
    timeout_s : float
        How long [s] a non-zero reference is held without renewal (> 0).

    Raises
    ------
    FrfIdentInputError
        ``timeout_s`` is not a positive number.

    """

    def __init__(self, n: int, timeout_s: float) -> None:
        if not (math.isfinite(timeout_s) and timeout_s > 0):
            raise FrfIdentInputError(f'reference_timeout_s={timeout_s} must be a positive '
                                     f'number of seconds')
        self.timeout_ns = int(round(timeout_s * 1e9))
        self.value = np.zeros(n)
        self.stamp_ns: Optional[int] = None     # joint-state time the reference came at
        self.states = 0                         # joint states since the renewal

    def renew(self, r: np.ndarray, now_ns: int) -> None:
        """
        Take a new reference.

        Parameters
        ----------
        r : ndarray, shape (n,)
            Velocity reference [rad/s].
        now_ns : int
            Stamp [ns] of the newest joint state, or a negative number before the first one.

        """
        self.value = r
        self.stamp_ns = now_ns if now_ns >= 0 else None
        self.states = 0

    def at(self, now_ns: int) -> tuple[np.ndarray, Optional[np.ndarray]]:
        """
        Return the reference to use at a joint state, and the one that just expired.

        Parameters
        ----------
        now_ns : int
            Stamp [ns] of the joint state.

        Returns
        -------
        ndarray, shape (n,)
            The held reference, or zero once it expired.
        ndarray or None
            The non-zero reference that expired at this joint state (log it), else None.

        """
        if self.stamp_ns is None:
            self.stamp_ns = now_ns
        self.states += 1
        if (now_ns - self.stamp_ns > self.timeout_ns and self.states >= 2
                and np.any(self.value != 0)):
            dropped, self.value = self.value, np.zeros_like(self.value)
            return self.value, dropped
        return self.value, None


class VelocityLoop:
    """
    The model file's velocity PI with the node's input and output rules.

    References of the wrong length count as zero (logged), non-finite entries as zero; the
    torque is always within +-torque_limit, and a non-finite torque becomes zero. Used by this
    node and by ``plant_node`` when it hosts the PI (``velocity_control: true``).
    """

    def __init__(self, node: Any, model_path: str) -> None:
        from frf_ident.io.model_file import load_model
        self.node = node
        _model, robot, self.ctrl = load_model(model_path or None)
        self.joints = list(robot.joint_names)
        self.n = len(self.joints)
        self.ctrl.torque_limit = np.minimum(self.ctrl.torque_limit, robot.torque_limits())
        self.ctrl.copy().step(np.zeros(self.n), np.zeros(self.n))   # load the compiled PI now

    def reference(self, data: Any) -> np.ndarray:
        """Return the sanitised velocity reference of a command message's data."""
        r = np.asarray(data, dtype=float)
        if r.shape != (self.n,):
            self.node.get_logger().error(f'velocity command has {r.size} values for {self.n} '
                                         'joints; using zero')
            return np.zeros(self.n)
        if not np.all(np.isfinite(r)):
            r = np.where(np.isfinite(r), r, 0.0)
        return r

    def torque(self, r: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Return the PI torque for reference ``r`` and measured velocity ``y``."""
        u = self.ctrl.step(r, y)
        lim = self.ctrl.torque_limit
        u = np.minimum(np.maximum(u, -lim), lim)   # enforced whatever the PI state
        if not all(map(math.isfinite, u)):
            u = np.zeros(self.n)
        return u


class ControllerNode:
    def __init__(self, node: Any) -> None:
        self.node = node
        model_path = c.param(node, 'model', '')
        self.lockstep = bool(c.param(node, 'lockstep', c.LOCKSTEP))
        c.refuse_lockstep_without_sim(node, self.lockstep)
        t = c.topics(node, ('joint_states_topic', 'effort_topic', 'velocity_topic'))
        self.loop = VelocityLoop(node, model_path)
        self.ctrl, self.joints, self.n = self.loop.ctrl, self.loop.joints, self.loop.n
        F64 = mw.msg('std_msgs/msg/Float64MultiArray')
        self.cmd = F64(data=[0.0] * self.n)
        self.pub = node.create_publisher(F64, t['effort_topic'], mw.qos_default(c.DEEP))
        self.refs: deque = deque()
        self.timeout_s = float(c.param(node, 'reference_timeout_s', REFERENCE_TIMEOUT_S))
        self.held = HeldReference(self.n, self.timeout_s)
        self.pending: Optional[np.ndarray] = None
        self.last_stamp = -1
        self.order: Optional[list[int]] = None
        self.names: Optional[list[str]] = None
        node.create_subscription(F64, t['velocity_topic'], self._on_ref,
                                 c.control_qos(self.lockstep))
        node.create_subscription(mw.msg('sensor_msgs/msg/JointState'), t['joint_states_topic'],
                                 self._on_state, c.control_qos(self.lockstep))

    def _ref(self, data: Any) -> np.ndarray:
        return self.loop.reference(data)

    def _on_ref(self, msg: Any) -> None:
        r = self._ref(msg.data)
        if not self.lockstep:
            self.held.renew(r, self.last_stamp)
            return
        if self.pending is not None:
            y, self.pending = self.pending, None
            self._control(r, y)
        else:
            self.refs.append(r)

    def _velocity(self, msg: Any) -> np.ndarray:
        names = msg.name
        if self.names is None or list(names) != self.names:
            self.names = list(names)
            pos = {n: i for i, n in enumerate(names)}
            missing = [j for j in self.joints if j not in pos]
            if missing:
                raise RuntimeError(f'/joint_states lacks joints {missing}')
            self.order = [pos[j] for j in self.joints]
        v = msg.velocity
        return np.array([v[i] for i in self.order], dtype=float)

    def _on_state(self, msg: Any) -> None:
        s = c.stamp_ns(msg)
        if s <= self.last_stamp:
            return
        self.last_stamp = s
        y = self._velocity(msg)
        if not self.lockstep:
            r, dropped = self.held.at(s)
            if dropped is not None:
                self.node.get_logger().warn(
                    f'no velocity reference for {self.timeout_s:g} s (reference_timeout_s): '
                    f'zero velocity instead of {[float(f"{v:.4g}") for v in dropped]} rad/s')
            self._control(r, y)
        elif self.refs:
            self._control(self.refs.popleft(), y)
        else:
            self.pending = y

    def _control(self, r: np.ndarray, y: np.ndarray) -> None:
        self.cmd.data = self.loop.torque(r, y).tolist()
        self.pub.publish(self.cmd)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """``ros2 run frf_ident controller_node``."""
    return c.run_node('controller_node', ControllerNode, argv)


if __name__ == '__main__':
    raise SystemExit(main())
