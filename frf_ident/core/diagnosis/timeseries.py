"""Diagnosis of plain time series (recorded trajectories, imported CSV/MAT): no identification
experiments, so the evidence is the inverse-dynamics residual regression of
:mod:`.residual` (tau - M ddq - Fv dq against sgn(dq), dq, ddq and motor-position harmonics),
fitted on the first part of the record and validated on the rest.

``time_nrmse`` here is the error of the torque predicted by inverse dynamics from the measured
motion (the output of the inverse model) over the RMS of the measured torque, both low-pass
filtered; ``frf_error_db`` compares the measured u -> dq FRF (Welch H1) with the one of the
predicted torque, on the lines with coherence > 0.5.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Callable

import numpy as np
from scipy import signal

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording

from .common import Effect
from .residual import inverse_dynamics_residual, lowpass, regress_axis

MIN_T = 5.0          # |t| an effect's coefficient must exceed
MIN_R2 = 0.02        # share of the residual variance it must explain


def _design(f, q, v, a, fs, fc, nuisance, ripple_s):
    cols = [np.ones_like(v), np.sign(lowpass(v, fs, fc)), v, a]
    if nuisance is not None:
        cols += list(nuisance.T)
    if ripple_s:
        cols += [np.sin(ripple_s * q), np.cos(ripple_s * q)]
    return np.column_stack([lowpass(c, fs, fc) for c in cols])


def diagnose_timeseries(rec: Recording, robot: RobotParams, *, fit_fraction: float = 0.7,
                        fc: float = 20.0, nuisance: np.ndarray | None = None,
                        link_position: np.ndarray | None = None,
                        progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Per axis: residual regression on the first ``fit_fraction`` of the record, effects with
    significant coefficients, extended model, metrics on the rest. ``nuisance`` (N, m):
    extra regressors fitted for baseline and extension alike (e.g. gravity terms)."""
    say = progress or (lambda _m: None)
    fs, dt = rec.fs, rec.dt
    N = rec.t.size
    n_fit = int(fit_fraction * N)
    f, qh, vh, ah = inverse_dynamics_residual(rec.position, rec.velocity, rec.effort, dt, robot)
    nu = None if nuisance is None else 0.5 * (nuisance[1:] + nuisance[:-1])
    fit_m = np.zeros(N - 1, bool)
    fit_m[int(0.02 * N):n_fit] = True
    val_m = np.zeros(N - 1, bool)
    val_m[n_fit + int(0.02 * N):-int(0.02 * N)] = True
    effects: list[Effect] = []
    ext_axes = list(robot.axes)
    pred = {'baseline': np.zeros_like(f), 'extended': np.zeros_like(f)}
    details = []
    for i, ax in enumerate(robot.axes):
        vnoise = 3 * float(np.std(np.diff(rec.velocity[:, i]))) / math.sqrt(2) * 0.1
        reg = regress_axis(f[:, i], qh[:, i], vh[:, i], ah[:, i], rec.effort[:-1, i], fit_m,
                           fs, fc=fc, v_eps=vnoise, with_inertia=True, nuisance=nu)
        say(f'{ax.name}: residual regression {({k: round(v, 4) for k, v in reg.coef.items()})}'
            f', t {({k: round(v, 1) for k, v in reg.tstat.items()})}, partial R2 '
            f'{({k: round(v, 3) for k, v in reg.partial_r2.items()})}')
        details.append(reg)
        ch: dict[str, Any] = {}
        jtot = ax.motor_inertia + ax.link_inertia

        def ok(key, group):
            return abs(reg.tstat.get(key, 0)) >= MIN_T and reg.partial_r2.get(group, 0) >= MIN_R2
        if ok('coulomb_friction', 'coulomb_friction') and reg.coef['coulomb_friction'] > 0:
            fcoul = ax.coulomb_friction + reg.coef['coulomb_friction']
            ch['coulomb_friction'] = fcoul
            effects.append(Effect('coulomb_friction', ax.name, reg.partial_r2['coulomb_friction'],
                                  {'coulomb_friction': fcoul},
                                  f'inverse-dynamics residual steps by {2 * reg.coef["coulomb_friction"]:.3g} '
                                  f'(torque units) at each velocity reversal (t = '
                                  f'{reg.tstat["coulomb_friction"]:.1f}; explains '
                                  f'{100 * reg.partial_r2["coulomb_friction"]:.0f} % of the residual '
                                  f'variance; offset {reg.coef["offset"]:+.3g})', i))
        if ok('viscous_friction', 'viscous_friction') and \
                ax.viscous_friction + reg.coef['viscous_friction'] > 0:
            fv = ax.viscous_friction + reg.coef['viscous_friction']
            ch['viscous_friction'] = fv
            effects.append(Effect('viscous_friction', ax.name, reg.partial_r2['viscous_friction'],
                                  {'viscous_friction': fv},
                                  f'residual proportional to velocity: '
                                  f'{reg.coef["viscous_friction"]:+.4g} per unit velocity (t = '
                                  f'{reg.tstat["viscous_friction"]:.1f}; explains '
                                  f'{100 * reg.partial_r2["viscous_friction"]:.0f} %)', i))
        if reg.ripple and reg.ripple_peak_ratio >= 30 and \
                reg.partial_r2.get('torque_ripple', 0) >= MIN_R2 and reg.ripple[0]['t'] >= MIN_T:
            r = reg.ripple[0]
            rip = list(ax.torque_ripple) + [{k: r[k] for k in ('amplitude', 'spatial_frequency',
                                                               'phase')}]
            ch['torque_ripple'] = rip
            effects.append(Effect('torque_ripple', ax.name, reg.partial_r2['torque_ripple'],
                                  {'torque_ripple': rip},
                                  f'residual periodic in position, amplitude {r["amplitude"]:.3g} at '
                                  f'spatial frequency {r["spatial_frequency"]:.4g} 1/rad', i))
        dj = reg.coef.get('inertia', 0.0)
        if ok('inertia', 'inertia') and abs(dj) > 0.05 * jtot:
            jm = max(ax.motor_inertia + dj, 1e-6 * jtot)
            ch['motor_inertia'] = jm
            effects.append(Effect('parameter_mismatch', ax.name, reg.partial_r2['inertia'],
                                  {'motor_inertia': jm},
                                  f'residual proportional to acceleration: inertia '
                                  f'{jtot:.4g} -> {jtot + dj:.4g} (t = {reg.tstat["inertia"]:.1f})', i))
        ext_axes[i] = replace(ax, **ch)
        # predictions on the whole record: baseline = nominal + offset/nuisance fitted on the
        # fit part; extended = nominal + all accepted terms fitted on the fit part
        s = reg.ripple[0]['spatial_frequency'] if 'torque_ripple' in ch else 0.0
        X = _design(f[:, i], qh[:, i], vh[:, i], ah[:, i], fs, fc, nu, s)
        ff = lowpass(f[:, i], fs, fc)
        n_nu = 0 if nu is None else nu.shape[1]
        base_cols = [0] + list(range(4, 4 + n_nu))
        use = base_cols + [c for c, k in ((1, 'coulomb_friction'), (2, 'viscous_friction'),
                                          (3, 'motor_inertia')) if k in ch]
        if s:
            use += [X.shape[1] - 2, X.shape[1] - 1]
        for key, cols in (('baseline', base_cols), ('extended', sorted(use))):
            c, *_ = np.linalg.lstsq(X[fit_m][:, cols], ff[fit_m], rcond=None)
            pred[key][:, i] = X[:, cols] @ c
    effects.sort(key=lambda e: -e.score)
    ext = replace(robot, axes=ext_axes)
    uf = lowpass(rec.effort[:-1], fs, fc)
    ff_all = lowpass(f, fs, fc)
    metrics: dict[str, Any] = {}
    for key in ('baseline', 'extended'):
        u_model = uf - ff_all + pred[key]          # nominal inverse dynamics + fitted terms
        e = (uf - u_model)[val_m]
        den = np.sqrt(np.mean((uf[val_m] - uf[val_m].mean(0)) ** 2))
        metrics[key] = {'frf_error_db': round(_frf_error(rec.velocity[:-1][val_m],
                                                         uf[val_m], u_model[val_m], fs), 4),
                        'time_nrmse': round(float(np.sqrt(np.mean(e ** 2)) / den), 5)}
    metrics['validation'] = (f'fitted on the first {100 * fit_fraction:.0f} % of the record '
                             f'(0-{rec.t[n_fit]:.2f} s), validated on the remaining '
                             f'{rec.t[-1] - rec.t[n_fit]:.2f} s; time_nrmse = error of the '
                             f'inverse-dynamics torque over the RMS of the measured torque '
                             f'({fc:g} Hz low-pass)')
    return {'effects': effects, 'extended': ext, 'metrics': metrics, 'regressions': details,
            'residual': {'t': rec.t[:-1], 'f': f, 'q': qh, 'v': vh,
                         'pred_baseline': pred['baseline'], 'pred_extended': pred['extended'],
                         'val_mask': val_m}}


def _frf_error(v: np.ndarray, u_meas: np.ndarray, u_model: np.ndarray, fs: float) -> float:
    """RMS dB difference of the Welch H1 estimates u_meas -> v and u_model -> v."""
    out = []
    nper = int(min(2 ** int(math.log2(max(v.shape[0] // 4, 64))), 4096))
    for i in range(v.shape[1]):
        fr, pm = signal.csd(u_meas[:, i], v[:, i], fs=fs, nperseg=nper)
        _, uu = signal.welch(u_meas[:, i], fs=fs, nperseg=nper)
        _, pmod = signal.csd(u_model[:, i], v[:, i], fs=fs, nperseg=nper)
        _, mm = signal.welch(u_model[:, i], fs=fs, nperseg=nper)
        _, coh = signal.coherence(u_meas[:, i], v[:, i], fs=fs, nperseg=nper)
        sel = (coh > 0.5) & (fr > 0) & (fr < 20)
        if sel.any():
            out.append(20 * np.log10(np.abs((pm[sel] / uu[sel]) / (pmod[sel] / mm[sel]))))
    v_ = np.concatenate(out) if out else np.array([np.nan])
    return float(np.sqrt(np.mean(v_ ** 2)))
