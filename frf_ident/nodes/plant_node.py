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
plant_node: the simulated robot (model file) or a docs/CONTRACT.md §4 plug-in plant.

Subscribes the effort commands (Float64MultiArray, joint order), publishes /joint_states
(position, velocity = plant output y, effort = the torque applied over the sample that just
ended; header.stamp = sample time k*dt) and /clock every ``clock_every`` samples (every node
with use_sim_time takes each /clock message in Python: one per sample would cost more than the
joint state itself; node clocks and timers only need it coarse, sample indices come from the
stamps).

lockstep: true  -- one sample per received command (deterministic, faster than real time); the
                   current joint state is re-sent every ``idle_republish_s`` wall seconds while
                   no command comes, so late subscribers still get it (same stamp: consumers
                   skip stamps they have seen).
lockstep: false -- free-running on a wall timer at the model's sample rate, zero-order holding
                   the last command. Like a robot's hardware interface, joint state k then
                   reports in ``effort`` the torque applied from t_k (the held command), so a
                   consumer pairs state k with its own effort (see
                   frf_ident.app.excitation_torque).

Run: ``python -m frf_ident.nodes.plant_node --ros-args -p model:=config/model_3axis.yaml``.
"""
from __future__ import annotations

import time
from typing import Any, Optional, Sequence

from frf_ident import middleware as mw
from frf_ident.nodes import common as c
import numpy as np


class PlantNode:
    def __init__(self, node: Any) -> None:
        from frf_ident.core.simulation.plant import FlexibleJointPlant
        from frf_ident.io.model_file import load_model, load_plant
        self.node = node
        model_path = c.param(node, 'model', '')
        plant_spec = c.param(node, 'plant', '')
        self.lockstep = bool(c.param(node, 'lockstep', c.LOCKSTEP))
        self.idle_republish_s = float(c.param(node, 'idle_republish_s', 0.2))
        self.clock_every = max(1, int(c.param(node, 'clock_every', 10)))
        self.velocity_control = bool(c.param(node, 'velocity_control', False))
        if self.velocity_control and not self.lockstep:
            raise c.Refused('velocity_control: true (the PI inside the plant) needs lockstep: '
                            'true; free-running, start controller_node')
        t = c.topics(node, ('joint_states_topic', 'effort_topic', 'clock_topic',
                            'velocity_topic'))
        model, _robot, ctrl = load_model(model_path or None)
        self.plant = load_plant(plant_spec or None, model)
        self.plant.reset()
        self.n = len(self.plant.joint_names)
        self.dt_ns = int(round(float(self.plant.dt) * 1e9))
        # the first measurement, exactly as the offline ClosedLoop takes it
        if isinstance(self.plant, FlexibleJointPlant):
            q0, v0 = self.plant.state[0].copy(), np.zeros(self.n)
            e0 = self.plant.equilibrium_torque()
        else:
            hold = np.asarray(ctrl.integral, dtype=float)
            q0, v0, e0 = (np.asarray(a, float) for a in self.plant.step(hold))
        if isinstance(self.plant, FlexibleJointPlant):   # compile/load the kernels now
            load_plant(plant_spec or None, model).step(e0)
        self.k = 0
        JointState, Clock = mw.msg('sensor_msgs/msg/JointState'), mw.msg('rosgraph_msgs/msg/Clock')
        self.js = JointState(name=list(self.plant.joint_names), position=q0.tolist(),
                             velocity=v0.tolist(), effort=e0.tolist())
        self.clock = Clock()
        self.hold = e0.copy()
        self.js_pub = node.create_publisher(JointState, t['joint_states_topic'],
                                            mw.qos_default(c.DEEP))
        self.clock_pub = node.create_publisher(Clock, t['clock_topic'], mw.qos_clock())
        F64 = mw.msg('std_msgs/msg/Float64MultiArray')
        if self.velocity_control:
            # the PI runs here, as ros2_control runs its controllers beside the hardware: no
            # plant -> controller -> plant round trip per sample; the torque still goes out
            # on the effort topic (for the recorder) before the joint state it produced
            from frf_ident.nodes.controller_node import VelocityLoop
            self.loop = VelocityLoop(node, model_path)
            self.y = v0.copy()
            self.cmd = F64(data=[0.0] * self.n)
            self.effort_pub = node.create_publisher(F64, t['effort_topic'],
                                                    mw.qos_default(c.DEEP))
            node.create_subscription(F64, t['velocity_topic'], self._on_reference,
                                     mw.qos_default(c.DEEP))
        else:
            node.create_subscription(F64, t['effort_topic'], self._on_command,
                                     c.control_qos(self.lockstep))
        self.last_pub = 0.0
        if self.lockstep:
            self._publish()
        else:   # the node clock is wall time here (the plant is the clock source)
            self.q, self.v = q0, v0
            node.create_timer(float(self.plant.dt), self._tick)

    def _publish(self) -> None:
        ns = self.k * self.dt_ns
        if self.k % self.clock_every == 0:
            st = self.clock.clock
            st.sec, st.nanosec = divmod(ns, 1_000_000_000)
            self.clock_pub.publish(self.clock)
        c.set_stamp(self.js, ns)
        self.js_pub.publish(self.js)
        self.last_pub = time.monotonic()

    def _advance(self, torque: Any) -> None:
        q, v, e = self.plant.step(torque)
        self.k += 1
        if self.velocity_control:
            self.y = np.asarray(v, dtype=float)
        js = self.js
        js.position = q.tolist() if hasattr(q, 'tolist') else list(q)
        js.velocity = v.tolist() if hasattr(v, 'tolist') else list(v)
        js.effort = e.tolist() if hasattr(e, 'tolist') else list(e)
        self._publish()

    def _on_reference(self, msg: Any) -> None:
        """Lockstep with the PI inside: one sample per velocity reference."""
        u = self.loop.torque(self.loop.reference(msg.data), self.y)
        self.cmd.data = u.tolist()
        self.effort_pub.publish(self.cmd)
        self._advance(u)

    def _on_command(self, msg: Any) -> None:
        data = msg.data
        if len(data) != self.n:
            self.node.get_logger().error(f'effort command has {len(data)} values for {self.n} '
                                         f'joints; ignored')
            return
        if self.lockstep:
            self._advance(np.asarray(data, dtype=float))
        else:
            self.hold[:] = data

    def _tick(self) -> None:
        """Free-running sample k: publish (q_k, v_k, torque applied from t_k), then step."""
        q, v, e = self.plant.step(self.hold)
        js = self.js
        js.position = np.asarray(self.q, float).tolist()
        js.velocity = np.asarray(self.v, float).tolist()
        js.effort = np.asarray(e, float).tolist()
        self._publish()
        self.q, self.v = q, v
        self.k += 1

    def idle(self) -> None:
        if self.lockstep and time.monotonic() - self.last_pub > self.idle_republish_s:
            self._publish()

    def spin(self, stop: Any) -> None:
        """Spin until ``stop`` is set, re-sending the joint state while idle (lockstep)."""
        self.node.get_logger().info(f'plant {type(self.plant).__name__} '
                                    f'{self.plant.joint_names}, dt {self.plant.dt} s, '
                                    f'lockstep={self.lockstep}')
        if not self.lockstep:
            mw.spin(self.node, stop)
            return
        while not stop.is_set():
            mw.spin_once(self.node, 0.05)
            self.idle()


def main(argv: Optional[Sequence[str]] = None) -> int:
    """``ros2 run frf_ident plant_node``; the plant is the clock source (no sim time)."""
    return c.run_node('plant_node', PlantNode, argv, use_sim_time=False)


if __name__ == '__main__':
    raise SystemExit(main())
