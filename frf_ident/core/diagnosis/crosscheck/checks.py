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
The outcome of the cross-checks of one diagnosis, as one typed record.

:class:`CrossChecks` gathers what each check of this package found; it is written into
report.json's ``metrics`` after the route's own metrics, each under its key and only where
the check ran (docs/CONTRACT.md §7).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .generalisation import TermsOnOthers
from .kinematic_gravity import KinematicGravityFit
from .least_squares import LeastSquaresCheck
from .spread import SpreadCheck
from .validation import RecordCheck

__all__ = ['CrossChecks']


@dataclass
class CrossChecks:
    """What the cross-checks found (None or empty: the check did not run)."""

    #: ``--urdf``: the gravity of the kinematics, fitted jointly over the axes
    kinematic_gravity: KinematicGravityFit | None = None
    #: ``--validate``: per axis its position-dependent terms on the other records
    position_terms_on_validate: dict[str, TermsOnOthers] = field(default_factory=dict)
    #: time series: the standard errors against the spread between records or halves
    standard_errors_across: SpreadCheck | None = None
    #: the least-squares baseline every report is judged against
    least_squares: LeastSquaresCheck | None = None
    #: ``--validate``: both model files on each other record
    validation_records: list[RecordCheck] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Return the checks' part of report.json ``metrics``, in the report's key order."""
        out: dict[str, Any] = {}
        if self.kinematic_gravity is not None:
            out['kinematic_gravity'] = self.kinematic_gravity.to_dict()
        if self.position_terms_on_validate:
            out['position_terms_on_validate'] = {
                ax: v.to_dict() for ax, v in self.position_terms_on_validate.items()}
        if self.standard_errors_across is not None:
            out['standard_errors_across'] = self.standard_errors_across.to_dict()
        if self.least_squares is not None:
            out['least_squares'] = self.least_squares.to_dict()
        if self.validation_records:
            out['validation_records'] = [v.to_dict() for v in self.validation_records]
        return out
