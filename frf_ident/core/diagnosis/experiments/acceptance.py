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
Decide which candidate effects a model takes: the acceptance rule and the greedy rounds.

An effect is taken when it removes at least MIN_SHARE of its axis' misfit above the noise
floor and the drop exceeds MIN_Z standard deviations of the misfit under noise, or, paired,
MIN_Z standard errors of the drop itself (:func:`passes`).
"""
from __future__ import annotations

from dataclasses import replace
from typing import Callable

from frf_ident.core.model.params import RobotParams
import numpy as np

from .evaluator import Evaluator
from .noise_gain import held_out_gain, HeldOutGain
from .refit import FRICTION, rebuild, refit_friction, refit_jointly
from ..common import apply_effect, Effect, SPRING_SHAPES
from ..thresholds import DOMINANT_SHARE, MIN_SHARE, MIN_Z, REFIT_T, UNEXPLAINED_RATIO


def share_of_misfit(ev: Evaluator, cur: np.ndarray, new: np.ndarray, i: int
                    ) -> tuple[float, float]:
    """
    Return the drop of axis i's misfit from ``cur`` to ``new`` and its share above the floor.

    Parameters
    ----------
    ev : Evaluator
        The recording's evaluator (its floor takes ``new`` into its record).
    cur, new : ndarray
        Misfit per axis without and with the change.
    i : int
        The axis.

    Returns
    -------
    (float, float)
        The drop and its share of the misfit above the floor (0 for an axis at its floor).

    """
    gain = float(cur[i] - new[i])
    fl = ev.floor_seen(new)[i]
    return gain, (gain / (cur[i] - fl) if cur[i] > fl else 0.0)


def passes(ev: Evaluator, gain: float, share: float,
           paired: Callable[[], HeldOutGain] | None = None,
           say: Callable[[str], None] | None = None) -> bool:
    """
    Return the acceptance rule: share >= MIN_SHARE and a drop beyond the noise.

    The drop is beyond the noise where it exceeds MIN_Z standard deviations of the misfit
    under noise alone, or else, with ``paired`` (the two models' paired test on the fit
    part, :func:`.noise_gain.held_out_gain` with ``held_out=False``), where it exceeds
    MIN_Z standard errors of the paired differences. The first is the spread of one model's
    misfit, not of the difference of two models judged on the same data: on an axis at its
    noise floor a real effect's drop is a small part of it (sensor scene 15162288 of
    benchmarks/diagnosis_sensor.py: a viscous friction of 47 for the nominal 25, read at
    39, dropped the misfit by 0.071 against 3 x 0.045). The paired spread holds only the
    noise's cross term with the change: a parameter fitted to noise alone gets a z of
    about half a standard normal (|sum n g| / (2 sigma |g|)), so under noise alone the
    second route adds no false alarm of its own. A change that takes part of another
    effect's signature passes it (a test of the direction, not of the name): the
    per-axis duel and the held-out check (:mod:`.held_out`) judge such rivals on data
    they were not fitted on.
    """
    if share < MIN_SHARE:
        return False
    if not within_spread(ev, gain, share):
        return gain > 0.0
    if paired is None:
        return False
    g = paired()
    if say is not None:
        say(f'    drop under {MIN_Z:g} sd of the misfit; paired: {g.describe()}')
    return g.beyond_noise


def within_spread(ev: Evaluator, gain: float, share: float) -> bool:
    """Return whether a drop that passes the share is within the misfit's spread (> 0)."""
    return share >= MIN_SHARE and 0.0 < gain < MIN_Z * ev.misfit_sd()


def _refit_first(ev: Evaluator, c: Effect, cur: np.ndarray, rnd: int) -> bool:
    """Return whether a friction candidate is refitted by simulation before it is judged."""
    return bool(rnd and c.name in FRICTION
                and cur[c.axis_index] > UNEXPLAINED_RATIO * ev.floor_seen(cur)[c.axis_index])


