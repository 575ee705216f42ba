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
Topic endpoints of the Cyclone DDS backend: :class:`Publisher` and :class:`Subscription`.

Topics are ``rt/<name>`` with the ROS type's ``typehash=`` USER_DATA; a subscription's
callbacks run in the thread that spins its node.
"""

from typing import Any, Callable

from cyclonedds.core import ReadCondition
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from frf_ident.middleware import ros_types
from frf_ident.middleware.dds_wire import (ANY_SAMPLE, dds_qos, delete_entity, format_user_data,
                                           resolve_name, TAKE_BATCH)
from frf_ident.middleware.qos import QosSpec

__all__ = ['Publisher', 'Subscription']


class Publisher:
    def __init__(self, node: Any, msg_cls: type, topic: str, qos: QosSpec) -> None:
        ros_type = ros_types.ros_type_name(msg_cls)
        self.topic_name = resolve_name(topic, node.get_name(), node.get_namespace())
        self.msg_type = msg_cls
        self._writer = DataWriter(
            node._ctx.participant, node._ctx.topic('rt' + self.topic_name, msg_cls),
            dds_qos(qos, format_user_data(typehash=ros_types.TYPE_HASHES[ros_type]), writer=True))
        self._write = self._writer.write

    def publish(self, msg: Any) -> None:
        self._write(msg)

    def get_subscription_count(self) -> int:
        return len(self._writer.get_matched_subscriptions())

    def _destroy(self) -> None:
        delete_entity(self._writer)


class Subscription:
    def __init__(self, node: Any, msg_cls: type, topic: str,
                 callback: Callable[[Any], None], qos: QosSpec) -> None:
        ros_type = ros_types.ros_type_name(msg_cls)
        self.topic_name = resolve_name(topic, node.get_name(), node.get_namespace())
        self.msg_type = msg_cls
        self.callback = callback
        self._reader = DataReader(
            node._ctx.participant, node._ctx.topic('rt' + self.topic_name, msg_cls),
            dds_qos(qos, format_user_data(typehash=ros_types.TYPE_HASHES[ros_type]), writer=False))
        self._condition = ReadCondition(self._reader, ANY_SAMPLE)

    def get_publisher_count(self) -> int:
        return len(self._reader.get_matched_publications())

    def _dispatch(self) -> None:
        for sample in self._reader.take(TAKE_BATCH, condition=self._condition):
            if sample.sample_info.valid_data:
                self.callback(sample)

    def _destroy(self) -> None:
        delete_entity(self._condition)
        delete_entity(self._reader)
