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
What locks an unexplained spectral line: the position, or the time (a typed report entry).

A line the residual keeps above the analysis band has one of two kinds of cause. Locked to
position, it moves with speed: cogging, torque ripple, gear mesh, a screw's pitch (f = kappa
|v| at kappa cycles per unit of travel). Locked to time, it stays put whatever the speed:
the mains and its harmonics, PWM, a structural mode. :class:`LineCause` is the verdict with
its evidence, one :class:`LineAtSpeed` per steady speed of the record
(:mod:`.timeseries.line_lock` finds them); :func:`mains_multiple` labels a frequency that is
a multiple of a mains frequency.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Any

__all__ = ['LineAtSpeed', 'LineCause', 'mains_multiple', 'MAINS_HZ']

#: the mains frequencies of the world's grids [Hz]
MAINS_HZ = (50.0, 60.0)


def mains_multiple(f_hz: float, tolerance_hz: float) -> str | None:
    """
    Return 'k x 50 Hz' (or 60 Hz) when ``f_hz`` is within ``tolerance_hz`` of a multiple.

    Examples
    --------
    >>> mains_multiple(100.2, 0.5), mains_multiple(33.0, 0.5), mains_multiple(300.0, 0.5)
    ('2 x 50 Hz', None, '6 x 50 Hz or 5 x 60 Hz')

    """
    hits = [f'{round(f_hz / m)} x {m:g} Hz' for m in MAINS_HZ
            if round(f_hz / m) >= 1 and abs(f_hz - m * round(f_hz / m)) <= tolerance_hz]
    return ' or '.join(hits) or None


@dataclass(frozen=True)
class LineAtSpeed:
    """The residual at one steady speed: at the frequency each hypothesis predicts there."""

    #: the steady speed [position unit/s] and the seconds the record holds it
    speed: float
    duration_s: float
    #: where a position-locked line would be at this speed [Hz], and its PSD over the floor
    position_hz: float
    position_over_floor: float
    #: the PSD over the floor at the line's own frequency (a time-locked line stays there)
    time_over_floor: float
    #: PSD over floor that noise alone exceeds there (false-alarm LINE_LOCK_FALSE_ALARM)
    threshold: float

    def to_dict(self) -> dict[str, Any]:
        """Return the report's entry."""
        return {'speed': float(f'{self.speed:.4g}'), 'duration_s': round(self.duration_s, 2),
                'position_hz': round(self.position_hz, 2),
                'position_over_floor': round(self.position_over_floor, 1),
                'time_over_floor': round(self.time_over_floor, 1),
                'threshold': round(self.threshold, 1)}


@dataclass(frozen=True)
class LineCause:
    """Whether a line is locked to position or to time, and the evidence."""

    #: 'position', 'time' or 'undetermined'
    locked_to: str
    #: the line's frequency [Hz] (the peak of the whole record's scan)
    frequency_hz: float
    #: one sentence: why
    reason: str
    #: position-locked: cycles per unit of position (kappa) at the speed it is strongest
    cycles_per_unit: float | None = None
    #: 'k x 50 Hz' where the frequency is a mains multiple (whatever locks it)
    mains_multiple: str | None = None
    #: per steady speed the two hypotheses' evidence
    speeds: list[LineAtSpeed] = field(default_factory=list)

    @property
    def spatial_frequency(self) -> float | None:
        """Return the model file's ``spatial_frequency`` (sin(s q)) of a position-locked line."""
        return None if self.cycles_per_unit is None else 2 * math.pi * self.cycles_per_unit

    def describe(self) -> str:
        """Return the line people read."""
        head = {'position': 'locked to position (moves with speed: cogging, torque ripple, '
                            'gear mesh or a screw pitch)',
                'time': 'locked to time (stays put at every speed: the mains, PWM or a '
                        'structural mode)'}.get(
                    self.locked_to, 'not determined')
        mains = ''
        if self.mains_multiple:
            mains = (f'; at a mains multiple ({self.mains_multiple})'
                     + (', but it moves with speed: not the mains'
                        if self.locked_to == 'position' else ''))
        return f'{head}: {self.reason}{mains}'

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``cause`` entry."""
        out: dict[str, Any] = {'locked_to': self.locked_to,
                               'frequency_hz': round(self.frequency_hz, 2),
                               'reason': self.reason}
        if self.cycles_per_unit is not None:
            out['cycles_per_unit'] = float(f'{self.cycles_per_unit:.4g}')
            out['spatial_frequency'] = float(f'{self.spatial_frequency:.4g}')
        if self.mains_multiple is not None:
            out['mains_multiple'] = self.mains_multiple
        out['speeds'] = [s.to_dict() for s in self.speeds]
        return out
