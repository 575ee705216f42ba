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
Judge the extended model against the least-squares baseline, and apply the rule.

The baseline (:mod:`.baseline`) is fitted on the diagnosis' fit rows and compared on its
held-out rows and on every other record. Time-series route: an axis whose extended model is
not below the baseline on every held-out set is refitted with the baseline's terms in the
model (inertia, viscous and Coulomb friction, a constant load); where that ties or beats the
baseline the axis takes it, else its effects are rejected (the nominal axis). The held-out
metrics are then taken again. Experiments route: the verdict is reported, nothing dropped
(not calibrated against the simulation sweep yet).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.progress import Progress
from frf_ident.core.recording import Recording

from .baseline import (axes_not_beating, BASELINE_GROUPS, fit_least_squares, held_out_comparison,
                       HeldOutSet, with_axes_of, without_axes)
from ..prediction import predict_metrics
from ..result import DiagnosisResult
from ..timeseries.pipeline import diagnose_timeseries

__all__ = ['against_least_squares', 'LeastSquaresCheck']


@dataclass
class LeastSquaresCheck:
    """The least-squares baseline the report is judged against (report.json ``least_squares``)."""

    #: the baseline's model and the metric, one sentence each
    model: str
    metric: str
    #: {axis: {'inertia', 'viscous', 'coulomb', 'offset'}} in SI units
    parameters: dict[str, dict[str, float]]
    #: the three models on each held-out set, after the rule
    held_out: list[HeldOutSet]
    #: the same with the extended model as the diagnosis fitted it, before the rule
    held_out_as_fitted: list[HeldOutSet]
    #: {axis: one sentence}: beats (or ties) the baseline, or what happened to its effects
    extended_vs_baseline: dict[str, str]

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``metrics.least_squares`` entry."""
        return {'model': self.model, 'metric': self.metric, 'parameters': self.parameters,
                'held_out': [s.to_dict() for s in self.held_out],
                'held_out_as_fitted': [s.to_dict() for s in self.held_out_as_fitted],
                'extended_vs_baseline': dict(self.extended_vs_baseline)}

    def summary(self) -> list[str]:
        """Return the lines people read: the three models per held-out set, the losing axes."""
        lines = ['held-out time_nrmse (torque predicted from the measured motion), nominal / '
                 'least squares / extended as fitted:']
        for s in self.held_out_as_fitted:
            lines.append(f'  {s.record}: ' + '; '.join(
                f'{ax} {v.nominal:.3f} / {v.least_squares:.3f} / {v.extended:.3f}'
                for ax, v in s.per_axis.items()))
        lines += [f'  {ax}: the extended model {v}'
                  for ax, v in self.extended_vs_baseline.items() if v.startswith('does not')]
        return lines


def against_least_squares(res: DiagnosisResult, rec: Recording,
                          others: list[tuple[str, Recording]], robot: RobotParams,
                          progress: Progress) -> tuple[DiagnosisResult, LeastSquaresCheck]:
    """
    Judge the extended model against the 4-parameter least-squares baseline.

    Parameters
    ----------
    res : DiagnosisResult
        The diagnosis of ``rec`` so far.
    rec : Recording
        The record it was fitted on.
    others : list of (str, Recording)
        Name and record of every other record of the robot (``--validate``).
    robot : RobotParams
        The nominal model.
    progress : callable
        Gets the lines people read (:meth:`LeastSquaresCheck.summary`).

    Returns
    -------
    (DiagnosisResult, LeastSquaresCheck)
        The result after the rule (time series; unchanged on the experiments route) and the
        check for the report.

    """
    ls = fit_least_squares(rec, res.fit_rows, names=robot.joint_names)
    sets = [('held out', rec, res.held_out_rows)] + [(p, o, None) for p, o in others]
    comp = fitted = held_out_comparison(robot, res.extended, ls, sets)
    lost = axes_not_beating(comp)
    named = {ax: ', '.join(sorted({e.name for e in res.effects if e.axis == ax})) for ax in lost}
    took: dict[str, list[str]] = {}
    if res.mode == 'timeseries' and lost:
        alt = diagnose_timeseries(rec, robot, fc=res.band.fc_hz if res.band else None,
                                  only={ax: BASELINE_GROUPS for ax in lost})
        still = axes_not_beating(held_out_comparison(robot, alt.extended, ls, sets))
        took = {ax: v for ax, v in lost.items() if ax not in still}
        res = without_axes(with_axes_of(res, alt, took, comp), robot,
                           {ax: v for ax, v in lost.items() if ax not in took}, comp)
        m = predict_metrics(rec, res.extended, mask=res.held_out_rows)
        res = replace(res, metrics=replace(res.metrics, extended=m.scores))
        comp = held_out_comparison(robot, res.extended, ls, sets)

    def verdict(ax: str) -> str:
        if ax not in lost:
            return 'beats the baseline (or ties it) on every held-out set'
        head = f'does not beat the baseline on {", ".join(lost[ax])}'
        if ax in took:
            return (f"{head}; its effects ({named[ax] or 'none'}) are replaced by the "
                    f"baseline's terms refitted in the model, which tie or beat it")
        if res.mode == 'timeseries' and named[ax]:
            return f'{head}; its effects ({named[ax]}) are rejected'
        return head
    check = LeastSquaresCheck(
        model='per axis: motor torque ~ inertia*qdd + viscous*qd + coulomb*tanh(qd/0.01) '
              '+ offset, velocity and acceleration from the motor positions, low-passed '
              f'at {ls.fc:g} Hz, fitted on the fit rows of the diagnosis',
        metric='time_nrmse of the torque predicted from the measured motion (time-series '
               'definition and sample mask)',
        parameters=ls.parameters(), held_out=comp, held_out_as_fitted=fitted,
        extended_vs_baseline={ax: verdict(ax) for ax in ls.names})
    for line in check.summary():
        progress(line)
    return res, check
