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
Keep a position-dependent term only where it generalises to the other records.

A gravity or ripple term fitted over one record's configurations may hold there and fail
beyond them (two large sinusoids cancelling over a short travel, a counterbalance spring
taken for a link's weight). Given other records of the same robot (``--validate``), each axis
with such a term is diagnosed again without it (the rest refitted: a constant load takes its
place) and the version with the smaller error on the other records is kept; the dropped term
is named in ``rejected`` with those numbers. The other records then no longer judge the terms
independently: the report says they decided.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.progress import Progress
from frf_ident.core.recording import Recording

from ..prediction import predict_metrics
from ..records import Rejected
from ..result import DiagnosisResult
from ..thresholds import FC_HZ
from ..timeseries.pipeline import diagnose_timeseries

__all__ = ['POSITION_TERMS', 'drop_terms_not_generalising', 'position_terms_on_others',
           'TermsOnOthers']

#: the effects whose torque depends on the configuration
POSITION_TERMS = ('gravity', 'torque_ripple')


@dataclass(frozen=True)
class TermsOnOthers:
    """An axis' position-dependent terms judged on the other records."""

    #: time_nrmse on each other record with the terms and without them (the rest refitted)
    with_terms: list[float]
    without_terms: list[float]
    #: whether they were dropped (the other records are predicted better without)
    dropped: bool

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``position_terms_on_validate`` entry of the axis."""
        return {'with': list(self.with_terms), 'without': list(self.without_terms),
                'dropped': self.dropped}


def _errors(robot: RobotParams, others: list[tuple[str, Recording]], fc: float
            ) -> dict[str, list[float]]:
    """Return per axis the time_nrmse of ``robot`` on each other record."""
    per = [predict_metrics(o, replace(robot, sample_rate=o.fs), fc=fc).scores.per_axis
           for _, o in others]
    return {ax: [p[ax].time_nrmse for p in per] for ax in robot.joint_names}


def position_terms_on_others(res: DiagnosisResult, rec: Recording, robot: RobotParams,
                             others: list[tuple[str, Recording]], progress: Progress
                             ) -> tuple[DiagnosisResult, dict[str, TermsOnOthers]]:
    """
    Run :func:`drop_terms_not_generalising` and print one line per axis it judged.

    Returns the result and per axis the verdict (empty when no axis was judged).
    """
    res, verdict = drop_terms_not_generalising(res, rec, robot, others)
    for ax, v in verdict.items():
        progress(f'{ax}: position-dependent terms on the --validate records, time_nrmse '
                 f'{" / ".join(f"{x:.3f}" for x in v.with_terms)} with, '
                 f'{" / ".join(f"{x:.3f}" for x in v.without_terms)} without: '
                 + ('dropped (they do not generalise)' if v.dropped else 'kept'))
    return res, verdict


def drop_terms_not_generalising(res: DiagnosisResult, rec: Recording, robot: RobotParams,
                                others: list[tuple[str, Recording]], *, fc: float = FC_HZ
                                ) -> tuple[DiagnosisResult, dict[str, TermsOnOthers]]:
    """
    Return the result without the position-dependent terms that fail on the other records.

    Parameters
    ----------
    res : DiagnosisResult
        The time-series diagnosis of ``rec``.
    rec : Recording
        The record it was fitted on.
    robot : RobotParams
        The nominal model.
    others : list of (str, Recording)
        Name and record of every other record of the robot.
    fc : float
        Analysis band [Hz].

    Returns
    -------
    (DiagnosisResult, dict)
        The result (unchanged when no term fails; its extended model's metrics taken again
        otherwise) and per axis with a position-dependent term its :class:`TermsOnOthers`.

    """
    axes = {e.axis for e in res.effects if e.name in POSITION_TERMS}
    if res.mode != 'timeseries' or not others or not axes:
        return res, {}
    # the URDF's gravity (a group of its own, effect gravity) is such a term too
    alt = diagnose_timeseries(rec, robot, fc=fc,
                              exclude={a: {*POSITION_TERMS, 'urdf_gravity'} for a in axes})
    e_with, e_without = _errors(res.extended, others, fc), _errors(alt.extended, others, fc)
    verdict = {}
    for ax in sorted(axes):
        a, b = e_with[ax], e_without[ax]
        verdict[ax] = TermsOnOthers(a, b, sum(x * x for x in b) < sum(x * x for x in a))
    lost = {ax for ax, v in verdict.items() if v.dropped}
    if not lost:
        return res, verdict
    names = ', '.join(n for n, _ in others)
    rejected = [r for r in res.rejected if r.axis not in lost]
    rejected += [r for r in alt.rejected if r.axis in lost]
    for e in res.effects:
        if e.axis in lost and e.name in POSITION_TERMS:
            v = verdict[e.axis]
            rejected.append(Rejected(
                e.name, e.axis, e.to_dict()['parameters'],
                reason=f'does not generalise to {names}: time_nrmse '
                       f'{" / ".join(f"{x:.3f}" for x in v.with_terms)} with it, '
                       f'{" / ".join(f"{x:.3f}" for x in v.without_terms)} without it (the '
                       f'rest refitted); dropped, so these records decided and no '
                       f'longer judge it independently'))
    effects = sorted([e for e in res.effects if e.axis not in lost]
                     + [e for e in alt.effects if e.axis in lost], key=lambda e: -e.score)
    ext = replace(res.extended, axes=[b if b.name in lost else a for a, b in
                                      zip(res.extended.axes, alt.extended.axes)])
    unexplained = ([u for u in res.unexplained if u.axis not in lost]
                   + [u for u in alt.unexplained if u.axis in lost])
    m = predict_metrics(rec, ext, fc=fc, mask=res.held_out_rows)
    metrics = replace(res.metrics, extended=m.scores)
    return replace(res, effects=effects, rejected=rejected, unexplained=unexplained,
                   metrics=metrics, extended=ext), verdict
