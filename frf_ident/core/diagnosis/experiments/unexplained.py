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
Report what the extended model leaves unexplained, and check the simulation's step.

Where the held-out residual of an axis lives (FRF bands no rescale of the linear parameters
removes, the signal its torque residual follows), the rival that replaces a parameter
mismatch that leaves its axis unexplained, and the discretisation check.
"""
from __future__ import annotations

from dataclasses import replace
import math
from typing import Callable

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.analytic import robot_frf_sampled
import numpy as np

from .acceptance import left_unexplained
from .candidates import fit_linear_scales, LIN_KEYS, scaled_axis
from .evaluator import Evaluator, frf_estimates, replace_segments
from .refit import rebuild, refit_jointly
from ..common import diag_ratio, Effect, SPRING_SHAPES
from ..records import IntegratorCheck, Signature
from ..thresholds import BAND_SHARE, CORRELATES_MIN, MAX_BANDS, MAX_SUBSTEPS, MIN_Z, SHOWN


def residual_bands(lines: list[tuple[np.ndarray, np.ndarray]]) -> list[list[float]]:
    """
    Return the bands [f1, f2] Hz where a misfit per line concentrates, strongest first.

    The estimates (multisine, chirp: each its own line grid) are independent experiments,
    and a misfit counts where all of them show it: on the union of the line grids within the
    range every estimate covers, each estimate contributes its own line's misfit, or between
    two of its lines the larger of the two (a narrow peak is seen on offset grids), and the
    smallest contribution is taken. One experiment's outlying line (a noisy line, a
    chirp-only artefact next to a resonance) then does not crowd out a misfit all show; only
    where no frequency's misfit is shown by all (at least ``SHOWN`` above the floor: twice
    the noise), the largest any shows is taken. A band is the run of lines around a local
    maximum while they stay above a quarter of it (half its amplitude in dB), plus one line
    each side; further bands are taken around the largest remaining lines as long as they
    reach a quarter of the strongest. A resonance the model lacks reshapes the whole FRF of
    its axis (the neighbouring resonance and antiresonance move too), so its own band need
    not be the strongest.

    Parameters
    ----------
    lines : list of (ndarray, ndarray)
        Per estimate the line frequencies [Hz] (ascending) and the misfit above the noise floor
        per line (>= 0).

    Returns
    -------
    list of [float, float]
        At most MAX_BANDS bands; empty when no line is above the floor.

    """
    f, wt = _misfit_all_show(lines)
    top = float(wt.max(initial=0.0))
    if top <= 0:
        return []
    found = []                                   # (lo, hi, peak)
    free = np.ones(f.size, bool)
    while free.any():
        k = int(np.argmax(np.where(free, wt, -1.0)))
        if wt[k] < BAND_SHARE * top:
            break
        lo, hi = k, k
        while lo > 0 and free[lo - 1] and wt[lo - 1] >= BAND_SHARE * wt[k]:
            lo -= 1
        while hi < f.size - 1 and free[hi + 1] and wt[hi + 1] >= BAND_SHARE * wt[k]:
            hi += 1
        free[max(lo - 1, 0):hi + 2] = False
        found.append([float(f[max(lo - 1, 0)]), float(f[min(hi + 1, f.size - 1)]),
                      float(wt[k])])
    return [[round(b[0], 2), round(b[1], 2)] for b in found[:MAX_BANDS]]


def _misfit_all_show(lines: list[tuple[np.ndarray, np.ndarray]]
                     ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the union of the line grids where all estimates cover it, and the misfit all show.

    Where no line's misfit is shown by all estimates (SHOWN above the noise floor), the largest
    any estimate shows.
    """
    lines = [(f, w) for f, w in lines if f.size]
    if not lines:
        return np.zeros(0), np.zeros(0)
    grid = np.unique(np.concatenate([f for f, _ in lines]))
    grid = grid[(grid >= max(f[0] for f, _ in lines)) & (grid <= min(f[-1] for f, _ in lines))]
    seen = np.empty((len(lines), grid.size))
    for j, (f, w) in enumerate(lines):
        k = np.searchsorted(f, grid)
        between = np.maximum(w[np.maximum(k - 1, 0)], w[k])
        seen[j] = np.where(f[k] == grid, w[k], between)
    out = seen.min(axis=0)
    return grid, out if out.max(initial=0.0) >= SHOWN else seen.max(axis=0)