def accept(ev: Evaluator, base: RobotParams, kept: list[Effect], cands: list[Effect],
           cur: np.ndarray, say: Callable[[str], None],
           rivals: dict[int, list[Effect]] | None = None) -> tuple[RobotParams, np.ndarray]:
    """
    Accept candidate effects greedily per axis.

    Greedy per axis: in each round every axis takes its candidate that removes the largest
    share of the axis' misfit above noise (own-axis attribution: a small effect on a weak axis
    competes only with that axis' misfit), if the share is >= MIN_SHARE and the drop exceeds
    MIN_Z standard deviations of the misfit under noise. The rest are re-evaluated on top.
    A candidate of an effect already kept on its axis (a friction level read again with the
    axis' time delay) is a new value for it: taken, it replaces the kept one. Where two
    candidates of one axis pass, the held-out data decide; the one that lost goes to
    ``rivals[axis]`` when given (:func:`.unexplained.rival_instead`).
    """
    ext = rebuild(base, kept)
    pending = list(cands)
    taken: set[tuple[str, str]] = set()
    rnd = 0
    while pending:
        ev.prefetch([apply_effect(ext, c) for c in pending if not _refit_first(ev, c, cur, rnd)])
        scored = [(c.gain, c) for c in pending if judge(ev, ext, c, cur, rnd, say)]
        best = pick_per_axis(ev, ext, scored, rivals, say)
        if not best:
            break
        take(best, kept, taken, say)
        ext = rebuild(base, kept)
        cur = ev.misfit(ev.terms(ext))
        ext, cur = refit_dominant_friction(ev, base, kept, best, ext, cur, say)
        pending = [c for c in (without_stiffness(c, best.get(c.axis_index)) for c in pending)
                   if c is not None and c.axis_index in best and c not in best.values()
                   and (c.name, c.axis) not in taken]
        rnd += 1
    return ext, cur


def without_stiffness(c: Effect, took: Effect | None) -> Effect | None:
    """
    Return a pending candidate as it stands once its axis took ``took``.

    A parameter mismatch pending on an axis that took a spring shape (a stiffening gear, a
    backlash) loses its stiffness part: that spring now holds the axis' stiffness, and the
    linear FRF fit that read the mismatch cannot see a stiffness depending on the
    deflection, so the part would count the spring twice (pair scene 284825 of
    benchmarks/diagnosis_uncertainty.py: with a stiffness x1.11 read beside the stiffening
    gear, the damping read with it, 396 for a true 369, lost the held-out duel to a viscous
    friction of 146 for the nominal 10). None where nothing is left; anything else as it is.
    """
    if (took is None or took.name not in SPRING_SHAPES or c.name != 'parameter_mismatch'
            or c.axis_index != took.axis_index or 'stiffness' not in c.parameters):
        return c
    rest = {k: v for k, v in c.parameters.items() if k != 'stiffness'}
    if not rest:
        return None
    return replace(c, parameters=rest,
                   evidence=c.evidence + f'; its stiffness part dropped once the axis took '
                                         f'a {took.name} (which holds the stiffness)')


