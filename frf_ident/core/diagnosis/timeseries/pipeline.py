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
Diagnose plain time series by regression of the inverse-dynamics residual.

Diagnosis of plain time series (recorded trajectories, imported CSV/MAT): no identification
experiments, so the evidence is the motor-side inverse-dynamics residual of the nominal model
(:mod:`..residual`), regressed per axis on the signatures of the candidate effects:

=====================  =====================================================================
group                  regressors (low-passed like the residual)
=====================  =====================================================================
coulomb_friction       sgn(dq)                                           (eq. 1)
viscous_friction       dq
parameter_mismatch     ddq (inertia)
torque_ripple          sin / cos (s q) at the spatial frequency of the position scan
gravity                1 (constant load) and sin / cos (sum of q over a contiguous set of
                       joints containing the axis): G sin(q_i + phi) of a link about its own
                       joint, or sums over the joints it depends on for a coupled arm
=====================  =====================================================================

Groups enter by forward selection with an F test at the data's own noise (residual variance,
effective sample count of the filtered signals, false-alarm probability ``ALPHA``), all selected
groups are refitted jointly, and a group is dropped when removing it does not worsen the
held-out error. Held out: every third block of 0.5 s (:func:`split_blocks`).

``time_nrmse`` is the error of the torque the model predicts from the measured motion
(inverse dynamics) over the RMS of the measured torque, both low-pass filtered; the model is
the model file itself (nominal or extended), so the same number can be computed on any other
record (``--validate``). ``frf_error_db`` compares the measured u -> dq FRF (Welch H1) with the
one of the predicted torque, on the lines with coherence > 0.5.
"""
from __future__ import annotations

from dataclasses import replace
import logging
from typing import Any, Collection

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
import numpy as np

from .effects import axis_effects, axis_groups, rejected_groups, select_extrapolating
from .line_lock import classify_lines
from .prepared import prepare, Prepared
from .resonance import resonances_above
from ..band import analysis_band, fixed_band
from ..common import Effect
from ..prediction import noise_floor, predict_metrics, Prediction, signature
from ..records import Rejected, RouteMetrics, Unexplained
from ..regressors import model_residual
from ..residual import lowpass
from ..result import DiagnosisResult, ResidualTrace, TimeseriesDetail
from ..thresholds import BLOCK_S, HOLD_EVERY, MIN_SHARE, UNEXPLAINED_RATIO

__all__ = ['diagnose_timeseries']

log = logging.getLogger(__name__)


def diagnose_timeseries(rec: Recording, robot: RobotParams, *, fc: float | None = None,
                        exclude: dict[str, set[str]] | None = None,
                        only: dict[str, tuple[str, ...]] | None = None,
                        all_rows: bool = False) -> DiagnosisResult:
    """
    Diagnose a time-series recording against the nominal ``robot``.

    Per axis: residual regression on the fit blocks of :func:`split_blocks`, effects
    selected by F test and held-out error, the extended model, metrics on the held-out blocks.

    Parameters
    ----------
    rec
        The recording (positions, velocities, efforts of the model's axes).
    robot
        The nominal model.
    fc
        Low-pass cut-off of residual and regressors [Hz]; by default chosen from the record
        (:func:`..band.analysis_band`). The residual above it is scanned for resonances
        (:func:`.resonance.resonances_above`), reported as ``unexplained``.
    exclude
        Per axis name the effects (regressor group names before any ':', e.g. 'gravity')
        that are no candidates: terms another record showed not to generalise.
    only
        Per axis name the regressor groups the axis takes, all of them fitted without a
        selection (those the record cannot test, as Coulomb friction on an axis moving one
        way, are left out as always): the least-squares baseline's terms
        (:data:`..crosscheck.baseline.BASELINE_GROUPS`) for an axis whose selected effects
        lost to it.
    all_rows
        Fit on every usable row of the record, its held-out blocks too (their metrics are
        then in sample): how the least-squares baseline judged on another record is fitted
        (:func:`..crosscheck.baseline.usable_rows`), for the axes refitted with its terms.

    Returns
    -------
    DiagnosisResult
        Mode 'timeseries', with :class:`..result.TimeseriesDetail` (the residual for the plots).

    Notes
    -----
    The trace (the band, the selection per axis and the rest) is logged at DEBUG level: the
    application diagnoses a record several times (its halves, ``--validate`` records) and
    reports the band and the effects once.

    """
    band = analysis_band(rec) if fc is None else fixed_band(rec, fc)
    fc = band.fc_hz
    log.debug('%s', band.describe())
    d = prepare(rec, robot, fc, log.debug, all_rows=all_rows)
    effects: list[Effect] = []
    rejected: list[Rejected] = []
    ext_axes = list(robot.axes)
    for i, ax in enumerate(robot.axes):
        ch, found = axis_stage(d, robot, i, rejected, (exclude or {}).get(ax.name, ()),
                               (only or {}).get(ax.name))
        effects += found
        ext_axes[i] = replace(ax, **ch)
    effects.sort(key=lambda x: -x.score)
    ext = replace(robot, axes=ext_axes)
    metrics, val = held_out_metrics(d, robot, ext)
    floor = noise_floor(d.rec, d.f, fc, val['extended'].rows)
    wide = model_residual(d.rec, ext)[0]
    unexplained = unexplained_axes(d, robot, val, floor) + classify_lines(
        resonances_above(wide, d.rec.fs, fc, robot.joint_names), wide, d.vh, d.rec.fs,
        robot.joint_names)
    low = lowpass(d.f, d.rec.fs, fc)
    residual = ResidualTrace(d.rec.t[:-1], d.f, d.qh, d.vh, low - val['baseline'].residual,
                             low - val['extended'].residual, d.val_m)
    return DiagnosisResult('timeseries', effects, rejected, unexplained, metrics, ext,
                           TimeseriesDetail(residual, floor.tolist()), d.fit_m, d.val_m,
                           band=band)


def axis_stage(d: Prepared, robot: RobotParams, i: int, rejected: list[Rejected],
               exclude: Collection[str], only: tuple[str, ...] | None
               ) -> tuple[dict[str, Any], list[Effect]]:
    """
    Diagnose axis i: its groups, their selection, its effects; add what is rejected.

    ``exclude``: effects that are no candidates; ``only``: the groups the axis takes, all
    fitted without a selection (see :func:`diagnose_timeseries`).
    """
    ax = robot.axes[i]
    groups, forced, scan = axis_groups(d, robot, i, rejected)
    groups = {k: x for k, x in groups.items() if k.split(':')[0] not in exclude}
    if only is not None:
        groups = {k: x for k, x in groups.items() if k in only}
        forced = list(groups)
    groups, chosen, info, cf = select_extrapolating(d, ax, i, groups, forced)
    if only is not None:
        info = {k: {**v, 'baseline': True} for k, v in info.items()}
    log.debug('%s: selected %s (ripple scan peak %.1f, threshold %.1f); %s', ax.name,
              chosen, scan[1], scan[2], ', '.join(f'{k} p={v.get("p", 1):.2g} '
                                                  f'share={v.get("share", 0):.3f}'
                                                  for k, v in info.items()))
    rejected += rejected_groups(ax.name, chosen, info)
    return axis_effects(d, robot, i, groups, chosen, info, cf, scan)


def held_out_metrics(d: Prepared, robot: RobotParams, ext: RobotParams
                     ) -> tuple[RouteMetrics, dict[str, Prediction]]:
    """Return the §7 metrics of the nominal and extended model on the held-out blocks."""
    rec, fc, val_m = d.rec, d.fc, d.val_m
    fs, N = rec.fs, rec.t.size
    val = {key: predict_metrics(rec, model, fc=fc, mask=val_m)
           for key, model in (('baseline', robot), ('extended', ext))}
    text = (f'held out (not used for fitting): every {HOLD_EVERY}rd block of {BLOCK_S:g} s '
            f'({val_m.sum() / fs:.2f} s of {N / fs:.2f} s); time_nrmse = error of the '
            f'inverse-dynamics torque of the model file over the RMS of the measured torque '
            f'({fc:g} Hz low-pass)')
    return RouteMetrics(val['baseline'].scores, val['extended'].scores, text), val


def unexplained_axes(d: Prepared, robot: RobotParams, val: dict[str, Prediction],
                     floor: np.ndarray) -> list[Unexplained]:
    """
    Return the axes whose held-out NRMSE^2 stays clearly above the noise floor.

    Above UNEXPLAINED_RATIO floors and at least MIN_SHARE of the nominal misfit above the floor
    (the floor over the rows the held-out NRMSE is taken over: a long rest lowers the torque
    variance), with the signature of the extended model's residual.
    """
    rec = d.rec
    out = []
    for i, ax in enumerate(robot.axes):
        b = val['baseline'].scores.per_axis[ax.name].time_nrmse ** 2
        x = val['extended'].scores.per_axis[ax.name].time_nrmse ** 2
        share = float(np.clip((x - floor[i]) / max(b - floor[i], 1e-300), 0, 1))
        if x > UNEXPLAINED_RATIO * floor[i] and share >= MIN_SHARE:
            sig = signature(val['extended'].residual[:, i], d.qh[:, i], d.vh[:, i],
                            d.ah[:, i], rec.t[:-1], d.val_m, rec.fs, d.fc)
            out.append(Unexplained(ax.name, sig, misfit_share=round(share, 3)))
    return out
