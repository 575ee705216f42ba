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
Judge the nominal and the extended model on other records of the same robot.

``--validate`` records are not fitted on: both model files are simulated on each record's
experiments when it has them (:class:`..experiments.evaluator.Evaluator`), else they predict
its torque from its motion (:func:`..prediction.predict_metrics`). Where a record drives an
axis beyond the positions the fit saw, a position-dependent term (gravity, ripple) is
extrapolated there: :func:`beyond_fitted_range` says how far, in degrees.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.progress import Progress
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.controller import PIVelocity
import numpy as np

from ..common import has_experiments, Simulator
from ..experiments.evaluator import Evaluator
from ..prediction import predict_metrics
from ..records import Scores
from ..result import DiagnosisResult
from ..thresholds import RANGE_TOLERANCE_DEG

__all__ = ['beyond_fitted_range', 'on_other_records', 'RangeExcursion', 'RecordCheck',
           'validate_on']


@dataclass(frozen=True)
class RangeExcursion:
    """How far another record drives an axis beyond the positions the fit saw [deg]."""

    fitted_deg: list[float]
    reached_deg: list[float]
    #: the larger excursion below or above
    beyond_deg: float

    def to_dict(self) -> dict[str, Any]:
        """Return the report's entry."""
        return {'fitted_deg': list(self.fitted_deg), 'reached_deg': list(self.reached_deg),
                'beyond_deg': self.beyond_deg}

    def describe(self, axis: str) -> str:
        """Return it as a phrase for people."""
        return (f'{axis} reaches {self.reached_deg[0]:.1f}..{self.reached_deg[1]:.1f} deg, '
                f'fitted {self.fitted_deg[0]:.1f}..{self.fitted_deg[1]:.1f} deg '
                f'({self.beyond_deg:.1f} deg beyond)')


@dataclass(frozen=True)
class RecordCheck:
    """Both model files on one other record (report ``metrics.validation_records``)."""

    record: str
    #: the nominal model (report.json calls it ``baseline``) and the extended one
    baseline: Scores
    extended: Scores
    #: per axis the excursion beyond the fitted range (empty: none)
    beyond_fitted_range: dict[str, RangeExcursion] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """Return the report's entry."""
        return {'record': self.record, 'baseline': self.baseline.to_dict(),
                'extended': self.extended.to_dict(),
                'beyond_fitted_range': {ax: r.to_dict()
                                        for ax, r in self.beyond_fitted_range.items()}}


def validate_on(name: str, other: Recording, robot: RobotParams, ext: RobotParams,
                ctrl: PIVelocity, simulator: Simulator | None = None) -> RecordCheck:
    """
    Return the scores of the nominal and the extended model on another record (no refit).

    Simulation of its experiments when it has them (by ``simulator``, default our plant),
    else the time-series torque prediction.
    """
    robot = replace(robot, sample_rate=other.fs)
    ext = replace(ext, sample_rate=other.fs)
    if has_experiments(other):
        ev = Evaluator(other, ctrl, simulator=simulator)
        try:
            return RecordCheck(name, ev.metrics(robot), ev.metrics(ext))
        finally:
            ev.close()
    return RecordCheck(name, predict_metrics(other, robot).scores,
                       predict_metrics(other, ext).scores)


def on_other_records(res: DiagnosisResult, rec: Recording, others: list[tuple[str, Recording]],
                     robot: RobotParams, ctrl: PIVelocity, progress: Progress, *,
                     name: str = 'the record', simulator: Simulator | None = None
                     ) -> list[RecordCheck]:
    """
    Return :func:`validate_on` of every other record, with its excursion beyond the fit.

    A record that leaves the fitted range gets one warning line (``name``: the fitted
    record's, for it).
    """
    out = []
    for other_name, other in others:
        far = beyond_fitted_range(rec, res.fit_rows, other, robot.joint_names)
        out.append(replace(validate_on(other_name, other, robot, res.extended, ctrl, simulator),
                           beyond_fitted_range=far))
        if far:
            progress(f'warning: --validate {other_name} leaves the configuration range fitted '
                     f'on {name}: ' + '; '.join(r.describe(ax) for ax, r in far.items())
                     + ': position-dependent terms are extrapolated there')
    return out


def beyond_fitted_range(fit: Recording, fit_rows: np.ndarray, other: Recording,
                        names: list[str]) -> dict[str, RangeExcursion]:
    """
    Return per axis how far ``other`` leaves the position range of the fit rows [deg].

    Parameters
    ----------
    fit : Recording
        The record the diagnosis fitted on.
    fit_rows : ndarray of bool, shape (N-1,)
        Its fit rows (between samples).
    other : Recording
        Another record of the same robot.
    names : list of str
        The axes' names in the report.

    Returns
    -------
    dict
        ``{axis: RangeExcursion}`` for every axis that ``other`` leaves by more than
        RANGE_TOLERANCE_DEG; empty when it stays inside.

    """
    q = 0.5 * (fit.position[1:] + fit.position[:-1])[fit_rows]
    out = {}
    if not q.size:
        return out
    lo, hi = np.nanmin(q, axis=0), np.nanmax(q, axis=0)
    olo, ohi = np.nanmin(other.position, axis=0), np.nanmax(other.position, axis=0)
    for i, name in enumerate(names):
        d = math.degrees(max(lo[i] - olo[i], ohi[i] - hi[i], 0.0))
        if d > RANGE_TOLERANCE_DEG:
            out[name] = RangeExcursion(
                [round(math.degrees(lo[i]), 2), round(math.degrees(hi[i]), 2)],
                [round(math.degrees(olo[i]), 2), round(math.degrees(ohi[i]), 2)], round(d, 2))
    return out