def judge(ev: Evaluator, ext: RobotParams, c: Effect, cur: np.ndarray, rnd: int,
          say: Callable[[str], None]) -> bool:
    """
    Simulate candidate ``c`` on top of ``ext``; set its gain and return whether it passes.

    A friction candidate of an axis still clearly above its floor after a round is refitted
    by simulation first (:func:`_refit_first`); one the regression clearly sees whose value
    makes the simulation worse is refitted around its reading; and one whose drop is within
    the misfit's spread, left to the paired test of :func:`passes`, is judged at its
    refitted value too.
    """
    i = c.axis_index
    refitted = _refit_first(ev, c, cur, rnd)
    if refitted:
        # its axis took an effect and is still clearly above its floor: the value the
        # regression read next to the unmodelled effect is refitted by simulation
        r = refit_friction(ev, ext, c, local=True)
        c.parameters, c.evidence = r.parameters, r.evidence
    e_c = ev.misfit(ev.terms(apply_effect(ext, c)))
    gain, share = share_of_misfit(ev, cur, e_c, i)
    if not refitted and share < MIN_SHARE and c.name in FRICTION and c.support >= REFIT_T:
        # the regression clearly sees the friction term but its value makes the
        # simulation worse: a sticking joint's breakaway transients bias the
        # inverse-dynamics residual at small speeds (a Coulomb level read twice too
        # high with a negative viscous term); the closed-loop simulation sticks
        # like the robot, so the level is refitted by it around the reading (over the
        # whole range when the reading left the physical range and was floored at 0)
        e_c, refitted = _refit_if_better(ev, ext, c, e_c, say), True
        gain, share = share_of_misfit(ev, cur, e_c, i)
    if not refitted and c.name in FRICTION and within_spread(ev, gain, share):
        # a drop within the misfit's spread goes to the paired test, which judges the
        # friction at its best value, not the regression's first reading (sensor scene
        # 15162298 of benchmarks/diagnosis_sensor.py: a viscous friction of 46 read at 62
        # lost to a Coulomb level of 0.4 that only stood in for it)
        e_c = _refit_if_better(ev, ext, c, e_c, say)
        gain, share = share_of_misfit(ev, cur, e_c, i)
    c.gain = float(share)
    say(f'  {c.axis} {c.name}: misfit {cur[i]:.4g} -> {e_c[i]:.4g} '
        f'(share {share:.3f}) {c.parameters}')
    return passes(ev, gain, share,
                  lambda: held_out_gain(ev, apply_effect(ext, c), ext, i, held_out=False), say)


def _refit_if_better(ev: Evaluator, ext: RobotParams, c: Effect, e_c: np.ndarray,
                     say: Callable[[str], None]) -> np.ndarray:
    """Refit friction ``c`` by simulation around its value; keep the refit where it is better."""
    i = c.axis_index
    r = refit_friction(ev, ext, c, local=True)
    e_r = ev.misfit(ev.terms(apply_effect(ext, r)))
    say(f'  {c.axis} {c.name} {c.parameters[c.name]:.4g} (t = {c.support:.1f}) '
        f'refitted by simulation: {r.parameters[c.name]:.4g}, misfit '
        f'{e_c[i]:.4g} -> {e_r[i]:.4g}')
    if e_r[i] < e_c[i]:
        c.parameters, c.evidence = r.parameters, r.evidence
        return e_r
    return e_c


def pick_per_axis(ev: Evaluator, ext: RobotParams, scored: list[tuple[float, Effect]],
                  rivals: dict[int, list[Effect]] | None, say: Callable[[str], None]
                  ) -> dict[int, Effect]:
    """
    Return per axis the passing candidate with the largest share; rivals go to ``rivals``.

    Rivals on one axis (a stiffening spring and a mismatched linear stiffness both explain a
    stiffer joint): the held-out data decide between the two best.
    """
    best: dict[int, Effect] = {}
    by_axis: dict[int, list[Effect]] = {}
    for share, c in sorted(scored, key=lambda x: -x[0]):
        by_axis.setdefault(c.axis_index, []).append(c)
    for i, cs in by_axis.items():
        if len(cs) == 1:
            best[i] = cs[0]
            continue
        held = [float(ev.held_out_misfit(apply_effect(ext, c))[i])
                for c in cs[:2]]
        best[i] = cs[int(np.argmin(held))]
        if rivals is not None:
            rivals.setdefault(i, []).append(cs[1 - int(np.argmin(held))])
        say(f'  {cs[0].axis}: {cs[0].name} vs {cs[1].name} on held-out data: '
            f'{held[0]:.4g} vs {held[1]:.4g}')
    return best


def take(best: dict[int, Effect], kept: list[Effect], taken: set[tuple[str, str]],
         say: Callable[[str], None]) -> None:
    """Add the round's best candidates to ``kept``; one of an effect kept already replaces it."""
    for c in best.values():
        c.score = float(np.clip(c.gain, 0.0, 1.0))
        for k in [k for k in kept if k.name == c.name and k.axis == c.axis]:
            say(f'  {k.axis} {k.name} {k.parameters} replaced by {c.parameters}')
            k.score, k.gain = 0.0, 0.0
            kept.remove(k)
        kept.append(c)
        taken.add((c.name, c.axis))


