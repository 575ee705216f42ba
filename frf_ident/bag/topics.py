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
"""Topic names, message types and QoS profiles of frf_ident bags (docs/CONTRACT.md §3)."""
from __future__ import annotations

from dataclasses import dataclass

from rosbags.interfaces import (Qos, QosDurability, QosHistory, QosLiveliness, QosReliability,
                                QosTime)

JOINT_STATE = 'sensor_msgs/msg/JointState'
FLOAT64_ARRAY = 'std_msgs/msg/Float64MultiArray'
STRING = 'std_msgs/msg/String'

#: rmw's "infinite" duration as rosbag2 writes it into metadata.yaml.
_INFINITE = QosTime(9223372036, 854775807)


def make_qos(*, depth: int = 10, reliable: bool = True, transient_local: bool = False) -> Qos:
    """Return a rosbags ``Qos`` with KEEP_LAST(depth) and infinite deadline/lifespan/lease."""
    return Qos(
        history=QosHistory.KEEP_LAST,
        depth=depth,
        reliability=QosReliability.RELIABLE if reliable else QosReliability.BEST_EFFORT,
        durability=QosDurability.TRANSIENT_LOCAL if transient_local else QosDurability.VOLATILE,
        deadline=_INFINITE,
        lifespan=_INFINITE,
        liveliness=QosLiveliness.AUTOMATIC,
        liveliness_lease_duration=_INFINITE,
        avoid_ros_namespace_conventions=False,
    )


#: reliable, volatile, depth 10 (ROS 2 default; matches ros2_control SystemDefaults readers).
QOS_DEFAULT = make_qos()
#: reliable, transient-local, depth 10: late joiners still get the experiment descriptors.
QOS_LATCHED = make_qos(transient_local=True)


@dataclass(frozen=True)
class BagTopics:
    """Topic names used in a bag; every name is configurable (docs/CONTRACT.md §3)."""

    joint_states: str = '/joint_states'
    velocity_commands: str = '/velocity_controller/commands'
    effort_commands: str = '/effort_controller/commands'
    excitation: str = '/frf/excitation'
    experiment: str = '/frf/experiment'

    def expected_types(self) -> dict[str, str]:
        """Topic name -> the message type frf_ident expects on it."""
        return {
            self.joint_states: JOINT_STATE,
            self.velocity_commands: FLOAT64_ARRAY,
            self.effort_commands: FLOAT64_ARRAY,
            self.excitation: JOINT_STATE,
            self.experiment: STRING,
        }

    def qos(self, topic: str) -> Qos:
        """Offered QoS profile recorded for ``topic``."""
        return QOS_LATCHED if topic == self.experiment else QOS_DEFAULT
