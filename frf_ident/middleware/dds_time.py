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
Time on the Cyclone DDS backend: :class:`RosTime`, the node :class:`Clock` and :class:`Timer`.

The clock is system time, or the last ``/clock`` value with use_sim_time; a timer follows rcl's
semantics (missed periods are skipped, a clock jumping backwards re-arms it).
"""

import time
from typing import Any, Callable, Optional

from frf_ident.middleware import ros_types

__all__ = ['Clock', 'RosTime', 'Timer']


class RosTime:
    """A point in ROS time (rclpy.time.Time subset): ``.nanoseconds`` and ``.to_msg()``."""

    __slots__ = ('nanoseconds',)

    def __init__(self, nanoseconds: int = 0) -> None:
        self.nanoseconds = int(nanoseconds)

    def to_msg(self) -> ros_types.Time:
        sec, nanosec = divmod(self.nanoseconds, 1_000_000_000)
        return ros_types.Time(sec=sec, nanosec=nanosec)

    def seconds_nanoseconds(self) -> tuple[int, int]:
        return divmod(self.nanoseconds, 1_000_000_000)

    def __repr__(self) -> str:
        return f'RosTime(nanoseconds={self.nanoseconds})'


class Clock:
    """The node clock: system time, or the last ``/clock`` value with use_sim_time (0 before)."""

    def __init__(self, use_sim_time: bool) -> None:
        self.use_sim_time = use_sim_time
        self._sim_ns = 0

    def now_ns(self) -> int:
        return self._sim_ns if self.use_sim_time else time.time_ns()

    def now(self) -> RosTime:
        return RosTime(self.now_ns())

    def _set_sim(self, msg: ros_types.Clock) -> None:
        self._sim_ns = msg.clock.sec * 1_000_000_000 + msg.clock.nanosec


class Timer:
    """A periodic timer on the node clock (rcl semantics: missed periods are skipped)."""

    def __init__(self, node: Any, period_sec: float, callback: Callable[[], None]) -> None:
        if not period_sec > 0:
            raise ValueError(f'timer period must be > 0 s, got {period_sec=}')
        self.timer_period_ns = int(round(period_sec * 1e9))
        self.callback = callback
        self._clock = node._clock
        self._next_ns = self._clock.now_ns() + self.timer_period_ns
        self._canceled = False

    def cancel(self) -> None:
        self._canceled = True

    def reset(self) -> None:
        self._canceled = False
        self._next_ns = self._clock.now_ns() + self.timer_period_ns

    def is_canceled(self) -> bool:
        return self._canceled

    def time_until_next_call(self) -> Optional[int]:
        """Nanoseconds until the next call (None when canceled)."""
        return None if self._canceled else self._next_ns - self._clock.now_ns()

    def _due(self, now_ns: int) -> bool:
        if self._canceled:
            return False
        period = self.timer_period_ns
        if self._next_ns - now_ns > period:  # the clock jumped backwards (sim reset)
            self._next_ns = now_ns + period
            return False
        if now_ns < self._next_ns:
            return False
        self._next_ns += ((now_ns - self._next_ns) // period + 1) * period
        return True
