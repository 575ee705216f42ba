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
Say per axis and held-out record whether the extended model beats, ties or loses.

The extended model against the least-squares baseline on one axis of one held-out set: the
ratio of their ``time_nrmse``; within LS_BASELINE_MARGIN either way (on a log scale) it
ties, below it beats, above it loses (docs/diagnosis/crosschecks.md, "The baseline").
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..thresholds import LS_BASELINE_MARGIN

__all__ = ['BaselineVerdict', 'verdict_of']


def verdict_of(extended: float, least_squares: float) -> str:
    """
    Return 'beats', 'ties' or 'loses': the extended model against the baseline.

    Parameters
    ----------
    extended, least_squares : float
        The two models' held-out ``time_nrmse`` on one axis of one record.

    Returns
    -------
    str
        'loses' above (1 + LS_BASELINE_MARGIN) times the baseline, 'beats' below it divided
        by the same factor, else 'ties'.

    Examples
    --------
    >>> verdict_of(0.0323, 0.0320), verdict_of(0.10, 0.29), verdict_of(0.35, 0.29)
    ('ties', 'beats', 'loses')

    """
    if not extended <= (1.0 + LS_BASELINE_MARGIN) * least_squares:
        return 'loses'
    if extended * (1.0 + LS_BASELINE_MARGIN) < least_squares:
        return 'beats'
    return 'ties'


@dataclass(frozen=True)
class BaselineVerdict:
    """One axis on one held-out set: the two models' ``time_nrmse`` and the verdict."""

    #: 'held out' (the diagnosis' own held-out rows) or the other record's path
    record: str
    axis: str
    extended: float
    least_squares: float

    @property
    def verdict(self) -> str:
        """Return 'beats', 'ties' or 'loses' (:func:`verdict_of`)."""
        return verdict_of(self.extended, self.least_squares)

    def sentence(self) -> str:
        """Return the line people read, with the numbers."""
        verb = {'loses': 'loses to'}.get(self.verdict, self.verdict)
        return (f'{self.axis} on {self.record}: the extended model {verb} the baseline '
                f'({self.extended:.3f} against {self.least_squares:.3f})')

    def to_dict(self) -> dict[str, Any]:
        """Return the report's entry."""
        return {'record': self.record, 'axis': self.axis, 'verdict': self.verdict,
                'extended': self.extended, 'least_squares': self.least_squares}
