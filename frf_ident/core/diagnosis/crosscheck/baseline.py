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
Fit the least-squares baseline every diagnosis is compared with.

Per axis, independently: motor torque ~ J qdd + b qd + Fc tanh(qd / LS_TANH_VELOCITY) +
offset, with velocity and acceleration taken from the motor positions, torque and regressors
low-passed zero-phase at the analysis band. Four parameters per axis, no model file: what a
diagnosis must beat on held-out data before its effects are believed. Evaluated with the
time-series route's own ``time_nrmse`` and sample mask (:func:`..prediction.torque_metrics`).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
import numpy as np

from .verdict import verdict_of
from ..common import bridge_gaps, Effect
from ..prediction import predict_metrics, Prediction, torque_metrics
from ..records import Rejected
from ..regressors import moving
from ..residual import lowpass
from ..result import DiagnosisResult
from ..thresholds import FC_HZ, LS_BASELINE_MARGIN, LS_TANH_VELOCITY, ONE_WAY

__all__ = ['axes_not_beating', 'BASELINE_GROUPS', 'fit_least_squares', 'held_out_comparison',
           'HeldOutSet', 'LeastSquaresBaseline', 'least_squares_metrics', 'ThreeModels',
           'usable_rows', 'with_axes_of', 'without_axes']

#: the columns of :attr:`LeastSquaresBaseline.coef`
TERMS = ('inertia', 'viscous', 'coulomb', 'offset')
#: the time-series route's regressor groups that carry :data:`TERMS` in the model file's terms
#: (an axis whose selected effects lose to the baseline is refitted with exactly these)
BASELINE_GROUPS = ('motor_inertia', 'viscous_friction', 'coulomb_friction', 'gravity_torque')


@dataclass
class LeastSquaresBaseline:
    """The fitted baseline: per axis the coefficients of :data:`TERMS`."""

    names: list[str]
    #: shape (n_axes, 4): inertia [kg m^2], viscous [N m s/rad], Coulomb [N m], offset [N m]
    coef: np.ndarray
    fc: float

    def parameters(self) -> dict[str, dict[str, float]]:
        """Return {axis: {term: value}} for the report."""
        return {n: {t: float(f'{c:.6g}') for t, c in zip(TERMS, row)}
                for n, row in zip(self.names, self.coef)}


@dataclass(frozen=True)
class ThreeModels:
    """One held-out ``time_nrmse`` of the nominal model, the baseline and the extended model."""

    nominal: float
    least_squares: float
    extended: float

    def to_dict(self) -> dict[str, float]:
        """Return the report's entry."""
        return {'nominal': self.nominal, 'least_squares': self.least_squares,
                'extended': self.extended}


@dataclass(frozen=True)
class HeldOutSet:
    """The three models on one held-out set: pooled over the axes and per axis."""

    #: the diagnosis' own held-out rows ('held out') or the path of a ``--validate`` record
    record: str
    time_nrmse: ThreeModels
    per_axis: dict[str, ThreeModels]

    def to_dict(self) -> dict[str, Any]:
        """Return the report's entry."""
        return {'record': self.record, 'time_nrmse': self.time_nrmse.to_dict(),
                'per_axis': {ax: v.to_dict() for ax, v in self.per_axis.items()}}


def regressors(rec: Recording, fc: float) -> np.ndarray:
    """
    Return the baseline's regressors between samples, shape (N-1, n_axes, 4).

    Velocity is the difference of the motor positions over a sample (between samples, where
    the held torque acts), low-passed at ``fc``; acceleration its derivative.
    """
    v = lowpass(np.diff(rec.position, axis=0) / rec.dt, rec.fs, fc)
    a = np.gradient(v, rec.dt, axis=0)
    return np.stack([a, v, np.tanh(v / LS_TANH_VELOCITY), np.ones_like(v)], axis=-1)


