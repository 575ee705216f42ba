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
The closing stages of the experiments route: the held-out check and what follows it.

Kept effects the held-out data do not ask for are dropped (:func:`held_out_check`), a
parameter mismatch that leaves its axis above its floor is withdrawn as missing structure
(:func:`structure_missing`), and :func:`finish` ranks the effects and takes the metrics.
"""
from __future__ import annotations

from dataclasses import replace
import logging
import math

from frf_ident.core.fit.residual_whiteness import ResidualBand
from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
import numpy as np

from .acceptance import left_unexplained
from .evaluator import frf_estimates, replace_segments
from .noise_gain import held_out_gain, HeldOutGain
from .refit import FRICTION, rebuild, refit_friction, refit_jointly
from .resonance_bands import bands_left, resonance_bands, with_p95
from .rigid_axes import rigid_in_band
from .search import named, Search
from .structure import model_bands
from .unexplained import (axis_signature, discretisation_check, rival_instead,
                          typical_unscalable_misfit)
from ..common import Effect
from ..records import Rejected, RouteMetrics, Unexplained
from ..result import DiagnosisResult, ExperimentsDetail
from ..thresholds import UNEXPLAINED_RATIO

__all__ = ['finish', 'held_out_check', 'partners_without', 'rejected_entry',
           'structure_left', 'structure_missing']

log = logging.getLogger(__name__)


def held_out_check(s: Search) -> tuple[np.ndarray, Recording]:
    """
    Drop every kept effect whose removal does not worsen its axis' held-out misfit.

    Judged only where the held-out part could show the effect (:attr:`.HeldOutGain.can_show`:
    its predicted gain, were the model with it the truth, beyond noise): a held-out part that
    cannot show it says nothing for or against it, and the fit part judges it instead by the
    same paired test at the values it has now, unless the held-out part speaks against it
    (:attr:`.HeldOutGain.against`); it is dropped where the model without it refitted fits the
    fit part as well.

    A friction term is checked against the axis' other friction term refitted without it (the
    two were fitted together, so the partner left at its value cannot show what the data need
    without it); so is a parameter mismatch of the axis, whose joint damping dissipates like
    viscous friction: both are refitted jointly by simulation without the term. With its
    partners refitted, the model without the term may fit even the fit part better: then the
    data do not ask for it either.

    Returns
    -------
    (ndarray, Recording)
        The held-out misfit per axis of the extended model and its simulation.

    """
    ev, robot, kept = s.ev, s.robot, s.kept
    sim_ext = ev.simulate(s.ext)
    val_ext = ev.held_out_misfit(s.ext, sim_ext)
    for c in list(kept):
        others = [k for k in kept if k is not c]
        refit = partners_without(s, c, others)
        alt = [refit.get(id(k), k) for k in others]
        i = c.axis_index
        without = rebuild(robot, alt)
        v = ev.held_out_misfit(without)
        v_fit = ev.misfit(ev.terms(without))[i] if refit else math.inf
        g = s.gains[id(c)] = held_out_gain(ev, s.ext, without, i)
        if g.held_out and not g.can_show and not g.against:
            # the held-out part could not show it were it true: the fit part judges it, at
            # the values it has now (a later refit may have taken it to nothing); a record
            # without a held-out part was judged on the fit part already
            g = s.gains[id(c)] = held_out_gain(ev, s.ext, without, i, held_out=False)
            if v_fit > s.cur[i] and g.beyond_noise:
                s.say(f"  kept {c.axis} {c.name} on the fit part's evidence: the held-out "
                      f'part cannot show it ({g.describe()})')
                continue
        if v[i] <= val_ext[i] or v_fit <= s.cur[i] or not g.beyond_noise:
            s.say(f'  dropped {c.axis} {c.name}: misfit without it held out '
                  f'{v[i]:.4g} (with it {val_ext[i]:.4g}; {g.describe()}), fitted {v_fit:.4g} '
                  f'(with it {s.cur[i]:.4g})'
                  + ''.join(f' ({r.name} refitted without it: ' + ', '.join(
                      f'{k} {x:.4g}' for k, x in r.parameters.items()
                      if isinstance(x, (int, float))) + ')' for r in refit.values()))
            kept.remove(c)
            c.gain = 0.0
            for k in others:
                if id(k) in refit:
                    k.parameters, k.evidence = refit[id(k)].parameters, refit[id(k)].evidence
    if len(kept) != len([c for c in s.cands if c.score > 0]):
        s.ext = rebuild(robot, kept)
        sim_ext = ev.simulate(s.ext)
        val_ext = ev.held_out_misfit(s.ext, sim_ext)
    log.info('held-out check: %s', named(kept))
    return val_ext, sim_ext


def partners_without(s: Search, c: Effect, others: list[Effect]) -> dict[int, Effect]:
    """Return the partners of a friction term refitted without it (by id), else nothing."""
    ev, robot = s.ev, s.robot
    refit: dict[int, Effect] = {}
    if c.name not in FRICTION:
        return refit
    for p in others:
        if p.axis_index == c.axis_index and p.name in FRICTION:
            refit[id(p)] = refit_friction(
                ev, rebuild(robot, [k for k in others if k is not p]), p, local=True)
    if any(p.axis_index == c.axis_index and p.name == 'parameter_mismatch' for p in others):
        mine = {id(k): replace(refit.get(id(k), k)) for k in others
                if k.axis_index == c.axis_index}
        trial = [mine.get(id(k), k) for k in others]
        refit_jointly(ev, robot, trial, c.axis_index,
                      ev.misfit(ev.terms(rebuild(robot, trial))), s.say)
        refit.update(mine)
    return refit


def structure_missing(s: Search, val_ext: np.ndarray, sim_ext: Recording
                      ) -> tuple[np.ndarray, Recording, np.ndarray]:
    """
    Withdraw a parameter mismatch that leaves its axis clearly above its floor.

    A mismatch claims the axis' linear parameters are off; if the axis stays clearly above its
    floor with them refitted, the model lacks structure there (an unmodelled resonance near the
    first one looks like a softer joint): the axis is reported unexplained, or the spring
    rival the mismatch won over takes its place where it explains the axis
    (:func:`.unexplained.rival_instead`). Clearly above: a share of the misfit left, an FRF
    no rescale of the axis' linear parameters brings near the measured one on the typical
    line, or a band of its FRF residual (:func:`_band_left`): a mode the model lacks leaves
    a few lines far off, which the typical line does not see. Not withdrawn: a spring read on
    a joint the model holds rigid (stage 0b, :mod:`.rigid_axes`), which adds structure.

    Returns
    -------
    (ndarray, Recording, ndarray)
        Held-out misfit per axis of the extended model, its simulation, and the held-out
        misfit of the nominal model.

    """
    ev, robot, kept = s.ev, s.robot, s.kept
    val_base = ev.held_out_misfit(robot, s.sim0)
    lacking = []
    for c in kept:
        # a spring read on a joint the model holds rigid (stage 0b) adds the resonance the
        # model lacked, it rescales nothing: withdrawn for what it leaves, the axis would lose
        # the resonance it explains (the demo's MuJoCo iiwa 14: joint4's spring 7,903 N m/rad
        # for 8,000, held out 1.49 -> 0.93 with it, withdrawn for the motor damping it leaves);
        # what it leaves is reported unexplained beside it
        if c.name != 'parameter_mismatch' or (rigid_in_band(robot, c.axis_index)
                                              and 'stiffness' in c.parameters):
            continue
        why = structure_left(s, c.axis_index, s.ext, sim_ext, val_ext, val_base)
        if why is None:
            continue
        s.say(f'  {c.axis} parameter_mismatch not named: the axis stays at '
              f'{val_ext[c.axis_index]:.4g} x its floor with it ({why}): structure missing, '
              f'not parameters')
        lacking.append(c)
    for c in lacking:
        trial = rival_instead(ev, robot, kept, c, s.rivals, val_base, s.say)
        new = trial if trial is not None else [k for k in kept if k is not c]
        for k in kept:
            if all(k is not x for x in new):
                k.gain = 0.0
        kept[:] = new
    if lacking:
        s.ext = rebuild(robot, kept)
        sim_ext = ev.simulate(s.ext)
        val_ext = ev.held_out_misfit(s.ext, sim_ext)
    return val_ext, sim_ext, val_base


def structure_left(s: Search, axis: int, model: RobotParams, sim: Recording, val: np.ndarray,
                   val_base: np.ndarray) -> str | None:
    """
    Return why a model's parameter mismatch leaves its axis lacking structure, in words.

    None where it does not: the axis' held-out misfit ``val`` left is no share of the
    nominal's ``val_base`` that calls it unexplained, a rescale of its linear parameters
    brings its FRF near the measured one on the typical line, and its FRF residual leaves no
    band (:func:`_band_left`). ``sim`` is the simulation of ``model``.
    """
    # the share rule first: the FRF test costs the estimates of the simulation
    if left_unexplained(val, val_base, axis):
        return 'its share of the nominal misfit'
    off = typical_unscalable_misfit(s.ev, sim, axis, model)
    band = _band_left(s, sim, axis, model)
    if off <= UNEXPLAINED_RATIO and band is None:
        return None
    return (f'its FRF {off:.3g} x on the typical line with the parameters refitted'
            if band is None else f'its FRF residual leaves {band.text()}')


def _band_left(s: Search, sim: Recording, axis: int, model: RobotParams
               ) -> ResidualBand | None:
    """
    Return the strongest band of missing structure a model leaves on an axis, or None.

    The model's multisine residual on the fit part, its linear parameters refitted, where
    stage 0 found a band (:func:`.structure.model_bands`): a band of at least MODE_MIN_LINES
    lines UNEXPLAINED_RATIO times its noise. A parameter change is named only where the
    residual left after it has none.
    """
    bands = model_bands(s.ev.meas_fit, s.ev.fit_estimates(model, sim), model, s.structure)
    left = [b for b in bands[axis] if b.excess >= UNEXPLAINED_RATIO]
    return left[0] if left else None


def finish(s: Search, val_ext: np.ndarray, sim_ext: Recording, val_base: np.ndarray,
           moved: bool = False) -> DiagnosisResult:
    """
    Check the step, rank the effects, list the unexplained axes and take the metrics.

    ``moved``: the last settling (:func:`.settle.final_errors`) moved values since the
    held-out check simulated the extended model; it is simulated again, so the integrator
    check, the unexplained axes and the metrics are those of the model written. The
    integrator check (:func:`.unexplained.discretisation_check`) may raise the extended
    model's substeps; the model is then simulated and judged at the step it is written with.
    """
    ev, robot, kept = s.ev, s.robot, s.kept
    if moved:
        sim_ext = ev.simulate(s.ext)
        val_ext = ev.held_out_misfit(s.ext, sim_ext)
    step = discretisation_check(ev, s.ext, val_ext)
    if step.written_substeps != step.substeps:
        # two lines: the axes' numbers made a 200-character line
        log.info('simulation.substeps = %d is too coarse for this record: the extended model '
                 'is written with %d\n    held-out misfit at twice as many substeps [noise '
                 'floors]: %s', step.substeps, step.written_substeps, ', '.join(
                     f'{a} {x:.4g} -> {y:.4g}' for a, x, y in zip(
                         step.axes, step.held_out_misfit, step.held_out_misfit_double_substeps)
                     if a in step.too_coarse))
        s.ext = replace(s.ext, substeps=step.written_substeps)
        sim_ext = ev.simulate(s.ext)
        val_ext = ev.held_out_misfit(s.ext, sim_ext)
    ext = s.ext
    kept.sort(key=lambda c: -c.score)
    unexplained = []
    for i, a in enumerate(robot.axes):
        if left_unexplained(val_ext, val_base, i):
            share = float(np.clip((val_ext[i] - 1) / max(val_base[i] - 1, 1e-12), 0, 1))
            unexplained.append(Unexplained(a.name, axis_signature(ev, sim_ext, i, ext),
                                           misfit_share=round(share, 3)))
    nominal, sim_nominal = robot, s.sim0
    misfit = {'baseline': val_base.tolist(), 'extended': val_ext.tolist()}
    if s.nominal is not None:
        # the search read against the record's sensor; the report's nominal is the file
        nominal, sim_nominal = s.nominal, ev.simulate(s.nominal)
        misfit['without_sensor'] = ev.held_out_misfit(nominal, sim_nominal).tolist()
    part = ev.val if ev.val.segments else ev.fit
    plots = {'measured': ev.meas_val or ev.meas_fit,
             'nominal': frf_estimates(replace_segments(sim_nominal, part)),
             'extended': frf_estimates(replace_segments(sim_ext, part))}
    unexplained += bands_left(ev.meas_fit, ev.fit_estimates(ext, sim_ext), ext, s.structure)
    metrics = RouteMetrics(
        with_p95(ev.metrics(nominal, sim_nominal), plots['measured'], plots['nominal']),
        with_p95(ev.metrics(ext, sim_ext), plots['measured'], plots['extended']),
        ev.validation_text, resonance_bands(ext, kept, unexplained, plots))
    log.info('%d simulations of the recorded excitation', ev.n_sims)
    rest = [c for c in s.cands if c not in kept]
    for c in kept:
        if id(c) in s.gains:
            c.evidence += f'; {s.gains[id(c)].describe()}'
    return DiagnosisResult(
        'experiments', kept, [rejected_entry(c, s.gains.get(id(c))) for c in rest], unexplained,
        metrics, ext,
        ExperimentsDetail(ev, plots, {'nominal': sim_nominal, 'extended': sim_ext}, misfit,
                          {f'{c.name}@{c.axis}': s.gains[id(c)] for c in kept + rest
                           if id(c) in s.gains}),
        ev.fit_mask[:-1], (ev.val_mask if ev.val_mask.any() else ev.fit_mask)[:-1],
        discretisation=step, n_sims=ev.n_sims, candidates=rest)


def rejected_entry(c: Effect, gain: HeldOutGain | None = None) -> Rejected:
    """
    Return the report.json ``rejected`` entry of a candidate that was not taken.

    One the simulator cannot hold carries the rule's ``reason`` (``c.reason``); one whose
    values the record does not determine says which; one the held-out check dropped for a
    gain within noise carries that as its ``reason``.
    """
    if c.reason is not None:
        return Rejected(c.name, c.axis, c.to_dict()['parameters'] or None, reason=c.reason)
    if c.not_determined:
        reason = 'not determined by this record: ' + '; '.join(
            f'{n.parameter} {n.reason}' for n in c.not_determined)
    else:
        reason = (f'{gain.describe()}: within what the noise alone gives, dropped'
                  if gain is not None and not gain.beyond_noise else None)
    return Rejected(c.name, c.axis, c.to_dict()['parameters'], reason=reason,
                    misfit_share_removed=round(float(c.gain), 4))
