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
Per-axis stages of the time-series route: regressor groups, their selection, the effects.

For one axis of a :class:`.prepared.Prepared` record: the candidate regressor groups and the
ripple scan (:func:`axis_groups`), forward selection that keeps physical values and
position-dependent terms that extrapolate (:func:`select_extrapolating`), the report's
``rejected`` entries of the groups not chosen (:func:`rejected_groups`) and the effects written
from the chosen ones, with their standard errors (:func:`axis_effects`).
"""
from __future__ import annotations

import math
from typing import Any

from frf_ident.core.model.params import RobotParams
import numpy as np

from .extrapolation import failing_position_terms
from .prepared import Prepared
from ..common import Effect
from ..records import Rejected
from ..regression import find_ripple
from ..regressors import regressor_groups, URDF_GROUPS
from ..residual import lowpass
from ..selection import block_standard_errors, by_group, lstsq, select_groups
from ..thresholds import ONE_WAY, RANGE_OUT_SHARE

__all__ = ['axis_effects', 'axis_groups', 'EFFECT_OF', 'rejected_groups',
           'select_extrapolating', 'select_physical']

#: the effect a one-coefficient group names where it is not the group's own name
EFFECT_OF = {'motor_inertia': 'parameter_mismatch', 'gravity_torque': 'parameter_mismatch',
             'urdf_inertia': 'pose_dependent_inertia', 'urdf_gravity': 'gravity'}
#: evidence sentence of each one-coefficient regressor group (c: fitted coefficient)
_SCALAR_EVIDENCE = {
    'coulomb_friction': ('inverse-dynamics residual steps by {step:.3g} (torque units) at each '
                         'velocity reversal (F test p = {p:.2g}; removing it raises the held-out '
                         'residual energy by {gain:.0f} %)'),
    'viscous_friction': ('residual proportional to velocity: {c:+.4g} per unit velocity '
                         '(p = {p:.2g})'),
    'motor_inertia': ('residual proportional to acceleration: inertia {old:.4g} -> {new:.4g} '
                      '(p = {p:.2g})'),
    'gravity_torque': ('constant torque residual {c:+.3g} (a load or friction asymmetry the model '
                       'lacks; p = {p:.2g})'),
    'urdf_inertia': ("residual proportional to the URDF's inertia and Coriolis torque along the "
                     'motion: a load inertia that changes with the pose, share {old:.4g} -> '
                     '{new:.4g} of the URDF (p = {p:.2g})'),
    'urdf_gravity': ("residual proportional to the URDF's gravity torque along the motion: "
                     'share {old:.4g} -> {new:.4g} of the URDF (p = {p:.2g})'),
}
#: evidence of a term of an axis refitted with the least-squares baseline's terms (``only``)
_BASELINE_EVIDENCE = ('{c:+.4g} on the model value {old:.4g}, fitted with the least-squares '
                      "baseline's terms (inertia, viscous and Coulomb friction, a constant) "
                      'after the effects selected on this axis did not beat that baseline on '
                      'held-out data')
#: evidence of the constant fitted without a test on an axis that moves one way only
_ONE_WAY_EVIDENCE = ('constant torque residual {c:+.3g} while the axis moves one way only: '
                     'Coulomb friction and a constant load (gravity at the operating point) in '
                     'one parameter, always fitted (not tested)')


def axis_groups(d: Prepared, robot: RobotParams, i: int, rejected: list[Rejected]
                ) -> tuple[dict[str, np.ndarray], list[str], tuple[float, float, float]]:
    """
    Return axis i's regressor groups, the groups always fitted, and the ripple scan.

    The ripple scan runs on the wide-band residual left by the base groups and a slow trend in
    the axis' own position (a cable carrier's spring, a load of a non-bearing axis: over the
    1.5 cycles at the low end of the scan it poses as a ripple, which repeats along the travel
    and a trend does not). On an axis that moves one way only, sgn(v) is the constant column:
    Coulomb friction becomes a load, always fitted. Untestable gravity and Coulomb friction
    are added to ``rejected`` with the reason.

    Returns
    -------
    (dict, list of str, (float, float, float))
        The groups, the forced group names, and the scan's (spatial frequency [1/rad], peak,
        threshold).

    """
    ax, names = robot.axes[i], robot.joint_names
    qh, vh, ah, fs, fc = d.qh, d.vh, d.ah, d.rec.fs, d.fc
    ff, fit_i, val_i, n_eff = d.prep[i]
    skip = d.skips[i]
    g0 = regressor_groups(qh, vh, ah, fs, fc, i, 0.0, d.bearing, skip)
    if skip:
        rejected.append(Rejected('gravity', ax.name, reason=(
            'not testable in this record: ' + ', '.join(
                ' + '.join('q_' + names[j] for j in js) for js in skip)
            + ' moves one way only where the axis moves, so a sinusoid of it fits any '
              'torque that changes along the path (friction, inertia)')))
    qc = qh[:, i] - qh[fit_i, i].mean() if fit_i.any() else qh[:, i]
    trend = np.column_stack([qc, qc ** 2])
    X0 = np.column_stack(list(g0.values()) + [lowpass(trend, fs, fc)])
    c0, *_ = np.linalg.lstsq(X0[fit_i], ff[fit_i], rcond=None)
    wide = lowpass(d.f[:, i], fs, 0.45 * fs) - np.column_stack(
        list(regressor_groups(qh, vh, ah, fs, 0.45 * fs, i, 0.0, d.bearing, skip).values())
        + [lowpass(trend, fs, 0.45 * fs)]) @ c0
    s, peak, thr = find_ripple(wide, qh[:, i], fit_i)
    groups = regressor_groups(qh, vh, ah, fs, fc, i, s if peak >= thr else 0.0, d.bearing, skip)
    if d.urdf_torque is not None:
        for k, x in zip(URDF_GROUPS, d.urdf_torque):
            groups[k] = lowpass(np.nan_to_num(x[:, i:i + 1]), fs, fc)
    up = float(np.mean(vh[fit_i, i] > 0)) if fit_i.any() else 0.0
    forced: list[str] = []
    if min(up, 1.0 - up) < ONE_WAY:
        del groups['coulomb_friction']
        forced = ['gravity_torque']
        rejected.append(Rejected('coulomb_friction', ax.name, forward_share=round(up, 3),
                                 reason=f'the axis moves one way only in this record '
                                        f'({100 * up:.0f} % of its moving samples forward): '
                                        f'Coulomb friction and a constant load are one '
                                        f'parameter here'))
    return groups, forced, (s, peak, thr)


def select_physical(d: Prepared, ax, i: int, groups: dict[str, np.ndarray], forced: list[str]
                    ) -> tuple[dict[str, np.ndarray], list[str], dict[str, dict], dict]:
    """
    Select axis i's groups, and again without any whose joint fit leaves the physical range.

    A negative friction or inertia is no evidence of that effect: the group is dropped and the
    selection runs again without it, since it may have kept out the group that carries that
    torque (a negative inertia standing in for a constant load).

    Returns
    -------
    (dict, list of str, dict, dict)
        The groups left, the chosen names, the selection numbers per group (with the
        ``unphysical`` value of a dropped one) and the chosen groups' coefficients.

    """
    ff, fit_i, val_i, n_eff = d.prep[i]
    chosen, info = select_groups(groups, ff, fit_i, val_i, n_eff, forced=forced)
    unphysical: dict[str, dict] = {}
    while True:
        coef, _ = lstsq([groups[k][fit_i] for k in chosen], ff[fit_i])
        cf = by_group(coef, groups, chosen)
        bad = [k for k, base in (('coulomb_friction', ax.coulomb_friction),
                                 ('viscous_friction', ax.viscous_friction),
                                 ('motor_inertia', ax.motor_inertia),
                                 ('urdf_inertia', ax.urdf_inertia))
               if k in cf and base + float(cf[k][0]) <= 0]
        if not bad:
            break
        unphysical.update({k: {**info[k], 'unphysical': getattr(ax, k) + float(cf[k][0])}
                           for k in bad})
        groups = {k: x for k, x in groups.items() if k not in unphysical}
        forced = [k for k in forced if k in groups]
        chosen, info = select_groups(groups, ff, fit_i, val_i, n_eff, forced=forced)
    return groups, chosen, {**unphysical, **info}, cf


def select_extrapolating(d: Prepared, ax, i: int, groups: dict[str, np.ndarray],
                         forced: list[str]
                         ) -> tuple[dict[str, np.ndarray], list[str], dict[str, dict], dict]:
    """
    Run :func:`select_physical` until every chosen position-dependent group extrapolates.

    A gravity or ripple group that fails leave-range-out
    (:func:`.extrapolation.failing_position_terms`) is dropped and the selection runs again
    without it (another joint set may carry the load); its info gets ``range_out``.
    """
    ff, fit_i = d.prep[i][0], d.prep[i][1]
    failed: dict[str, dict] = {}
    while True:
        groups, chosen, info, cf = select_physical(d, ax, i, groups, forced)
        bad = failing_position_terms(groups, chosen, ff, fit_i, d.qh, i)
        if not bad:
            return groups, chosen, {**failed, **info}, cf
        failed.update({k: {**info[k], 'range_out': e} for k, e in bad.items()})
        groups = {k: x for k, x in groups.items() if k not in bad}


def rejected_groups(axis: str, chosen: list[str], info: dict[str, dict]
                    ) -> list[Rejected]:
    """Return the report's ``rejected`` entries of the groups not chosen, with their numbers."""
    out = []
    for k, v in info.items():
        if k in chosen:
            continue
        reason, fitted = None, None
        if 'range_out' in v:
            reason = (
                f'does not extrapolate: fitted without each end ({100 * RANGE_OUT_SHARE:.0f} % '
                f'of its configuration range), the residual there is {v["range_out"][0]:.3g} '
                f'with it and {v["range_out"][1]:.3g} without (leave-range-out)')
        if 'unphysical' in v:
            fitted = round(v['unphysical'], 4)
            reason = (f'the joint fit gives {k} = {v["unphysical"]:.3g}, outside the '
                      f'physical range: another term the model lacks')
        out.append(Rejected(k.split(':')[0], axis, reason=reason,
                            p_value=float(f'{v.get("p", 1.0):.3g}'),
                            residual_share=round(float(v.get('share', 0.0)), 4),
                            held_out_gain=round(float(v.get('held_out_gain', 0.0)), 4),
                            fitted_value=fitted))
    return out


