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
Diagnose identification recordings (multisine on constant velocity + iterated chirps).

Every candidate effect is fitted from the evidence it leaves (:mod:`.candidates`), then the
candidate model is simulated on the recorded excitation through the same controller and
estimated exactly like the measurement (:class:`.evaluator.Evaluator`). Its gain is the share
of its own axis' misfit above the noise floor that it removes (:mod:`.acceptance`). The
pipeline, :func:`diagnose_experiments`, is a sequence of named stages acting on one
:class:`.search.Search`; the closing ones (held-out check, missing structure, the result) are
in :mod:`.held_out`.
"""
from __future__ import annotations

from dataclasses import replace
import logging
import math

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.errors import EstimationError
import numpy as np

from .acceptance import accept
from .candidates import (coupled_ripples, fit_backlash, fit_coulomb, fit_gravity,
                         fit_parameter_mismatch, fit_ripple, fit_stiffness_nonlinearity,
                         fit_time_delay, fit_viscous, friction_regression, LIN_KEYS,
                         ripple_again, stiffness_seen, with_params)
from .dissipation_reading import damping_or_viscous
from .evaluator import Evaluator
from .frequency_fit import fd_parameter_mismatch, linear_shifts, load_dependence, shifts_text
from .held_out import finish, held_out_check, structure_missing
from .later_passes import friction_after_refit, joint_refits, late_ripples, second_pass
from .mode_search import search_left_modes
from .quantisation_floor import add_quantisation_floor
from .refit import refit_friction, refit_jointly
from .rigid_axes import rigid_axes, rigid_in_band
from .search import named, Search
from .second_mode import refine_modes, take_second_mode
from .settle import final_errors, settle, within_nominal
from .spring_reading import gap_or_stiffening
from .structure import read_structure
from .unheld import not_held, spring_shapes_skipped
from ..common import apply_effect, Effect, Simulator, SPRING_SHAPES
from ..result import DiagnosisResult
from ..sensor import describe_sensor, with_lacking_sensor
from ..thresholds import MIN_DELAY_SAMPLES, SIM_JOBS, STAGE2_ROUNDS

__all__ = ['diagnose_experiments']

log = logging.getLogger(__name__)


def diagnose_experiments(rec: Recording, robot: RobotParams, ctrl: PIVelocity, *,
                         jobs: int = SIM_JOBS, fd_fit: bool = True,
                         simulator: Simulator | None = None) -> DiagnosisResult:
    """
    Diagnose an identification recording against the nominal ``robot``.

    Every candidate is judged on its own axis' misfit (noise floors). First (stage 0) a linear
    parameter mismatch the frequency-domain physical fit of the measured FRFs shows at both loads
    (:mod:`.frequency_fit`), so the later stages start from the model with it; then the
    torque-residual effects (Coulomb and viscous friction, torque ripple, gravity) from one joint
    regression per axis; then, against the simulation of that model, the FRF-shape effects (time
    delay, parameter mismatch, stiffening, backlash), so friction does not pose as stiffness. A
    second pass, joint refits, a second mode fitted by simulation where an axis stays
    unexplained (:mod:`.mode_search`), a stiffening gear read in place of a mismatched stiffness
    a spring shape bends (:mod:`.spring_reading`) and a gear damping read in place of a viscous
    friction or the other way round (:mod:`.dissipation_reading`) follow; then every value's
    standard error (a parameter that has not settled is refitted jointly with those it trades
    against, else labelled not determined) and the held-out check (effects within their errors
    of the nominal or not needed are dropped).

    Parameters
    ----------
    rec : Recording
        The identification recording (with its velocity reference).
    robot : RobotParams
        The nominal model.
    ctrl : PIVelocity
        The velocity controller the recording ran through.
    jobs : int
        Processes that simulate independent models at once (1: one after the other; the
        same result either way).
    fd_fit : bool
        Run stage 0 (default); False: the mismatch is read in stage 2 only (the path before
        issue 40 item 5, kept for the before/after benchmark).
    simulator : Simulator, optional
        What simulates the candidate models (:class:`..common.Simulator`); default our plant
        (:func:`..common.simulate_like`).

    Returns
    -------
    DiagnosisResult
        Mode 'experiments', with :class:`..result.ExperimentsDetail`.

    Notes
    -----
    A few lines per stage at INFO level (logger ``frf_ident.core.diagnosis.*``), the search
    trace (candidates' misfits before and after, refits, held-out duels) at DEBUG level.

    """
    s = start(rec, robot, ctrl, jobs, simulator)
    try:
        if fd_fit:
            frequency_domain_fit(s)
        rigid_axes(s)
        take_second_mode(s)
        torque_residual_effects(s)
        frf_shape_effects(s)
        second_pass(s)
        joint_refits(s)
        friction_after_refit(s)
        late_ripples(s)
        search_left_modes(s)
        refine_modes(s)
        gap_or_stiffening(s)
        damping_or_viscous(s)
        settled = settle(s)
        within_nominal(s, settled)
        val_ext, sim_ext = held_out_check(s)
        val_ext, sim_ext, val_base = structure_missing(s, val_ext, sim_ext)
        moved = final_errors(s, settled)
        return finish(s, val_ext, sim_ext, val_base, moved)
    finally:
        s.ev.close()


def start(rec: Recording, robot: RobotParams, ctrl: PIVelocity, jobs: int = SIM_JOBS,
          simulator: Simulator | None = None) -> Search:
    """Build the evaluator and simulate the nominal model: its misfit per axis."""
    if rec.reference is None:
        raise EstimationError('recording has no velocity reference: use the time-series '
                              'diagnosis')
    ev = Evaluator(rec, ctrl, jobs=jobs, simulator=simulator)
    given = robot       # its simulation is sim0 where the record shows no sensor it lacks
    robot = with_lacking_sensor(rec, given, ev.simulate(given))
    if robot is not given:
        log.info('the record shows its sensor (%s): the search reads every effect against '
                 'the model with it', describe_sensor(given, robot))
    if ev.missing.any():
        log.info('%.1f %% of the samples lack a reference (or follow such a stretch): left '
                 'out of the comparison', 100 * ev.missing.mean())
    sim0 = ev.simulate(robot)
    added = add_quantisation_floor(ev, robot)
    if added:
        log.info('encoder quantisation added to the noise floors (the record repeats it with '
                 'the period): %s', '; '.join(
                     f'{k} ' + ', '.join(f'{a.name} {d / max(f, 1e-300):.2f}' for a, d, f in
                                         zip(robot.axes, added[k], ev.floors[k] - added[k]))
                     for k in added))
    ev.base_terms = ev.terms(robot, sim0)
    e0 = ev.misfit(ev.base_terms)
    ev.floor_seen(e0)
    log.info('nominal misfit per axis (1 = noise floor): %s (noise sd %.3g)', ', '.join(
        f'{a.name} {v:.4g}' for a, v in zip(robot.axes, e0)), ev.misfit_sd())
    return Search(ev, robot, log.debug, sim0, robot, e0,
                  nominal=given if robot is not given else None)


def frequency_domain_fit(s: Search) -> None:
    """
    Stage 0: take a linear parameter mismatch or a second mode the FRF fits show.

    The physical fit of the measured multisine and chirp FRFs against the same fit of the nominal
    simulation (:func:`.frequency_fit.linear_shifts`); an axis whose inertias or stiffness differ
    at both loads, with a spring stage 2 would call linear (:func:`.frequency_fit.load_dependence`)
    and a residual the linear parameters leave white (:func:`.structure.read_structure`), gets a
    ``parameter_mismatch`` candidate (:func:`.frequency_fit.fd_parameter_mismatch`). Where the
    residual has a band, a second mode fitted there may explain it
    (:func:`.second_mode.take_second_mode`, offered after stage 0b's springs of the rigid axes: a
    spring's resonance couples into its neighbours' FRFs). Each is judged by simulation.
    """
    ev, robot = s.ev, s.robot
    sim_est = ev.fit_estimates(robot, s.sim0)
    shifts = linear_shifts(ev.meas_fit, sim_est, robot)
    load = load_dependence(ev.meas_fit, sim_est, robot)
    s.say(shifts_text(shifts, load, robot))
    s.structure = read_structure(ev.meas_fit, sim_est, robot)
    if s.structure is not None:
        s.say('stage 0 residual of the linear fit (multisine against the nominal simulation): '
              + s.structure.text(robot.joint_names))
    s.stage0 = [c for c in (fd_parameter_mismatch(shifts, robot, i, load[i])
                            for i in range(robot.n_axes)
                            # a rigid axis has no motor/link split to rescale: rigid_axes reads it
                            if not rigid_in_band(robot, i)
                            and (s.structure is None or s.structure.white(i)))
                if c is not None]
    if s.stage0:
        s.ext, s.cur = accept(ev, robot, s.kept, s.stage0, s.cur, s.say)
    s.cands += s.stage0
    log.info('stage 0 (frequency-domain fit): %d candidate(s), %s', len(s.stage0), named(s.kept))


def torque_residual_effects(s: Search) -> None:
    """
    Stage 1: read friction, ripple and gravity from the residual regression and take them.

    Read against the model so far (the nominal one, or the stage-0 mismatch taken).

    A ripple candidate that is another axis' ripple carried over by the link coupling
    (:func:`.candidates.coupled_ripples`) is not offered.
    """
    ev, robot, ext = s.ev, s.robot, s.ext
    resolution = np.full(robot.n_axes, math.inf)
    for i in range(robot.n_axes):
        reg = friction_regression(ev, ext, i)
        resolution[i] = reg.ripple_resolution
        s.say(f'{robot.axes[i].name}: residual regression '
              f'{ {k: round(v, 4) for k, v in reg.coef.items()} }, ripple scan peak '
              f'{reg.ripple_peak_ratio:.1f} (threshold {reg.ripple_threshold:.1f})')
        for e in [fn(reg, ext, i) for fn in (fit_coulomb, fit_viscous, fit_ripple)] + [
                fit_gravity(ev, ext, i)]:
            if e is not None and not_held(s, e) is None:
                s.stage1.append(e)
    for c in coupled_ripples(s.stage1, robot.link_inertia_matrix(), resolution):
        s.stage1.remove(c)
        c.evidence += ('; at the spatial frequency of a stronger ripple on another axis, '
                       'within what the link coupling carries from it: not taken')
        s.cands.append(c)
        s.say(f'  {c.axis} torque_ripple: the link coupling of a ripple on another axis, '
              f'not taken')
    s.ext, s.cur = accept(s.ev, robot, s.kept, s.stage1, s.cur, s.say)
    s.cands += s.stage1
    log.info('stage 1 (torque residual): %d candidate(s), %s', len(s.stage1), named(s.kept))


def frf_shape_effects(s: Search) -> None:
    """
    Stage 2: read the FRF-shape effects against the model so far and take them, in rounds.

    An axis that took an effect is read again on top of it (a time delay hides a backlash's
    load dependence), at most STAGE2_ROUNDS rounds. An FRF-shape effect fitted on top of what
    the axis took before is refitted jointly with it before the axis is read again.
    """
    ev, robot = s.ev, s.robot
    stage2_all: list[Effect] = []
    axes = set(range(robot.n_axes))
    for rnd in range(STAGE2_ROUNDS):
        sim_est = ev.fit_estimates(s.ext)
        stage2 = [c for found in axis_candidates(s, sorted(axes), sim_est) for c in found]
        s.stage2_read += stage2
        n_kept = len(s.kept)
        s.ext, s.cur = accept(ev, robot, s.kept, stage2, s.cur, s.say, s.rivals)
        stage2_all = [c for c in stage2_all if c in s.kept or not any(
            c.name == e.name and c.axis == e.axis for e in stage2)] + stage2
        axes = {c.axis_index for c in s.kept[n_kept:]}
        for i in sorted(axes):
            if any(c.axis_index == i for c in s.kept[:n_kept]):
                s.ext, s.cur = refit_jointly(ev, robot, s.kept, i, s.cur, s.say)
        if not axes or rnd == STAGE2_ROUNDS - 1:
            break
    s.stage2 = stage2_all
    s.cands += stage2_all
    log.info('stage 2 (FRF shape): %d candidate(s), %s', len(stage2_all), named(s.kept))


def _values(params: dict) -> str:
    """Return parameters as 'key value' pairs for an evidence line."""
    return ', '.join(f'{k} {v:.4g}' for k, v in params.items())


def axis_candidates(s: Search, axes: list[int], sim_est: dict) -> list[list[Effect]]:
    """
    Return :func:`frf_shape_candidates` of each axis, one axis after the other.

    The searches inside an axis (a stiffening's simplex, a backlash's grid) hand their models
    to the evaluator's workers. One axis usually holds all of a round's searches (demo bag:
    joint_2's stiffening, 35 of 37 simulations): forked one per axis, that axis ran alone on
    one core while the other idled.
    """
    return [frf_shape_candidates(s, i, sim_est) for i in axes]


def frf_shape_candidates(s: Search, i: int, sim_est: dict) -> list[Effect]:
    """
    Return axis i's FRF-shape candidates of one round, against the model so far.

    Time delay, parameter mismatch, stiffening and backlash from the stiffness the multisine
    (low load) and the chirp (high load) see against the model so far; friction read again with
    a delay long enough to bias it; viscous friction as the rival of a joint-damping mismatch
    (both dissipate in proportion to a velocity: where both pass, the held-out data decide);
    and a ripple the stage-1 scan saw but the axis did not take, read again on top of the model
    so far (offered only after the FRF-shape candidates, a backlash and a viscous term took its
    torque and it then worsened the axis).
    """
    ev, ext, kept = s.ev, s.ext, s.kept
    s_ms, s_ch = (stiffness_seen(ev.meas_fit, sim_est, ext, i, k)
                  for k in ('multisine', 'chirp'))
    s.say(f'{s.robot.axes[i].name}: stiffness seen by multisine x{math.exp(s_ms):.3f}, '
          f'chirp x{math.exp(s_ch):.3f} (against the model so far)')
    taken = {k.name for k in kept if k.axis_index == i}
    # the delay and the mismatch are FRF fits whose values serve the re-reads below; the
    # simulation fits of a stiffening or a backlash are not run for an axis that took one (it
    # is not offered again below), nor for an axis rigid in the band (no spring to bend or
    # rescale: rigid_axes reads it) or where the simulator cannot hold them
    skip = spring_shapes_skipped(s, i, s_ms, s_ch) | taken
    # a spring shape taken holds the axis' stiffness: a mismatch is read without it
    lin = tuple(k for k in LIN_KEYS if k != 'stiffness' or not taken & set(SPRING_SHAPES))
    found = [fit_time_delay(ev, sim_est, ext, i),
             None if rigid_in_band(ext, i) else fit_parameter_mismatch(ev, ext, i, s_ms, s_ch,
                                                                       lin),
             None if 'stiffness_nonlinearity' in skip
             else fit_stiffness_nonlinearity(ev, ext, i, s_ms, s_ch),
             None if 'backlash' in skip else fit_backlash(ev, ext, i, s_ms, s_ch)]
    out: list[Effect] = []
    td = found[0]
    if (td is not None and td.parameters['time_delay'] - ext.axes[i].time_delay
            > MIN_DELAY_SAMPLES * ev.rec.dt):
        # the stage-1 regression ran against an undelayed model, which biases viscous friction
        # (a joint-damping mismatch then poses as the rest) and Coulomb friction (the command
        # acts later than the reversal it answers); a Coulomb level kept from stage 1 is
        # offered again as its delayed re-read: left at its biased value, a spurious viscous
        # term absorbs the difference
        reg = friction_regression(ev, with_params(ext, i, time_delay=td.parameters[
            'time_delay']), i)
        redo = [e for e in (fit_coulomb(reg, ext, i), fit_viscous(reg, ext, i))
                if e is not None]
        for e in redo:
            e.evidence = 'read again with the time delay: ' + e.evidence
        out += redo
    pm = found[1]
    if (pm is not None and 'damping' in pm.parameters and not any(
            k.name == 'viscous_friction' and k.axis_index == i for k in kept)
            and ev.misfit(ev.terms(apply_effect(ext, pm)))[i] < s.cur[i]):
        # the regression next to FRF-shape effects or coupled axes is biased: the rival is
        # viscous friction refitted by simulation over its whole range
        vc = next((e for e in out if e.name == 'viscous_friction' and e.axis_index == i), None)
        if vc is not None:
            out.remove(vc)
        else:
            vc = Effect('viscous_friction', ext.axes[i].name, 0.0,
                        {'viscous_friction': ext.axes[i].viscous_friction},
                        'rival of the joint-damping mismatch (both dissipate in '
                        'proportion to a velocity)', i)
        out.append(refit_friction(ev, ext, vc))
    for e in found:
        if e is None:
            continue
        old = next((k for k in kept if k.name == e.name and k.axis == e.axis), None)
        if old is None:
            out.append(e)
        elif e.name == 'parameter_mismatch':
            # a mismatch kept already (stage 0 reads stiffness and inertias): the reading on
            # top of it is a new value for it, what it kept and what is read now together;
            # without it the viscous rival above was offered alone (pair scene 284807: a
            # viscous friction of 179 named for a joint-damping mismatch never offered)
            out.append(replace(e, parameters={**old.parameters, **e.parameters},
                               evidence=e.evidence + f'; read on top of the mismatch kept '
                                                     f'({_values(old.parameters)})'))
    r = ripple_again(ev, ext, i, s.stage1, kept)
    if r is not None:
        out.append(r)
    return out