def fit_least_squares(rec: Recording, fit_rows: np.ndarray, *, fc: float = FC_HZ,
                      names: list[str] | None = None) -> LeastSquaresBaseline:
    """
    Fit the baseline per axis on the fit rows where the axis moves.

    Parameters
    ----------
    rec : Recording
        The record the diagnosis fits on.
    fit_rows : ndarray of bool, shape (N-1,)
        The diagnosis' fit rows (between samples).
    fc : float
        Analysis band [Hz].
    names : list of str, optional
        The axes' names in the report (the model's; default the record's joint names).

    Returns
    -------
    LeastSquaresBaseline

    """
    rec, lost = bridge_gaps(rec)
    X = regressors(rec, fc)
    uf = lowpass(rec.effort[:-1], rec.fs, fc)
    vh = 0.5 * (rec.velocity[1:] + rec.velocity[:-1])
    move = moving(vh, rec.velocity, rec.fs, fc)
    rows = fit_rows & ~(lost[1:] | lost[:-1])
    coef = np.zeros((X.shape[1], len(TERMS)))
    for i in range(X.shape[1]):
        m = rows & move[:, i]
        if m.sum() <= len(TERMS):
            continue
        up = float(np.mean(X[m, i, 1] > 0))
        # an axis that moves one way only: tanh(qd / 0.01) is the constant column, the
        # Coulomb term and the offset one parameter (as in the time-series route)
        cols = [0, 1, 3] if min(up, 1.0 - up) < ONE_WAY else [0, 1, 2, 3]
        coef[i, cols] = np.linalg.lstsq(X[m, i][:, cols], uf[m, i], rcond=None)[0]
    return LeastSquaresBaseline(list(names or rec.joint_names), coef, fc)


def least_squares_metrics(rec: Recording, model: LeastSquaresBaseline,
                          mask: np.ndarray | None = None) -> Prediction:
    """Return the baseline's ``time_nrmse`` (pooled, per axis) on ``rec`` (mask as the tool's)."""
    rec, lost = bridge_gaps(rec)
    X = regressors(rec, model.fc)
    uf = lowpass(rec.effort[:-1], rec.fs, model.fc)
    ff = uf - np.einsum('tnk,nk->tn', X, model.coef)
    return torque_metrics(rec, lost, ff, model.names, fc=model.fc, mask=mask)


def held_out_comparison(robot: RobotParams, ext: RobotParams,
                        sets: list[tuple[str, Recording, np.ndarray | None,
                                         LeastSquaresBaseline]]) -> list[HeldOutSet]:
    """
    Return nominal, least-squares and extended ``time_nrmse`` on every held-out set.

    Parameters
    ----------
    robot, ext : RobotParams
        The nominal and the extended model.
    sets : list of (str, Recording, ndarray or None, LeastSquaresBaseline)
        Name, record and rows of each held-out set (None: all but the ends, as for another
        record), and the baseline it is judged against: fitted on the diagnosis' fit rows for
        its own held-out rows, on every usable row of the fitted record for another record
        (:func:`usable_rows`).

    Returns
    -------
    list of HeldOutSet
        Per set the three models' ``time_nrmse``, pooled over the axes and per axis.

    """
    out = []
    for name, rec, mask, ls in sets:
        m = [predict_metrics(rec, replace(robot, sample_rate=rec.fs), fc=ls.fc,
                             mask=mask).scores,
             least_squares_metrics(rec, ls, mask).scores,
             predict_metrics(rec, replace(ext, sample_rate=rec.fs), fc=ls.fc,
                             mask=mask).scores]
        out.append(HeldOutSet(name, ThreeModels(*(s.time_nrmse for s in m)),
                              {ax: ThreeModels(*(s.per_axis[ax].time_nrmse for s in m))
                               for ax in ls.names}))
    return out