def axis_effects(d: Prepared, robot: RobotParams, i: int, groups: dict[str, np.ndarray],
                 chosen: list[str], info: dict[str, dict], cf: dict,
                 scan: tuple[float, float, float]) -> tuple[dict[str, Any], list[Effect]]:
    """
    Return axis i's changed model-file parameters and its effects, with standard errors.

    The residual is u - model: every coefficient adds to the model's value. The score of an
    effect is its group's held-out gain (clipped to [0, 1]).
    """
    ax = robot.axes[i]
    ff, fit_i, _, _ = d.prep[i]
    s, peak, thr = scan
    ch: dict[str, Any] = {}
    out: list[Effect] = []
    score = {k: float(np.clip(info[k].get('held_out_gain', 0.0), 0, 1)) for k in chosen}
    se = block_standard_errors(groups, chosen, ff, fit_i, d.rec.fs)
    for k in ('coulomb_friction', 'viscous_friction', 'motor_inertia', 'torque_ripple',
              'gravity_torque') + URDF_GROUPS:
        if k not in cf:
            continue
        if k == 'torque_ripple':
            a_s, a_c = (float(x) for x in cf[k])
            amp = math.hypot(a_s, a_c)
            rip = {'amplitude': amp, 'spatial_frequency': s,
                   'phase': math.atan2(-a_c, -a_s)}
            ch[k] = list(ax.torque_ripple) + [rip]
            err = {k: [None] * len(ax.torque_ripple) + [{'amplitude': _se(se[k][0])}]}
            text = (f'residual periodic in position: amplitude {amp:.3g}{_pm(se[k][0])} at '
                    f'{s:.4g} /rad (scan peak {peak:.0f}x the local noise level, '
                    f'false-alarm level {thr:.0f})')
        else:
            c = float(cf[k][0])
            ch[k] = getattr(ax, k) + c
            form = (_BASELINE_EVIDENCE if info[k].get('baseline') else _ONE_WAY_EVIDENCE
                    if info[k].get('forced') else _SCALAR_EVIDENCE[k])
            text = form.format(
                c=c, step=2 * c, old=getattr(ax, k), new=ch[k], p=info[k]['p'],
                gain=100 * info[k].get('held_out_gain', 0.0))
            if math.isfinite(se[k][0]):
                text += f'; {k} = {ch[k]:.4g}{_pm(se[k][0])}'
            err = {k: _se(se[k][0])}
        out.append(Effect(EFFECT_OF.get(k, k), ax.name, score[k], {k: ch[k]}, text, i,
                          standard_error=err))
    gk = [k for k in chosen if k.startswith('gravity:')]
    if gk:
        ch['gravity'], eff = gravity_effect(robot, i, gk, cf, se, max(score[k] for k in gk))
        out.append(eff)
    return ch, out


