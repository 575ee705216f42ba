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
held-out rows; on every other record it is fitted on all usable rows of the fitted record, as
a plain engineer would (:func:`.baseline.usable_rows`). Per axis and held-out set the report
says whether the extended model beats, ties or loses (:mod:`.verdict`). Time-series route: an
axis whose extended model is not below the baseline on every held-out set is refitted with the
baseline's terms in the model (inertia, viscous and Coulomb friction, a constant load); where
that ties or beats the baseline the axis takes it, else the best of that refit, the axis as
fitted and the nominal axis (:func:`apply_rule`; refitted on the rows of the baseline it is
judged against). The held-out metrics are then taken again.
Experiments route: the verdict is reported, nothing dropped (not calibrated against the
simulation sweep yet).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.progress import Progress
from frf_ident.core.recording import Recording

from .baseline import (axes_not_beating, BASELINE_GROUPS, fit_least_squares, held_out_comparison,
                       HeldOutSet, usable_rows, with_axes_of, without_axes)
from .verdict import BaselineVerdict
from ..prediction import predict_metrics
from ..regressors import URDF_GROUPS
from ..result import DiagnosisResult
from ..timeseries.pipeline import diagnose_timeseries

__all__ = ['against_least_squares', 'LeastSquaresCheck']


@dataclass
class LeastSquaresCheck:
    """The least-squares baseline the report is judged against (report.json ``least_squares``)."""

    #: the baseline's model and the metric, one sentence each
    model: str
    metric: str
    #: {axis: {'inertia', 'viscous', 'coulomb', 'offset'}} in SI units, fitted on the fit rows
    parameters: dict[str, dict[str, float]]
    #: the three models on each held-out set, after the rule
    held_out: list[HeldOutSet]
    #: the same with the extended model as the diagnosis fitted it, before the rule
    held_out_as_fitted: list[HeldOutSet]
    #: {axis: one sentence}: beats (or ties) the baseline, or what happened to its effects
    extended_vs_baseline: dict[str, str]
    #: the same as ``parameters``, fitted on every usable row of the record: the baseline
    #: the other records are judged against (None: no other record)
    parameters_all_rows: dict[str, dict[str, float]] | None = None

    @property
    def verdicts(self) -> list[BaselineVerdict]:
        """Return per held-out set and axis the verdict on the model after the rule."""
        return [BaselineVerdict(s.record, ax, v.extended, v.least_squares)
                for s in self.held_out for ax, v in s.per_axis.items()]

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``metrics.least_squares`` entry."""
        out = {'model': self.model, 'metric': self.metric, 'parameters': self.parameters,
               'held_out': [s.to_dict() for s in self.held_out],
               'held_out_as_fitted': [s.to_dict() for s in self.held_out_as_fitted],
               'extended_vs_baseline': dict(self.extended_vs_baseline),
               'verdicts': [v.to_dict() for v in self.verdicts]}
        if self.parameters_all_rows is not None:
            out['parameters_all_rows'] = self.parameters_all_rows
        return out

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
        lines.append('  after the rule: ' + '; '.join(
            f'{v.axis} on {v.record} {v.verdict} ({v.extended:.3f} / {v.least_squares:.3f})'
            for v in self.verdicts))
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
    ls_all = (fit_least_squares(rec, usable_rows(rec), fc=ls.fc, names=robot.joint_names)
              if others else None)
    sets = [('held out', rec, res.held_out_rows, ls)]
    sets += [(p, o, None, ls_all) for p, o in others]
    comp = fitted = held_out_comparison(robot, res.extended, sets)
    lost = axes_not_beating(comp)
    named = {ax: ', '.join(sorted({e.name for e in res.effects if e.axis == ax})) for ax in lost}
    outcome: dict[str, str] = {}
    if res.mode == 'timeseries' and lost:
        res, outcome, held = apply_rule(res, rec, robot, sets, comp, lost)
        comp = (held_out_comparison(robot, held, sets[:1])
                + held_out_comparison(robot, res.extended, sets[1:]))

    def verdict(ax: str) -> str:
        if ax not in lost:
            return 'beats the baseline (or ties it) on every held-out set'
        return rule_sentence(f'does not beat the baseline on {", ".join(lost[ax])}',
                             named[ax], outcome.get(ax, ''))
    check = LeastSquaresCheck(
        model='per axis: motor torque ~ inertia*qdd + viscous*qd + coulomb*tanh(qd/0.01) '
              '+ offset, velocity and acceleration from the motor positions, low-passed '
              f'at {ls.fc:g} Hz, fitted on the fit rows of the diagnosis (judged on its '
              'held-out rows) and on all usable rows (judged on other records)',
        metric='time_nrmse of the torque predicted from the measured motion (time-series '
               'definition and sample mask)',
        parameters=ls.parameters(), held_out=comp, held_out_as_fitted=fitted,
        extended_vs_baseline={ax: verdict(ax) for ax in ls.names},
        parameters_all_rows=ls_all.parameters() if ls_all is not None else None)
    for line in check.summary():
        progress(line)
    return res, check


#: what :func:`apply_rule` did to a losing axis, as the report says it (its effects in {})
RULE_OUTCOMES = {
    'replaced': "its effects ({}) are replaced by the baseline's terms refitted in the model, "
                'which tie or beat it (fitted as the baseline each set is judged against; '
                'the model written: on every usable row where other records judge it)',
    'replaced, still losing': "its effects ({}) are replaced by the baseline's terms refitted "
                              'in the model, which lose less',
    'kept': "its effects ({}) are kept: neither the baseline's terms refitted in the model "
            'nor the nominal axis predict the held-out sets better',
    'rejected': 'its effects ({}) are rejected'}


def rule_sentence(head: str, effects: str, outcome: str) -> str:
    """Return the report's sentence on a losing axis: ``head``, then what the rule did."""
    if outcome not in RULE_OUTCOMES or (outcome == 'rejected' and not effects):
        return head
    return f'{head}; ' + RULE_OUTCOMES[outcome].format(effects or 'none')


