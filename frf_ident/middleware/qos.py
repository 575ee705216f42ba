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
Backend-neutral QoS profiles (ROS2_CONVENTIONS.md section 1.4).

Node code passes a :class:`QosSpec` (or a plain ``int`` depth, as rclpy allows) to
``create_publisher`` / ``create_subscription``; each backend converts it to its native QoS.
Unset policies (deadline, lifespan, lease duration) are infinite and liveliness is automatic,
exactly as the ROS 2 defaults.
"""

from dataclasses import dataclass


@dataclass(frozen=True)
class QosSpec:
    """The QoS policies this project uses: keep-last history, reliability and durability."""

    depth: int = 10
    reliable: bool = True
    transient_local: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.depth, int) or self.depth < 1:
            raise ValueError(f'QoS history depth must be a positive int, got {self.depth=}')


def qos_default(depth: int = 10) -> QosSpec:
    """ROS default (``create_publisher(T, topic, 10)``): keep-last, reliable, volatile."""
    return QosSpec(depth=depth, reliable=True, transient_local=False)


def qos_transient_local(depth: int = 1) -> QosSpec:
    """Latched topic: keep-last, reliable, transient-local (late joiners get the last)."""
    return QosSpec(depth=depth, reliable=True, transient_local=True)


def qos_sensor_data() -> QosSpec:
    """``rmw_qos_profile_sensor_data``: keep-last 5, best-effort, volatile."""
    return QosSpec(depth=5, reliable=False, transient_local=False)


def qos_clock() -> QosSpec:
    """``/clock`` as rclpy's TimeSource and rclcpp's ClockQoS use it: keep-last 1, best-effort."""
    return QosSpec(depth=1, reliable=False, transient_local=False)


def as_qos_spec(qos: 'QosSpec | int') -> QosSpec:
    """Accept a :class:`QosSpec` or an ``int`` depth (as rclpy: ``QoSProfile(depth=n)``)."""
    if isinstance(qos, QosSpec):
        return qos
    if isinstance(qos, int) and not isinstance(qos, bool):
        return qos_default(qos)
    raise TypeError(f'expected a QosSpec or an int history depth, got {qos=}')
