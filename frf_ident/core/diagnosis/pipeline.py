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
Diagnose a record against a nominal model: the route, then the cross-checks.

:func:`diagnose` is the whole diagnosis as a short pipeline of named stages: the route the
record's evidence calls for (identification experiments: :mod:`.experiments`, anything else:
:mod:`.timeseries`), then the checks against what the route did not fit on
(:mod:`.crosscheck`): the gravity of the robot's kinematics, position-dependent terms on the
other records, standard errors across records (and the values they leave undetermined),
the least-squares baseline and both model files on every other record; last the sensor the
record shows and the nominal model's own simulation does not is named (:mod:`.sensor`; the
experiments route already read its effects against it). Its :class:`Diagnosis` is what
``frf-ident diagnose`` writes (report.json from :meth:`Diagnosis.report`, docs/CONTRACT.md §7)
and what the console and the HTML report read.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Any, Sequence

from frf_ident.core.model.params import RobotParams
from frf_ident.core.progress import Progress, sink
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.controller import PIVelocity

from .common import has_experiments, Simulator
from .crosscheck.checks import CrossChecks
from .crosscheck.generalisation import position_terms_on_others
from .crosscheck.kinematic_gravity import GravityBasis, kinematic_gravity
from .crosscheck.least_squares import against_least_squares
from .crosscheck.spread import standard_errors_across
from .crosscheck.validation import on_other_records
from .determination import on_unexplained_axes, undetermined_effects
from .experiments.pipeline import diagnose_experiments
from .result import DiagnosisResult
from .sensor import model_sensor, name_sensor
from .thresholds import SIM_JOBS
from .timeseries.pipeline import diagnose_timeseries

__all__ = ['diagnose', 'Diagnosis', 'strict_json']


@dataclass
class Diagnosis:
    """One record diagnosed: the route's result after the cross-checks, and the checks."""

    result: DiagnosisResult
    checks: CrossChecks
    #: the diagnosed record, its joints matched to the model's axes
    recording: Recording
    #: the other records it was checked on (name, record)
    others: list[tuple[str, Recording]] = field(default_factory=list)

    @property
    def mode(self) -> str:
        """Return the route: 'experiments' or 'timeseries'."""
        return self.result.mode

    def report(self, extended_model: str = 'extended_model.yaml') -> dict[str, Any]:
        """
        Return the content of report.json (docs/CONTRACT.md §7), strict JSON.

        Parameters
        ----------
        extended_model : str
            The file name the extended model is written under, beside report.json.

        """
        res = self.result
        out: dict[str, Any] = {
            'effects': [e.to_dict() for e in res.effects],
            'metrics': {**res.metrics.to_dict(), **self.checks.to_dict()},
            'unexplained': [u.to_dict() for u in res.unexplained],
            'rejected': [r.to_dict() for r in res.rejected],
            'extended_model': extended_model}
        if res.discretisation is not None:
            out['discretisation'] = res.discretisation.to_dict()
        if res.band is not None:
            out['analysis_band'] = res.band.to_dict()
        if self.recording.gaps:
            out['gaps'] = [list(g) for g in self.recording.gaps]
        return strict_json(out)


def diagnose(rec: Recording, robot: RobotParams, ctrl: PIVelocity, *,
             others: Sequence[tuple[str, Recording]] = (), gravity: GravityBasis | None = None,
             jobs: int = SIM_JOBS, fd_fit: bool = True, name: str = 'the record',
             progress: Progress | None = None, simulator: Simulator | None = None
             ) -> Diagnosis:
    """
    Diagnose ``rec`` against the nominal ``robot`` and check the result.

    Parameters
    ----------
    rec : Recording
        The record to fit on, its joints the model's axes.
    robot : RobotParams
        The nominal model, at the record's sample rate.
    ctrl : PIVelocity
        The velocity controller the record's experiments ran through.
    others : sequence of (str, Recording)
        Other records of the same robot (name, record; the same joints): both model files are
        judged on each, and a gravity or ripple term that does not generalise to them is
        dropped (time series).
    gravity : GravityBasis, optional
        The robot's kinematics: the time-series route fits the gravity they imply.
    jobs : int
        Processes that simulate independent candidate models at once (experiments route;
        1: one after the other, the same result).
    fd_fit : bool
        Experiments route: stage 0, the frequency-domain physical fit (default); False: the
        path without it (for the before/after benchmark).
    name : str
        The record's name in the lines people read.
    progress : callable, optional
        Gets one line per step people read; the stages log their trace to
        ``logging.getLogger('frf_ident.core.diagnosis.*')``.
    simulator : Simulator, optional
        What simulates the candidate models on the record's and the other records'
        experiments (:class:`.common.Simulator`); default our plant. An adapter injects
        another engine here (MuJoCo for a model naming an MJCF).

    Returns
    -------
    Diagnosis

    """
    progress = sink(progress)
    others = list(others)
    res = route(rec, robot, ctrl, jobs=jobs, fd_fit=fd_fit, progress=progress,
                simulator=simulator)
    checks = CrossChecks()
    if gravity is not None:
        res, checks.kinematic_gravity = kinematic_gravity(res, rec, robot, gravity, progress)
    res, checks.position_terms_on_validate = position_terms_on_others(res, rec, robot, others,
                                                                      progress)
    res, checks.standard_errors_across = standard_errors_across(res, rec, others, robot,
                                                                progress)
    res, checks.least_squares = against_least_squares(res, rec, others, robot, progress)
    res = undetermined(res)
    checks.validation_records = on_other_records(res, rec, others, robot, ctrl, progress,
                                                 name=name, simulator=simulator)
    shown = model_sensor(rec, robot, ctrl, simulator)
    return Diagnosis(name_sensor(res, rec, robot, shown), checks, rec, others)


def route(rec: Recording, robot: RobotParams, ctrl: PIVelocity, *, jobs: int, fd_fit: bool,
          progress: Progress, simulator: Simulator | None = None) -> DiagnosisResult:
    """Run the route the record's evidence calls for and return its result."""
    if has_experiments(rec):
        progress('identification experiments found: FRF and closed-loop simulation evidence')
        return diagnose_experiments(rec, robot, ctrl, jobs=jobs, fd_fit=fd_fit,
                                    simulator=simulator)
    progress('no identification experiments: time-series (inverse-dynamics) evidence')
    return diagnose_timeseries(rec, robot)


def undetermined(res: DiagnosisResult) -> DiagnosisResult:
    """
    Label the values the record does not determine; rank again.

    On either route, after the standard errors were checked against the spread between
    records: a value whose standard error exceeds NOT_DETERMINED_SHARE of it
    (:func:`.determination.undetermined_effects`), and the values on an axis left unexplained
    (:func:`.determination.on_unexplained_axes`); an effect with such a value scores 0 and
    goes after the effects found. The experiments route labelled its own already (the
    joint refits that may settle a value are simulations, :mod:`.experiments.settle`).
    """
    effects = on_unexplained_axes(undetermined_effects(res.effects), res.unexplained)
    return replace(res, effects=sorted(effects, key=lambda e: -e.score))


def strict_json(x: Any) -> Any:
    """Return ``x`` (dicts, lists, numbers) as strict JSON: NaN becomes None."""
    if isinstance(x, dict):
        return {k: strict_json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [strict_json(v) for v in x]
    if isinstance(x, float) and math.isnan(x):
        return None
    return x