def apply_rule(res: DiagnosisResult, rec: Recording, robot: RobotParams,
               sets: list, comp: list[HeldOutSet], lost: dict[str, list[str]]
               ) -> tuple[DiagnosisResult, dict[str, str], RobotParams]:
    """
    Apply the time-series rule to the axes that lose to the baseline.

    Each is refitted with the baseline's terms in the model (:data:`.baseline.BASELINE_GROUPS`;
    given the robot's URDF, with its shares of the URDF's inertia and gravity beside them,
    :data:`..regressors.URDF_GROUPS`: the physics the user's robot description fixes) on the
    rows of the baseline it is judged against: the diagnosis' fit rows for the
    record's own held-out rows (``sets[0]``), every usable row for other records. Where
    that ties or beats the baseline on every held-out set the axis takes it ('replaced').
    Elsewhere the axis takes whichever of the refit, the extended model as fitted and the
    nominal axis has the smallest sum of squared held-out ``time_nrmse`` over the sets
    ('replaced, still losing', 'kept', 'rejected'): a model fitted on fewer rows than the
    baseline judged on another record may lose to it and still be far better than the
    nominal axis.

    With other records the model written takes the refit on every usable row, and the
    record's own held-out figures are those of the same terms fitted on the fit rows (the
    written ones saw the held-out rows). On KUKA A -> B, C axis 3 refitted on the fit rows
    took an inertia of 7.53 and predicted C at 0.293 against the baseline's 0.210; on every
    usable row 6.18 and 0.212 (test/app/test_diagnose_baseline_real.py).

    Returns
    -------
    (DiagnosisResult, dict of str to str, RobotParams)
        The result after the rule (its extended metrics those of the record's held-out
        rows), per losing axis its outcome, and the model judged on those rows.

    """
    fc = res.band.fc_hz if res.band else None
    # given the robot's URDF, its shares of the URDF's inertia and gravity beside them
    terms = BASELINE_GROUPS + (URDF_GROUPS if robot.urdf is not None else ())
    only = {ax: terms for ax in lost}
    alt = written = diagnose_timeseries(rec, robot, fc=fc, only=only)
    alt_comp = held_out_comparison(robot, alt.extended, sets[:1])
    if len(sets) > 1:
        written = diagnose_timeseries(rec, robot, fc=fc, only=only, all_rows=True)
        alt_comp += held_out_comparison(robot, written.extended, sets[1:])
    still = axes_not_beating(alt_comp)
    outcome = {}
    for ax in lost:
        if ax not in still:
            outcome[ax] = 'replaced'
            continue
        cost = {'kept': sum(s.per_axis[ax].extended ** 2 for s in comp),
                'rejected': sum(s.per_axis[ax].nominal ** 2 for s in comp),
                'replaced, still losing': sum(s.per_axis[ax].extended ** 2 for s in alt_comp)}
        outcome[ax] = min(cost, key=cost.__getitem__)
    took = {ax: v for ax, v in lost.items() if outcome[ax].startswith('replaced')}
    dropped = {ax: v for ax, v in lost.items() if outcome[ax] == 'rejected'}
    held = without_axes(with_axes_of(res, alt, took, comp), robot, dropped, comp).extended
    res = without_axes(with_axes_of(res, written, took, comp), robot, dropped, comp)
    m = predict_metrics(rec, held, mask=res.held_out_rows)
    return replace(res, metrics=replace(res.metrics, extended=m.scores)), outcome, held