def refit_dominant_friction(ev: Evaluator, base: RobotParams, kept: list[Effect],
                            best: dict[int, Effect], ext: RobotParams, cur: np.ndarray,
                            say: Callable[[str], None]) -> tuple[RobotParams, np.ndarray]:
    """
    Refit by simulation a friction just taken that explains most of its axis but not all.

    A friction coefficient read from the regression that explains most of its axis' misfit
    but leaves it clearly above the floor is refitted by simulation before anything else may
    explain the rest (a Coulomb level 4 % off otherwise lets a spurious viscous term in);
    where another effect dominates, the joint refit at the end does it.
    """
    fl = ev.floor_seen(cur)
    for c in best.values():
        i = c.axis_index
        if (c.name not in FRICTION or c.gain < DOMINANT_SHARE
                or cur[i] <= UNEXPLAINED_RATIO * fl[i]):
            continue
        r = refit_friction(ev, rebuild(base, [k for k in kept if k is not c]), c, local=True)
        trial = rebuild(base, [r if k is c else k for k in kept])
        new = ev.misfit(ev.terms(trial))
        if new[i] < cur[i]:
            say(f'  {c.axis} {c.name} refitted by simulation: {c.parameters[c.name]:.4g} -> '
                f'{r.parameters[c.name]:.4g}, misfit {cur[i]:.4g} -> {new[i]:.4g}')
            c.parameters, c.evidence = r.parameters, r.evidence
            ext, cur = trial, new
    return ext, cur


def gravity_with_shape(ev: Evaluator, base: RobotParams, kept: list[Effect], cand: Effect,
                       cur: np.ndarray, say: Callable[[str], None]
                       ) -> tuple[RobotParams, np.ndarray]:
    """
    Offer a gravity candidate with its axis' FRF-shape effects refitted jointly beside it.

    A load G sin(q + phi) sets the gear's deflection at every position. A stiffening spring or
    a backlash fitted while the model lacked the load has absorbed that shift; offered on top
    of it, the right load worsens the axis. Of the stage-1 candidates only the load acts on
    the link side: friction and ripple act at the motor and leave the gear's static deflection
    alone, so they are offered on top. The candidate is added, the axis' kept effects are
    refitted jointly by simulation (:func:`.refit.refit_jointly`), and the pair replaces the
    axis' effects if it passes the acceptance rule of :func:`accept` against the model
    without the load (:func:`passes`).

    Parameters
    ----------
    ev : Evaluator
        The recording's evaluator.
    base : RobotParams
        The nominal model.
    kept : list of Effect
        The kept effects, updated in place when the candidate is taken.
    cand : Effect
        The gravity candidate (stage 1).
    cur : ndarray
        Misfit per axis of the model of ``kept``.
    say : callable
        Progress lines.

    Returns
    -------
    (RobotParams, ndarray)
        The extended model and its misfit per axis.

    """
    i = cand.axis_index
    trial = [replace(k) if k.axis_index == i else k for k in kept] + [replace(cand)]
    with_load = ev.misfit(ev.terms(rebuild(base, trial)))
    ext, new = refit_jointly(ev, base, trial, i, with_load, say, gravity=True)
    gain, share = share_of_misfit(ev, cur, new, i)
    say(f"  {cand.axis} gravity with the axis' effects refitted beside it: misfit "
        f'{cur[i]:.4g} -> {with_load[i]:.4g} on top, {new[i]:.4g} refitted (share {share:.3f})')
    without = rebuild(base, kept)
    if not passes(ev, gain, share,
                  lambda: held_out_gain(ev, ext, without, i, held_out=False), say):
        return without, cur
    cand.parameters = trial[-1].parameters
    cand.gain = cand.score = float(np.clip(share, 0.0, 1.0))
    for k, t in zip(kept, trial):
        k.parameters = t.parameters
    kept.append(cand)
    return ext, new


def left_unexplained(val_ext: np.ndarray, val_base: np.ndarray, i: int) -> bool:
    """Return true when axis i's held-out misfit stays clearly above its noise floor."""
    share = (val_ext[i] - 1) / max(val_base[i] - 1, 1e-12)
    return bool(val_ext[i] > UNEXPLAINED_RATIO and share >= MIN_SHARE)