def gravity_effect(robot: RobotParams, i: int, gk: list[str], cf: dict, se: dict,
                   score: float) -> tuple[list[dict[str, Any]], Effect]:
    """Return axis i's gravity terms (the model's plus the fitted) and their effect."""
    ax, names = robot.axes[i], robot.joint_names
    terms = list(ax.gravity)
    errs: list[dict[str, float | None] | None] = [None] * len(terms)
    parts = []
    for k in gk:
        for t_i, set_text in enumerate(k.split(':')[1].split('|')):
            js = [int(x) for x in set_text.split(',')]
            a_s, a_c = (float(x) for x in cf[k][2 * t_i:2 * t_i + 2])
            # residual = +G sin(arg + phi) = G cos(phi) sin(arg) + G sin(phi) cos(arg)
            term = {'amplitude': math.hypot(a_s, a_c), 'phase': math.atan2(a_c, a_s),
                    'joints': [names[j] for j in js]}
            terms.append(term)
            errs.append({'amplitude': _se(se[k][t_i])})
            parts.append(f'{term["amplitude"]:.3g}{_pm(se[k][t_i])} sin('
                         f'{" + ".join("q_" + names[j] for j in js)} '
                         f'{term["phase"]:+.2f})')
    return terms, Effect(
        'gravity', ax.name, score, {'gravity': terms},
        f'residual follows the configuration: {", ".join(parts)} (torque units; '
        f'held-out gain {100 * score:.0f} %)', i, standard_error={'gravity': errs})


def _se(x: float) -> float | None:
    """Return a standard error for the report: None when there were too few blocks."""
    return None if not math.isfinite(x) else float(x)


def _pm(x: float) -> str:
    """Return ' +- se' for the evidence text ('' without a standard error)."""
    return f' \u00b1 {x:.2g}' if math.isfinite(x) else ''
