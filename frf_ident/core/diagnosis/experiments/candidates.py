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
Read the evidence of each candidate effect and fit it, one function per effect.

Torque-residual effects (Coulomb and viscous friction, torque ripple, gravity) from a
regression of the inverse-dynamics residual; FRF-shape effects (time delay, parameter
mismatch, stiffening spring, backlash) from the measured FRF against the model's simulation.
"""
from __future__ import annotations

from dataclasses import replace
import math
from typing import Any, Callable

from frf_ident.core.model.params import RobotParams
from frf_ident.core.simulation.analytic import robot_frf_sampled
import numpy as np
from scipy import optimize

from .brent import bounded_minimum
from .evaluator import Evaluator
from .simplex import nelder_mead
from ..common import diag_ratio, Effect, segment_mask
from ..regression import regress_axis
from ..residual import coulomb_and_ripple
from ..thresholds import GRAVITY_MIN_T, LOAD_DEPENDENCE_MIN_LOG, MISMATCH_MIN_LOG


def friction_regression(ev: Evaluator, robot: RobotParams, axis: int, *,
                        position_slope: bool = False):  # noqa: D401
    """
    Regress the motor-side inverse-dynamics residual of a model on one axis.

    Motor-side inverse-dynamics residual of ``robot`` (:meth:`Evaluator.residual`, the command
    delayed by its axes' ``time_delay``) regressed on sgn(v), v and motor-position harmonics,
    on the fit segments plus the constant-velocity run; with ``position_slope`` on sgn(v), v
    and q - q0 instead of the harmonics (q0: the mean position, ``Regression.q0``).

    The inverse dynamics is linear: the model's own Coulomb friction and torque ripple of the
    axis are taken out of its residual here, so every coefficient is a correction to the
    model (what :func:`fit_coulomb`, :func:`fit_viscous` and :func:`fit_ripple` add to it),
    also when friction is read again on top of a model that already has a Coulomb level.
    """
    rec = ev.rec
    f, qh, vh, ah = ev.residual(robot)
    fa = f[:, axis] - coulomb_and_ripple(robot, qh, vh)[:, axis]
    mask = (segment_mask(ev.fit, ('multisine', 'chirp', 'constant_velocity'))
            & ~ev.missing)[:-1]
    noise = max(robot.axes[axis].velocity_noise, 1e-6)
    q = qh[:, axis]
    kw: dict[str, Any] = {'ripple_mask': (segment_mask(ev.fit, ('constant_velocity',))
                                          & ~ev.missing)[:-1]}
    q0 = float(np.mean(q[mask])) if mask.any() else 0.0
    if position_slope:
        kw = {'nuisance': (q - q0)[:, None], 'ripple': False}
    reg = regress_axis(fa, q, vh[:, axis], ah[:, axis], rec.effort[:-1, axis], mask,
                       rec.fs, v_eps=5 * noise + 1e-4, **kw)
    reg.q0, reg.travel = q0, float(np.ptp(q[mask])) if mask.any() else 0.0
    return reg


def fit_coulomb(reg, robot: RobotParams, axis: int) -> Effect | None:
    c = reg.coef.get('coulomb_friction')
    if c is None:
        return None
    a = robot.axes[axis]
    fc = max(a.coulomb_friction + c, 0.0)
    return Effect('coulomb_friction', a.name, 0.0, {'coulomb_friction': fc},
                  f'torque residual of the nominal model steps by {2 * c:.3g} N m when the '
                  f'motor velocity changes sign (t = {reg.tstat["coulomb_friction"]:.1f}, '
                  f'partial R2 {reg.partial_r2.get("coulomb_friction", 0):.2f}); the chirp '
                  f'(velocity reversals) deviates from the nominal FRF while the multisine on '
                  f'constant velocity does not', axis, support=abs(reg.tstat['coulomb_friction']))


def fit_viscous(reg, robot: RobotParams, axis: int) -> Effect | None:
    c = reg.coef.get('viscous_friction')
    if c is None:
        return None
    a = robot.axes[axis]
    bv = max(a.viscous_friction + c, 0.0)
    return Effect('viscous_friction', a.name, 0.0, {'viscous_friction': bv},
                  f'torque residual proportional to motor velocity: {c:+.3g} N m s/rad '
                  f'(t = {reg.tstat["viscous_friction"]:.1f}, partial R2 '
                  f'{reg.partial_r2.get("viscous_friction", 0):.2f})', axis,
                  support=abs(reg.tstat['viscous_friction']))


def fit_ripple(reg, robot: RobotParams, axis: int) -> Effect | None:
    if not reg.ripple or reg.ripple_peak_ratio < reg.ripple_threshold:
        return None
    r = reg.ripple[0]
    a = robot.axes[axis]
    rip = list(a.torque_ripple) + [{'amplitude': r['amplitude'],
                                    'spatial_frequency': r['spatial_frequency'],
                                    'phase': r['phase']}]
    return Effect('torque_ripple', a.name, 0.0, {'torque_ripple': rip},
                  f'torque residual periodic in motor position: {r["amplitude"]:.3g} N m at '
                  f'{r["spatial_frequency"]:.4g} /rad (scan peak {reg.ripple_peak_ratio:.0f}x '
                  f'the local noise level, above the false-alarm level '
                  f'{reg.ripple_threshold:.0f}), held by the constant-velocity run', axis)


def fit_gravity(ev: Evaluator, robot: RobotParams, axis: int) -> Effect | None:
    """
    Fit a configuration-dependent load (gravity) from the torque residual's position slope.

    Over the short travel of identification experiments a load G sin(q + phi) shows as its
    value and slope at the operating point q0 (the mean position of the fit data): the
    residual of the model regressed on [1, sgn v, v, q - q0] gives the missing constant c and
    slope s, and one term through both, G sin(q0 + phi) = L0 + c, G cos(q0 + phi) = s, replaces
    the axis' constant load L0 (``gravity_torque``). Proposed only for an axis whose model has
    no gravity terms yet and where the slope's t statistic reaches GRAVITY_MIN_T (a clean axis
    costs no simulation).

    Parameters
    ----------
    ev : Evaluator
        The recording's evaluator.
    robot : RobotParams
        The model so far.
    axis : int
        The axis.

    Returns
    -------
    Effect or None
        The ``gravity`` candidate (parameters ``gravity`` and ``gravity_torque`` = 0), None
        when the axis already has gravity terms or the data do not move it.

    """
    a = robot.axes[axis]
    if a.gravity:
        return None
    reg = friction_regression(ev, robot, axis, position_slope=True)
    q0 = reg.q0
    c, slope = reg.coef.get('offset', 0.0), reg.coef.get('nuisance_0')
    if slope is None or abs(reg.tstat['nuisance_0']) < GRAVITY_MIN_T:
        return None
    value = a.gravity_torque + c
    amp = math.hypot(value, slope)          # > 0: the slope passed its t test
    phase = math.atan2(value, slope) - q0
    return Effect('gravity', a.name, 0.0,
                  {'gravity': [{'amplitude': amp, 'phase': phase}], 'gravity_torque': 0.0},
                  f'torque residual rises with position: {slope:+.4g} N m/rad over the '
                  f'{reg.travel:.3g} rad travelled (t = {reg.tstat["nuisance_0"]:.1f}), '
                  f'load {value:.4g} N m at {q0:.3g} rad: {amp:.4g} sin(q {phase:+.3f}) N m '
                  f'in place of the constant {a.gravity_torque:.4g}', axis)


def fit_time_delay(ev: Evaluator, sim_est: dict, robot: RobotParams, axis: int) -> Effect | None:
    """
    Fit a time delay to the phase of P_meas/P_nominal.

    Phase of P_meas/P_nominal linear in frequency with unchanged magnitude: weighted LS of
    the unwrapped phase on -2 pi f (multisine and chirp lines).
    """
    fr, ph, mg = [], [], []
    for k, pm in ev.meas_fit.items():
        r = diag_ratio(pm, sim_est[k])[axis]
        fr.append(pm.freq_hz)
        ph.append(np.unwrap(np.angle(r)))
        mg.append(20 * np.log10(np.abs(r)))
    f, p, m = np.concatenate(fr), np.concatenate(ph), np.concatenate(mg)
    tau = float(-(f @ p) / (2 * np.pi * (f @ f)))
    resid = p + 2 * np.pi * f * tau
    a = robot.axes[axis]
    if tau <= 0:
        return None
    return Effect('time_delay', a.name, 0.0, {'time_delay': a.time_delay + tau},
                  f'phase of P_measured/P_nominal falls linearly with frequency '
                  f'({-360 * tau * 60:.1f} deg at 60 Hz = {1e3 * tau:.2f} ms, RMS deviation from '
                  f'the line {np.degrees(np.sqrt(np.mean(resid ** 2))):.1f} deg) while the '
                  f'magnitude ratio stays at {np.sqrt(np.mean(m ** 2)):.2f} dB RMS', axis)


LIN_KEYS = ('motor_inertia', 'link_inertia', 'stiffness', 'damping')


def scaled_axis(robot: RobotParams, axis: int, keys, x) -> RobotParams:
    axes = list(robot.axes)
    a = axes[axis]
    axes[axis] = replace(a, **{k: getattr(a, k) * math.exp(v) for k, v in zip(keys, x)})
    return replace(robot, axes=axes)


def fit_linear_scales(meas: dict, robot: RobotParams, axis: int, keys=LIN_KEYS,
                      which=('multisine', 'chirp')) -> np.ndarray:
    """
    Fit log scale factors of model parameters to the measured FRF.

    Least squares of log scale factors of ``keys`` so that the analytic sampled FRF fits the
    measured diagonal element (complex log error) of the chosen estimates.
    """
    sel = [(meas[k].freq_hz, meas[k].response[axis, axis]) for k in which if k in meas]

    def res(x):
        rb = scaled_axis(robot, axis, keys, x)
        out = []
        for f, pm in sel:
            pa = robot_frf_sampled(rb, f, inputs=[axis])[axis, 0]
            e = np.log(pm / pa)
            out += [e.real, np.angle(pm / pa)]
        return np.concatenate(out)
    sol = optimize.least_squares(res, np.zeros(len(keys)), bounds=(-1.5, 1.5), x_scale=0.1)
    return sol.x


def stiffness_seen(meas: dict, sim_est: dict, robot: RobotParams, axis: int, key: str
                   ) -> float:
    """
    Return the stiffness scale the measurement shows beyond the estimator bias.

    Log stiffness scale that fits estimate ``key`` of the measurement, minus the one that
    fits the same estimate of the nominal simulation (removes estimator bias).
    """
    if key not in meas:
        return 0.0
    return float(fit_linear_scales(meas, robot, axis, ('stiffness',), (key,))[0]
                 - fit_linear_scales(sim_est, robot, axis, ('stiffness',), (key,))[0])


def fit_parameter_mismatch(ev: Evaluator, robot: RobotParams, axis: int, scales_ms, scales_ch,
                           keys: tuple[str, ...] = LIN_KEYS) -> Effect | None:
    """
    Fit inertias, stiffness and damping to both loads; consistent shifts only.

    ``keys``: the linear parameters fitted (without the stiffness on an axis whose spring a
    kept stiffening or backlash holds: :func:`.acceptance.without_stiffness`).
    """
    x = fit_linear_scales(ev.meas_fit, robot, axis, keys)
    a = robot.axes[axis]
    changed = {k: getattr(a, k) * math.exp(v) for k, v in zip(keys, x)
               if abs(v) > MISMATCH_MIN_LOG}
    if not changed:
        return None
    ks = [f'{k} x{math.exp(v):.2f}' for k, v in zip(keys, x) if abs(v) > MISMATCH_MIN_LOG]
    return Effect('parameter_mismatch', a.name, 0.0, changed,
                  f'resonance/antiresonance shifted consistently at low and high load '
                  f'(stiffness fit multisine x{math.exp(scales_ms):.3f}, chirp '
                  f'x{math.exp(scales_ch):.3f}); FRF fit gives {", ".join(ks)}', axis)


def fit_stiffness_nonlinearity(ev: Evaluator, robot: RobotParams, axis: int, scales_ms,
                               scales_ch) -> Effect | None:
    """
    Fit a stiffening spring (eq. 2): the two loads see different stiffness, stiffer than nominal.

    Without preload the chirp (high load) reaches beyond the breakpoint and sees the stiffer joint;
    with a static load (gravity) that deflects the spring beyond bs already, the small multisine
    sits on k2 while the chirp averages over the kink. k2 and bs are refined by simulation from the
    matching describing-function guess.
    """
    if (abs(scales_ch - scales_ms) < LOAD_DEPENDENCE_MIN_LOG
            or max(scales_ch, scales_ms) <= LOAD_DEPENDENCE_MIN_LOG):
        return None
    a = robot.axes[axis]
    k1 = a.stiffness
    tau = float(np.percentile(np.abs(ev.rec.effort[ev.fit_mask, axis]), 99))
    preload = abs(float(robot.gravity_load(np.zeros(robot.n_axes))[axis])) / k1
    if scales_ch > scales_ms or preload <= 0:
        x0 = np.array([math.log(1 + 2.5 * (math.exp(max(scales_ch, scales_ms)) - 1)),
                       math.log(0.25 * tau / k1)])
    else:
        x0 = np.array([scales_ms, math.log(0.7 * preload)])
    x0[0] = min(max(x0[0], 0.05), 1.45)

    def mk(x):
        return with_params(robot, axis, stiffness_k2=k1 * math.exp(x[0]),
                           stiffness_breakpoint=math.exp(x[1]))
    x = _refine(ev, mk, x0, [(0.0, 1.5), (x0[1] - 2.5, x0[1] + 2.0)], axis)
    return Effect('stiffness_nonlinearity', a.name, 0.0,
                  {'stiffness_k2': k1 * math.exp(x[0]), 'stiffness_breakpoint': math.exp(x[1])},
                  f'stiffness depends on the load: fitted to the chirp (high load) it is '
                  f'x{math.exp(scales_ch - scales_ms):.3f} the multisine (low load) one '
                  f'(static deflection {preload:.3g} rad); '
                  f'simulation fit k2 = {k1 * math.exp(x[0]):.4g} N m/rad beyond '
                  f'bs = {math.exp(x[1]):.3g} rad', axis)


def fit_backlash(ev: Evaluator, robot: RobotParams, axis: int, scales_ms, scales_ch
                 ) -> Effect | None:
    """
    Fit a backlash (dead zone) to the load dependence of the stiffness.

    Dead zone: the joint looks softer than nominal at the load that crosses the gap more
    often: without preload the small multisine (mostly inside the gap) sees it softer than the
    chirp; with a static load (gravity) holding the joint on one flank the multisine sees the
    nominal spring and only the chirp, whose torque reverses the deflection, sees it softer.
    The gap is found by a bounded 1-D simulation fit.
    """
    if (min(scales_ms, scales_ch) > -LOAD_DEPENDENCE_MIN_LOG
            or abs(scales_ch - scales_ms) < LOAD_DEPENDENCE_MIN_LOG):
        return None
    a = robot.axes[axis]
    tau = float(np.percentile(np.abs(ev.rec.effort[ev.fit_mask, axis]), 99))
    lo = math.log(1e-3 * tau / a.stiffness)
    hi = math.log(20 * tau / a.stiffness)
    grid = np.linspace(lo, hi, 7)
    ev.prefetch([with_params(robot, axis, backlash=math.exp(g)) for g in grid])
    losses = [ev.loss(with_params(robot, axis, backlash=math.exp(g)), axis) for g in grid]
    i = int(np.argmin(losses))
    gap = math.exp(bounded_minimum(
        lambda g: ev.loss(with_params(robot, axis, backlash=math.exp(g)), axis),
        grid[max(i - 1, 0)], grid[min(i + 1, 6)], xatol=0.03, maxiter=8,
        prefetch=lambda gs: ev.prefetch([with_params(robot, axis, backlash=math.exp(g))
                                         for g in gs])))
    return Effect('backlash', a.name, 0.0, {'backlash': gap},
                  f'joint softer at low load: stiffness fitted to the multisine is '
                  f'x{math.exp(scales_ms):.3f} nominal, to the chirp x{math.exp(scales_ch):.3f}; '
                  f'simulation fit of the dead zone gives a total gap of {gap:.3g} rad', axis)


def with_params(robot: RobotParams, axis: int, **kw) -> RobotParams:
    axes = list(robot.axes)
    axes[axis] = replace(axes[axis], **kw)
    return replace(robot, axes=axes)


def _refine(ev: Evaluator, mk: Callable, x0: np.ndarray, bounds, axis: int) -> np.ndarray:
    simplex = np.array([x0, x0 + [0.3, 0], x0 + [0, 0.7]])
    # the starting simplex at once (Nelder-Mead clips it into the bounds first)
    ev.prefetch([mk(np.clip(x, *np.transpose(bounds))) for x in simplex])
    return nelder_mead(lambda x: ev.loss(mk(x), axis), simplex, bounds=bounds, xatol=0.01,
                       fatol=1e-3, maxfev=35, prefetch=lambda xs: ev.prefetch([mk(x) for x in xs]))


def ripple_again(ev: Evaluator, robot: RobotParams, axis: int, stage1: list[Effect],
                 kept: list[Effect]) -> Effect | None:
    """
    Return the torque ripple of an axis read again on top of ``robot``, or None.

    Only where the stage-1 scan saw one (a candidate in ``stage1``) that the axis has not
    taken (in ``kept``): read from the residual of the model so far, which holds the
    FRF-shape effects that biased the stage-1 reading.
    """
    if (not any(c.name == 'torque_ripple' and c.axis_index == axis for c in stage1)
            or any(k.name == 'torque_ripple' and k.axis_index == axis for k in kept)):
        return None
    r = fit_ripple(friction_regression(ev, robot, axis), robot, axis)
    if r is not None:
        r.evidence = 'read again on top of the FRF-shape effects: ' + r.evidence
    return r


def coupled_ripples(cands: list[Effect], inertia: np.ndarray, resolution: np.ndarray
                    ) -> list[Effect]:
    """
    Return the torque-ripple candidates that are another axis' ripple seen through the links.

    On the constant-velocity run the axes move together, so a ripple of axis i, periodic in
    q_i, loads axis j through the link coupling M_ji as a torque periodic in q_j at the same
    spatial frequency. A ripple candidate of axis j is that coupling when another axis i has
    one within the scan's resolution (the coarser of the two axes') and j's amplitude is at
    most |M_ji / M_ii| times i's (the share of i's ripple torque that reaches j when it
    accelerates i's link alone).

    Parameters
    ----------
    cands : list of Effect
        Candidates; those named ``torque_ripple`` are compared (their last ripple entry).
    inertia : ndarray, shape (n, n)
        Link inertia matrix M of the model (:meth:`RobotParams.link_inertia_matrix`).
    resolution : ndarray, shape (n,)
        Spatial-frequency resolution [1/rad] of each axis' ripple scan
        (``Regression.ripple_resolution``).

    Returns
    -------
    list of Effect
        The candidates of ``cands`` that are a coupled ripple.

    """
    rip = [(c.axis_index, c, c.parameters['torque_ripple'][-1]) for c in cands
           if c.name == 'torque_ripple']
    return [c for j, c, r in rip if any(
        i != j
        and abs(r['spatial_frequency'] - p['spatial_frequency'])
        <= max(resolution[j], resolution[i])
        and r['amplitude'] <= abs(inertia[j, i] / inertia[i, i]) * p['amplitude']
        for i, _, p in rip)]
