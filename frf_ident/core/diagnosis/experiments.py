"""Diagnosis of identification recordings (multisine on constant velocity + iterated chirps).

Every candidate effect is fitted from the evidence it leaves (one function per effect), then
the candidate model is simulated on the recorded excitation through the same controller and
estimated exactly like the measurement. Its gain is the relative drop of the fit loss (FRF
misfit of multisine and chirp, torque and velocity output errors, each relative to the
nominal model's). Effects are ranked by gain; ones below ``MIN_GAIN`` are noise.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Callable

import numpy as np
from scipy import optimize

from frf_ident.core.simulation.analytic import robot_frf_sampled
from frf_ident.core.estimation.described import chirp_frf, multisine_frf
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError

from .common import (Effect, apply_effect, diag_ratio, frf_error_db, nrmse, segment_mask,
                     simulate_like, split_recording)
from .residual import inverse_dynamics_residual, regress_axis

MIN_GAIN = 0.12      # an effect must remove this share of the nominal model's misfit
KEEP_GAIN = 0.04     # ... and, when combined, still this share of what is left


def estimates(rec: Recording) -> dict[str, Any]:
    """The two estimates the diagnosis compares: compensated multisine BLA and the chirp."""
    out: dict[str, Any] = {}
    if any(s.info.get('design') == 'multisine' for s in rec.segments):
        cv = any(s.info.get('design') == 'constant_velocity' for s in rec.segments)
        out['multisine'] = multisine_frf(rec, compensate=cv)[0]
    if any(s.info.get('design') == 'chirp' for s in rec.segments):
        out['chirp'] = chirp_frf(rec)
    return out


class Evaluator:
    """Simulates candidate models on the recorded excitation and scores them."""

    def __init__(self, rec: Recording, ctrl: PIVelocity) -> None:
        self.rec, self.ctrl = rec, ctrl
        self.fit, self.val, self.validation_text = split_recording(rec)
        self.meas_fit = estimates(self.fit)
        self.meas_val = estimates(self.val) if self.val.segments else {}
        self.fit_mask = segment_mask(self.fit)
        self.val_mask = segment_mask(self.val)
        self.base_terms: dict[str, float] | None = None
        # noise yardsticks of the loss terms: the BLA variance of the measured multisine
        # (relative, per line), 1e-4 (0.09 dB / 1 %) elsewhere
        self.floors = {'multisine': 1e-4, 'chirp': 1e-4, 'effort': 1e-4, 'velocity': 1e-4}
        ms = self.meas_fit.get('multisine')
        if ms is not None and ms.noise_variance is not None:
            n = min(ms.response.shape[:2])
            idx = np.arange(n)
            rel = ms.noise_variance[idx, idx] / np.abs(ms.response[idx, idx]) ** 2
            self.floors['multisine'] = max(float(np.mean(rel)), 1e-4)
        self.n_sims = 0

    def _sim(self, robot: RobotParams) -> Recording:
        self.n_sims += 1
        return simulate_like(self.rec, robot, self.ctrl)

    def terms(self, robot: RobotParams, sim: Recording | None = None) -> dict[str, float]:
        """Raw fit-loss terms of a model: mean |ln(P_meas/P_model)|^2 per estimate (diagonal),
        torque and velocity NRMSE^2 on the fit segments."""
        sim = sim if sim is not None else self._sim(robot)
        s = replace_segments(sim, self.fit)
        est = estimates(s)
        out = {}
        for k, pm in self.meas_fit.items():
            r = np.log(diag_ratio(pm, est[k]))
            out[k] = float(np.mean(np.abs(r) ** 2))
        m = self.fit_mask
        out['effort'] = nrmse(self.rec.effort, sim.effort, m) ** 2
        out['velocity'] = nrmse(self.rec.velocity, sim.velocity, m) ** 2
        return out

    def loss(self, robot: RobotParams) -> float:
        """Fit loss relative to the nominal model (1 = as bad as nominal)."""
        t = self.terms(robot)
        b = self.base_terms or t
        fl = self.floors
        return float(np.mean([(t[k] + fl[k]) / (b[k] + fl[k]) for k in b]))

    def metrics(self, robot: RobotParams) -> dict[str, float]:
        """docs/CONTRACT.md §7 metrics on the held-out part."""
        sim = self._sim(robot)
        sv = replace_segments(sim, self.val if self.val.segments else self.fit)
        mv = self.meas_val if self.meas_val else self.meas_fit
        est = estimates(sv)
        mask = self.val_mask if self.val_mask.any() else self.fit_mask
        return {'frf_error_db': round(frf_error_db([(mv[k], est[k]) for k in mv]), 4),
                'time_nrmse': round(nrmse(self.rec.velocity, sim.velocity, mask), 5)}


def replace_segments(rec: Recording, like: Recording) -> Recording:
    return Recording(rec.t, rec.joint_names, rec.position, rec.velocity, rec.effort,
                     rec.reference, rec.excitation, list(like.segments), rec.meta)


# --- evidence and fits, one function per effect ------------------------------------------------

def friction_regression(ev: Evaluator, robot: RobotParams, axis: int):
    """Motor-side inverse-dynamics residual of the nominal model regressed on sgn(v), v and
    motor-position harmonics, on the fit segments plus the constant-velocity run."""
    rec = ev.rec
    f, qh, vh, ah = inverse_dynamics_residual(rec.position, rec.velocity, rec.effort, rec.dt,
                                              robot)
    mask = (segment_mask(ev.fit, ('multisine', 'chirp', 'constant_velocity')))[:-1]
    noise = max(robot.axes[axis].velocity_noise, 1e-6)
    return regress_axis(f[:, axis], qh[:, axis], vh[:, axis], ah[:, axis],
                        rec.effort[:-1, axis], mask, rec.fs, v_eps=5 * noise + 1e-4,
                        ripple_mask=segment_mask(ev.fit, ('constant_velocity',))[:-1])


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
                  f'constant velocity does not', axis)


def fit_viscous(reg, robot: RobotParams, axis: int) -> Effect | None:
    c = reg.coef.get('viscous_friction')
    if c is None:
        return None
    a = robot.axes[axis]
    bv = max(a.viscous_friction + c, 0.0)
    return Effect('viscous_friction', a.name, 0.0, {'viscous_friction': bv},
                  f'torque residual proportional to motor velocity: {c:+.3g} N m s/rad '
                  f'(t = {reg.tstat["viscous_friction"]:.1f}, partial R2 '
                  f'{reg.partial_r2.get("viscous_friction", 0):.2f})', axis)


def fit_ripple(reg, robot: RobotParams, axis: int) -> Effect | None:
    if not reg.ripple or reg.ripple_peak_ratio < 30:
        return None
    r = reg.ripple[0]
    a = robot.axes[axis]
    rip = list(a.torque_ripple) + [{'amplitude': r['amplitude'],
                                    'spatial_frequency': r['spatial_frequency'],
                                    'phase': r['phase']}]
    return Effect('torque_ripple', a.name, 0.0, {'torque_ripple': rip},
                  f'torque residual periodic in motor position: {r["amplitude"]:.3g} N m at '
                  f'{r["spatial_frequency"]:.4g} cycles*2pi/rad (peak {reg.ripple_peak_ratio:.0f}x '
                  f'the median of the position spectrum), held by the constant-velocity '
                  f'compensation run', axis)


def fit_time_delay(ev: Evaluator, sim_est: dict, robot: RobotParams, axis: int) -> Effect | None:
    """Phase of P_meas/P_nominal linear in frequency with unchanged magnitude: weighted LS of
    the unwrapped phase on -2 pi f (multisine and chirp lines)."""
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


_LIN_KEYS = ('motor_inertia', 'link_inertia', 'stiffness', 'damping')


def _scaled(robot: RobotParams, axis: int, keys, x) -> RobotParams:
    axes = list(robot.axes)
    a = axes[axis]
    axes[axis] = replace(a, **{k: getattr(a, k) * math.exp(v) for k, v in zip(keys, x)})
    return replace(robot, axes=axes)


def fit_linear_scales(meas: dict, robot: RobotParams, axis: int, keys=_LIN_KEYS,
                      which=('multisine', 'chirp')) -> np.ndarray:
    """Least squares of log scale factors of ``keys`` so that the analytic sampled FRF fits the
    measured diagonal element (complex log error) of the chosen estimates."""
    sel = [(meas[k].freq_hz, meas[k].response[axis, axis]) for k in which if k in meas]

    def res(x):
        rb = _scaled(robot, axis, keys, x)
        out = []
        for f, pm in sel:
            pa = robot_frf_sampled(rb, f)[axis, axis]
            e = np.log(pm / pa)
            out += [e.real, np.angle(pm / pa)]
        return np.concatenate(out)
    sol = optimize.least_squares(res, np.zeros(len(keys)), bounds=(-1.5, 1.5), x_scale=0.1)
    return sol.x


def stiffness_seen(meas: dict, sim_est: dict, robot: RobotParams, axis: int, key: str
                   ) -> float:
    """Log stiffness scale that fits estimate ``key`` of the measurement, minus the one that
    fits the same estimate of the nominal simulation (removes estimator bias)."""
    if key not in meas:
        return 0.0
    return float(fit_linear_scales(meas, robot, axis, ('stiffness',), (key,))[0]
                 - fit_linear_scales(sim_est, robot, axis, ('stiffness',), (key,))[0])


def fit_parameter_mismatch(ev: Evaluator, robot: RobotParams, axis: int, scales_ms, scales_ch
                           ) -> Effect | None:
    """Inertias, stiffness and damping fitted to both loads; consistent shifts only."""
    x = fit_linear_scales(ev.meas_fit, robot, axis)
    a = robot.axes[axis]
    changed = {k: getattr(a, k) * math.exp(v) for k, v in zip(_LIN_KEYS, x) if abs(v) > 0.03}
    if not changed:
        return None
    ks = [f'{k} x{math.exp(v):.2f}' for k, v in zip(_LIN_KEYS, x) if abs(v) > 0.03]
    return Effect('parameter_mismatch', a.name, 0.0, changed,
                  f'resonance/antiresonance shifted consistently at low and high load '
                  f'(stiffness fit multisine x{math.exp(scales_ms):.3f}, chirp '
                  f'x{math.exp(scales_ch):.3f}); FRF fit gives {", ".join(ks)}', axis)


def fit_stiffness_nonlinearity(ev: Evaluator, robot: RobotParams, axis: int, scales_ms,
                               scales_ch) -> Effect | None:
    """Stiffening spring (eq. 2): the chirp (high load) sees a stiffer joint than the multisine
    (low load). k2 and bs refined by simulation from the describing-function guess."""
    if scales_ch - scales_ms < 0.01:
        return None
    a = robot.axes[axis]
    k1 = a.stiffness
    tau = float(np.percentile(np.abs(ev.rec.effort[ev.fit_mask, axis]), 99))
    x0 = np.array([math.log(1 + 2.5 * (math.exp(scales_ch) - 1)), math.log(0.25 * tau / k1)])

    def mk(x):
        return _with(robot, axis, stiffness_k2=k1 * math.exp(x[0]),
                     stiffness_breakpoint=math.exp(x[1]))
    x = _refine(ev, mk, x0, [(0.0, 1.5), (x0[1] - 2.5, x0[1] + 2.0)])
    return Effect('stiffness_nonlinearity', a.name, 0.0,
                  {'stiffness_k2': k1 * math.exp(x[0]), 'stiffness_breakpoint': math.exp(x[1])},
                  f'resonance moves up with load: stiffness fitted to the chirp (high load) is '
                  f'x{math.exp(scales_ch - scales_ms):.3f} the multisine (low load) one; '
                  f'simulation fit k2 = {k1 * math.exp(x[0]):.4g} N m/rad beyond '
                  f'bs = {math.exp(x[1]):.3g} rad', axis)


def fit_backlash(ev: Evaluator, robot: RobotParams, axis: int, scales_ms, scales_ch
                 ) -> Effect | None:
    """Dead zone: softer joint at low load (multisine) than at high load (chirp); the gap is
    found by a bounded 1-D simulation fit."""
    if scales_ms > -0.01 or scales_ch - scales_ms < 0.01:
        return None
    a = robot.axes[axis]
    tau = float(np.percentile(np.abs(ev.rec.effort[ev.fit_mask, axis]), 99))
    lo = math.log(1e-3 * tau / a.stiffness)
    hi = math.log(20 * tau / a.stiffness)
    grid = np.linspace(lo, hi, 7)
    losses = [ev.loss(_with(robot, axis, backlash=math.exp(g))) for g in grid]
    i = int(np.argmin(losses))
    sol = optimize.minimize_scalar(lambda g: ev.loss(_with(robot, axis, backlash=math.exp(g))),
                                   bounds=(grid[max(i - 1, 0)], grid[min(i + 1, 6)]),
                                   method='bounded', options={'xatol': 0.03, 'maxiter': 8})
    gap = math.exp(sol.x)
    return Effect('backlash', a.name, 0.0, {'backlash': gap},
                  f'joint softer at low load: stiffness fitted to the multisine is '
                  f'x{math.exp(scales_ms):.3f} nominal, to the chirp x{math.exp(scales_ch):.3f}; '
                  f'simulation fit of the dead zone gives a total gap of {gap:.3g} rad', axis)


def _with(robot: RobotParams, axis: int, **kw) -> RobotParams:
    axes = list(robot.axes)
    axes[axis] = replace(axes[axis], **kw)
    return replace(robot, axes=axes)


def _refine(ev: Evaluator, mk: Callable, x0: np.ndarray, bounds) -> np.ndarray:
    sol = optimize.minimize(lambda x: ev.loss(mk(x)), x0, method='Nelder-Mead', bounds=bounds,
                            options={'xatol': 0.01, 'fatol': 1e-3, 'maxfev': 35,
                                     'initial_simplex': np.array([x0, x0 + [0.3, 0],
                                                                  x0 + [0, 0.7]])})
    return sol.x


# --- the diagnosis --------------------------------------------------------------------------

def diagnose_experiments(rec: Recording, robot: RobotParams, ctrl: PIVelocity, *,
                         progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Diagnose an identification recording against the nominal ``robot``.

    Returns {'effects': [Effect], 'extended': RobotParams, 'metrics': {...}, 'estimates':
    {'measured', 'nominal', 'extended'} for the plots, 'sims': {...}, 'evaluator': ev}."""
    say = progress or (lambda _m: None)
    if rec.reference is None:
        raise EstimationError('recording has no velocity reference: use the time-series '
                              'diagnosis')
    ev = Evaluator(rec, ctrl)
    sim0 = ev._sim(robot)
    ev.base_terms = ev.terms(robot, sim0)
    sim_est = estimates(replace_segments(sim0, ev.fit))
    say('nominal model misfit: ' + ', '.join(f'{k} {v:.3g}' for k, v in ev.base_terms.items()))
    cands: list[Effect] = []
    for i in range(robot.n_axes):
        reg = friction_regression(ev, robot, i)
        s_ms, s_ch = (stiffness_seen(ev.meas_fit, sim_est, robot, i, k)
                      for k in ('multisine', 'chirp'))
        say(f'{robot.axes[i].name}: stiffness seen by multisine x{math.exp(s_ms):.3f}, chirp '
            f'x{math.exp(s_ch):.3f}; residual regression {reg.coef}')
        for fn in (lambda: fit_coulomb(reg, robot, i), lambda: fit_viscous(reg, robot, i),
                   lambda: fit_ripple(reg, robot, i),
                   lambda: fit_time_delay(ev, sim_est, robot, i),
                   lambda: fit_parameter_mismatch(ev, robot, i, s_ms, s_ch),
                   lambda: fit_stiffness_nonlinearity(ev, robot, i, s_ms, s_ch),
                   lambda: fit_backlash(ev, robot, i, s_ms, s_ch)):
            e = fn()
            if e is not None:
                e.gain = 1.0 - ev.loss(apply_effect(robot, e))
                say(f'  candidate {e.name}: gain {e.gain:.3f} {e.parameters}')
                cands.append(e)
    cands = sorted((c for c in cands if c.gain >= MIN_GAIN), key=lambda c: -c.gain)
    # combine greedily: keep an effect only if it still helps on top of the stronger ones
    ext, kept, cur = robot, [], 1.0
    for c in cands:
        if any(k.name == c.name and k.axis == c.axis for k in kept):
            continue
        trial = apply_effect(ext, c)
        lt = ev.loss(trial)
        if not kept or lt <= cur * (1 - KEEP_GAIN):
            ext, cur = trial, lt
            kept.append(c)
    for c in kept:
        c.score = float(np.clip(c.gain, 0, 1))
    metrics = {'baseline': ev.metrics(robot), 'extended': ev.metrics(ext),
               'validation': ev.validation_text}
    sim_ext = ev._sim(ext)
    plots = {'measured': ev.meas_val or ev.meas_fit,
             'nominal': estimates(replace_segments(sim0, ev.val if ev.val.segments else ev.fit)),
             'extended': estimates(replace_segments(sim_ext,
                                                    ev.val if ev.val.segments else ev.fit))}
    say(f'{ev.n_sims} simulations of the recorded excitation')
    return {'effects': kept, 'candidates': cands, 'extended': ext, 'metrics': metrics,
            'estimates': plots, 'sims': {'nominal': sim0, 'extended': sim_ext},
            'evaluator': ev}