def unscalable_misfit(ev: Evaluator, sim: Recording, axis: int, ext: RobotParams
                      ) -> list[tuple[np.ndarray, np.ndarray]]:
    """
    Return the held-out FRF misfit of one axis that no linear rescale of it removes.

    The axis' inertias, stiffness and damping are refitted to the measured FRF
    (P_meas/P_sim times the analytic FRF of ``ext``: the estimator bias and the effects the
    simulation already models cancel), and the misfit left per line is in units of the line
    noise floor. A shifted antiresonance is a parameter question and goes; a resonance the
    model lacks stays.

    Parameters
    ----------
    ev : Evaluator
        The recording and its noise floors.
    sim : Recording
        The simulation of ``ext`` on the recorded excitation.
    axis : int
        The axis.
    ext : RobotParams
        The model.

    Returns
    -------
    list of (ndarray, ndarray)
        Per estimate (multisine, chirp) the line frequencies [Hz] and |ln(P_meas/P_refit)|^2
        over the noise floor per line (1 = at noise).

    """
    meas = ev.meas_val if ev.meas_val else ev.meas_fit
    part = ev.val if ev.val.segments else ev.fit
    floors = ev.floors_held if ev.meas_val else ev.floors
    est = frf_estimates(replace_segments(sim, part))
    ratio = {k: diag_ratio(pm, est[k])[axis] for k, pm in meas.items()}
    scaled = {k: replace(pm, response=pm.response * 0 + 0j) for k, pm in meas.items()}
    for k, pm in meas.items():
        scaled[k].response[axis, axis] = ratio[k] * robot_frf_sampled(ext, pm.freq_hz)[axis, axis]
    x = fit_linear_scales(scaled, ext, axis)
    refit = scaled_axis(ext, axis, LIN_KEYS, x)
    out = []
    for k, pm in meas.items():
        f_ = pm.freq_hz
        r = np.abs(np.log(ratio[k] * robot_frf_sampled(ext, f_)[axis, axis]
                          / robot_frf_sampled(refit, f_)[axis, axis])) ** 2
        out.append((f_, r / floors[k][axis]))
    return out


def typical_unscalable_misfit(ev: Evaluator, sim: Recording, axis: int, ext: RobotParams
                              ) -> float:
    """
    Return the typical line's :func:`unscalable_misfit` (noise floors).

    The median over the lines of each estimate, averaged over the estimates: about 1 when a
    rescale of the axis' linear parameters brings its FRF to the measured one, well above
    where a resonance is missing. The median lets the few lines next to a resonance, whose
    noise is far above the axis' mean floor, pass.
    """
    return float(np.mean([np.median(r) for _, r in unscalable_misfit(ev, sim, axis, ext)]))


def axis_signature(ev: Evaluator, sim: Recording, axis: int, ext: RobotParams) -> Signature:
    """
    Return where the held-out residual of one axis lives.

    Where the held-out residual of one axis lives: the bands [f1, f2] Hz of the FRF misfit
    above noise that is left after refitting the axis' inertias, stiffness and damping to the
    measured FRF (:func:`residual_bands` of :func:`unscalable_misfit`; ``band_hz`` the
    strongest, ``bands_hz`` all), and the signal the torque residual of the extended model
    correlates with most (|r| >= 0.3).
    """
    fr, w = [], []
    for f_, r in unscalable_misfit(ev, sim, axis, ext):
        fr.append(f_)
        w.append(np.maximum(r - 1.0, 0.0))
    bands = residual_bands(list(zip(fr, w)))
    m = ev.val_mask if ev.val_mask.any() else ev.fit_mask
    res = (ev.rec.effort[:, axis] - sim.effort[:, axis])[m]
    sigs = {'position': ev.rec.position[:, axis], 'velocity': ev.rec.velocity[:, axis],
            'acceleration': np.gradient(ev.rec.velocity[:, axis], ev.rec.dt),
            'time': ev.rec.t}
    best, rbest = None, CORRELATES_MIN
    for name, x in sigs.items():
        xm = x[m] - x[m].mean()
        den = math.sqrt(float(xm @ xm) * float((res - res.mean()) @ (res - res.mean())))
        r = abs(float(xm @ (res - res.mean())) / den) if den > 0 else 0.0
        if r >= rbest:
            best, rbest = name, r
    return Signature(band_hz=bands[0] if bands else None, bands_hz=bands or None,
                     correlates_with=best)