def usable_rows(rec: Recording) -> np.ndarray:
    """
    Return every row (between samples) a baseline judged on another record is fitted on.

    All of the fitted record, ends included: :func:`fit_least_squares` keeps of them the rows
    where the axis moves and that no gap bridged. What a plain engineer fits on before
    predicting another record; the diagnosis' fit rows are two thirds of them (its held-out
    blocks are not needed when the test is another record), and on KUKA A's second half
    fitted alone they left axis 2's prediction of the first half at 0.524 against 0.471
    (test/app/test_diagnose_real.py).
    """
    return np.ones(rec.t.size - 1, bool)


def axes_not_beating(comparison: list[HeldOutSet]) -> dict[str, list[str]]:
    """
    Return {axis: the held-out sets on which the extended model loses to the baseline}.

    It loses where its time_nrmse exceeds the baseline's by more than
    :data:`~frf_ident.core.diagnosis.thresholds.LS_BASELINE_MARGIN` (a tie is no loss).
    """
    out: dict[str, list[str]] = {}
    for s in comparison:
        for ax, v in s.per_axis.items():
            if verdict_of(v.extended, v.least_squares) == 'loses':
                out.setdefault(ax, []).append(s.record)
    return out


def without_axes(res: DiagnosisResult, robot: RobotParams, lost: dict[str, list[str]],
                 comparison: list[HeldOutSet]) -> DiagnosisResult:
    """
    Return the result with the effects of the axes that do not beat the baseline rejected.

    Each such effect moves to ``rejected`` with the held-out numbers that fail it, and its
    axis is the nominal one again in the extended model. Metrics are not recomputed here.
    """
    if not lost:
        return res
    kept = [e for e in res.effects if e.axis not in lost]
    rejected = list(res.rejected) + [lost_to_baseline(e, comparison, lost[e.axis], 'not taken')
                                     for e in res.effects if e.axis in lost]
    axes = [robot.axes[i] if a.name in lost else a for i, a in enumerate(res.extended.axes)]
    return replace(res, effects=kept, rejected=rejected,
                   extended=replace(res.extended, axes=axes))


def with_axes_of(res: DiagnosisResult, alt: DiagnosisResult, lost: dict[str, list[str]],
                 comparison: list[HeldOutSet]) -> DiagnosisResult:
    """
    Return the result with the axes in ``lost`` as ``alt`` has them.

    ``alt`` is the same record diagnosed with those axes refitted with the baseline's terms
    (:data:`BASELINE_GROUPS`, ``only=`` of :func:`..timeseries.pipeline.diagnose_timeseries`). The
    effects ``res`` selected on them move to ``rejected`` with the held-out numbers that
    fail them. Metrics are not recomputed here.
    """
    if not lost:
        return res
    effects = sorted([e for e in res.effects if e.axis not in lost]
                     + [e for e in alt.effects if e.axis in lost], key=lambda e: -e.score)
    rejected = list(res.rejected) + [
        lost_to_baseline(e, comparison, lost[e.axis], "the axis takes the baseline's terms, "
                                                      'refitted in the model, instead')
        for e in res.effects if e.axis in lost]
    axes = [b if a.name in lost else a for a, b in zip(res.extended.axes, alt.extended.axes)]
    return replace(res, effects=effects, rejected=rejected,
                   extended=replace(res.extended, axes=axes))


def lost_to_baseline(e: Effect, comparison: list[HeldOutSet], records: list[str],
                     outcome: str) -> Rejected:
    """Return the ``rejected`` entry of an effect whose axis lost to the baseline."""
    nums = '; '.join(f'{s.record}: extended {s.per_axis[e.axis].extended:.3f}, '
                     f'least squares {s.per_axis[e.axis].least_squares:.3f}'
                     for s in comparison if s.record in records)
    return Rejected(e.name, e.axis, e.to_dict()['parameters'],
                    reason=f'the extended model does not beat the 4-parameter least-squares '
                           f'baseline on held-out data (more than '
                           f'{100 * LS_BASELINE_MARGIN:.0f} % above it: {nums}): {outcome}')