def discretisation_check(ev: Evaluator, robot: RobotParams, val: np.ndarray
                         ) -> IntegratorCheck:
    """
    Return how much the model's held-out misfit owes to the integrator's step.

    The plant's error is first order in the substep where friction sticks or backlash closes
    (benchmarks/discretisation.py): part of every misfit the diagnosis computes is the
    integrator's. The model is simulated once more at twice ``simulation.substeps``; an axis
    whose held-out misfit moves by more than MIN_Z standard deviations of the misfit under
    noise is simulated too coarsely for this record. The substeps are then doubled for as long
    as doubling moves some axis and lowers the held-out misfit of every axis it moves (at most
    MAX_SUBSTEPS): the extended model is written with that step, so a user never has to raise
    it by hand. Where doubling still moves an axis but not every moved axis down, the rest of
    the misfit is not the integrator's alone (``settled`` False).

    Parameters
    ----------
    ev : Evaluator
        The recording's evaluator.
    robot : RobotParams
        The model (the extended one).
    val : ndarray, shape (n_axes,)
        Its held-out misfit per axis at its own substeps.

    Returns
    -------
    IntegratorCheck
        The model's axis names, its substeps, the held-out misfit per axis at both steps, the
        axes whose misfit moved and the substeps the extended model is written with.

    """
    def misfit_at(n: int) -> np.ndarray:
        return ev.held_out_misfit(replace(robot, substeps=n))
    n = int(robot.substeps)
    fine = misfit_at(2 * n)
    moved = np.abs(fine - val) > MIN_Z * ev.misfit_sd()
    written, now, finer, move = n, val, fine, moved
    # halve the step while that moves some axis and lowers the misfit of every axis it moves
    while move.any() and np.all(finer[move] < now[move]) and 2 * written <= MAX_SUBSTEPS:
        written, now = 2 * written, finer
        if 2 * written > MAX_SUBSTEPS:
            break
        finer = misfit_at(2 * written)
        move = np.abs(finer - now) > MIN_Z * ev.misfit_sd()
    return IntegratorCheck(robot.joint_names, n, [round(float(x), 4) for x in val],
                           [round(float(x), 4) for x in fine],
                           [a.name for a, m in zip(robot.axes, moved) if m], written,
                           settled=not move.any())


def rival_instead(ev: Evaluator, base: RobotParams, kept: list[Effect], pm: Effect,
                  rivals: dict[int, list[Effect]], val_base: np.ndarray,
                  say: Callable[[str], None]) -> list[Effect] | None:
    """
    Return the kept effects with a parameter mismatch's lost rival in its place, or None.

    A parameter mismatch that wins the held-out duel against a stiffening gear or a backlash
    while a coupled axis still lacks its own effect (rescaled linear parameters absorb what
    the link coupling carries over, a nonlinear spring cannot) and that leaves its axis
    unexplained in the end had the wrong rival win. Each lost spring rival in turn replaces
    the mismatch and the spring effects its axis took after it, the axis' effects are refitted
    jointly, and the first that leaves the axis no longer unexplained on the held-out data is
    taken.

    Parameters
    ----------
    ev : Evaluator
        The recording's evaluator.
    base : RobotParams
        The nominal model.
    kept : list of Effect
        The kept effects (not changed).
    pm : Effect
        The parameter mismatch that leaves its axis unexplained.
    rivals : dict
        Per axis the candidates that lost a held-out duel (:func:`accept`).
    val_base : ndarray
        Held-out misfit per axis of the nominal model.
    say : callable
        Progress lines.

    Returns
    -------
    list of Effect or None
        The new kept effects (the rival's parameters refitted), None when no rival explains
        the axis.

    """
    i = pm.axis_index
    for r in rivals.get(i, []):
        if r.name not in SPRING_SHAPES:
            continue
        out = [k for k in kept if k.axis_index != i
               or (k is not pm and k.name not in SPRING_SHAPES)]
        trial = [replace(k) for k in out] + [replace(r)]
        ext, _ = refit_jointly(ev, base, trial, i,
                               ev.misfit(ev.terms(rebuild(base, trial))), say)
        val = ev.held_out_misfit(ext)
        say(f'  {pm.axis}: {r.name} (the rival the parameter mismatch won over) in its place: '
            f'held-out misfit {val[i]:.4g} x its floor')
        if not left_unexplained(val, val_base, i):
            for k, t in zip(out + [r], trial):
                k.parameters = t.parameters
            r.score = float(np.clip(r.gain, 0.0, 1.0))
            r.evidence += ('; named in place of a parameter mismatch that had won over it on '
                           'the held-out data but left the axis unexplained')
            return out + [r]
    return None
