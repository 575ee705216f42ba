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
Settle the values of the experiments route, and say which ones the record does not determine.

Three stages of :func:`.pipeline.diagnose_experiments` around the held-out check:

- :func:`settle`: every kept effect's parameters get standard errors from the linearised
  simulation fit (:mod:`.standard_errors`). A scale whose error exceeds NOT_DETERMINED_SHARE
  of its value, or whose refits on the multisine alone and on the chirp alone disagree
  beyond REFITS_AGREE_Z combined errors, is refitted jointly with the parameters of its axis
  it trades against (correlation >= TRADE_CORRELATION), a Gauss-Newton step on the Jacobian
  already simulated, up to SETTLE_ROUNDS times; one that its joint refit would still move by
  more than REFITS_AGREE_Z errors when the rounds run out has not settled either.
- :func:`within_nominal`: an effect each of whose parameters lies within NOMINAL_Z standard
  errors of the nominal model's value is dropped before the held-out check: the record
  cannot tell it from the nominal model.
- :func:`final_errors`: after the held-out check the errors are written on the effects
  (taken again where the check refitted them); what has not settled is labelled not
  determined (:func:`..determination.not_determined`) and its effect's score is 0.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .refit import built, loss_of, rebuild
from .search import Search
from .standard_errors import axis_fit, AxisFit, effects_with, model_with
from ..common import Effect
from ..determination import labelled, not_determined, share_text
from ..records import NotDetermined
from ..thresholds import (NOMINAL_Z, NOT_DETERMINED_SHARE, OFF_OPTIMUM_Z, REFITS_AGREE_Z,
                          SETTLE_ROUNDS, TRADE_CORRELATION)

__all__ = ['final_errors', 'settle', 'Settled', 'within_nominal']

#: a Gauss-Newton refit keeps a scale within this factor of its value (the log-scale
#: refits of .refit move from there too)
_MAX_FACTOR = 5.0


@dataclass
class Settled:
    """What :func:`settle` leaves for the later stages, per axis."""

    fits: dict[int, AxisFit] = field(default_factory=dict)
    #: per axis the values each parameter's refits took, by (effect id, parameter)
    seen: dict[int, dict[tuple[int, str], list[float]]] = field(default_factory=dict)
    #: per axis its kept effects' parameters at the fit (changed: the fit is taken again)
    snapshot: dict[int, str] = field(default_factory=dict)
    #: the axes whose last joint refit was taken when the rounds ran out (still moving)
    moving: set[int] = field(default_factory=set)


def _key(fit: AxisFit, j: int) -> tuple[int, str]:
    return id(fit.slots[j].effect), fit.slots[j].label


def _snapshot(kept: list[Effect], axis: int) -> str:
    return repr([(c.name, c.parameters) for c in kept if c.axis_index == axis])


def unsettled(fit: AxisFit, *, disagree: bool = False, moving: bool = False
              ) -> dict[int, list[str]]:
    """
    Return per scale slot that has not settled the reasons, in words.

    Its error exceeds NOT_DETERMINED_SHARE of its value; with ``moving`` (the joint refits
    ran out of rounds while still lowering the misfit), a scalar parameter the linearised
    refit would still move by more than REFITS_AGREE_Z of its errors within the record and by
    more than NOT_DETERMINED_SHARE of its value (a smaller move widens its error in ``fit.se``
    to the move instead); with
    ``disagree`` also where its refits on the multisine alone and on the chirp alone differ
    by more than REFITS_AGREE_Z combined errors (a reason to refit it jointly; their spread is
    then part of its error, so it alone leaves a value determined).
    """
    z = fit.disagreement()
    out: dict[int, list[str]] = {}
    for j, sl in enumerate(fit.slots):
        if not sl.magnitude:
            continue
        why = []
        if not fit.se[j] <= NOT_DETERMINED_SHARE * abs(sl.value):
            why.append(share_text(sl.value, float(fit.se[j])))
        if disagree and z[j] > REFITS_AGREE_Z:
            (a, _), (b, _) = fit.alone.values()
            why.append(f'its refits on the multisine alone ({a[j]:.4g}) and on the chirp '
                       f'alone ({b[j]:.4g}) differ by {z[j]:.1f} combined standard errors')
        step = abs(fit.optimum[j] - sl.value)
        if moving and sl.field is None and step > REFITS_AGREE_Z * fit.within[j]:
            if max(float(fit.se[j]), step) <= NOT_DETERMINED_SHARE * abs(sl.value):
                # still moving, by a small share of itself: determined to that share, its
                # error widened to the move (a stiffening breakpoint moving 1.2 % at 8 errors
                # was labelled not determined beside a gravity load it traded with)
                fit.se[j] = max(float(fit.se[j]), step)
            else:
                why.append(f'its joint refit still moves it, to {fit.optimum[j]:.4g} '
                           f'({step / fit.within[j]:.1f} standard errors)')
        if why:
            out[j] = why
    return out


def settle(s: Search) -> Settled:
    """Take the standard errors of every axis with kept effects; refit what has not settled."""
    out = Settled()
    for i in range(s.robot.n_axes):
        if any(c.axis_index == i for c in s.kept):
            settle_axis(s, i, out)
    return out


def settle_axis(s: Search, i: int, out: Settled) -> None:
    """
    :func:`settle` of one axis.

    Each round refits jointly, by one Gauss-Newton step, the scales that have not settled
    (:func:`unsettled`; in the first round also those whose refits on each experiment alone
    disagree) with their partners, and every scalar parameter the search left more than
    OFF_OPTIMUM_Z errors from the linearised optimum (not a ripple's or a load's term: the
    search leaves those where their reading put them, see :func:`.refit.refit_jointly`);
    then linearises again. It settles where no step is left to take or none lowers the misfit.
    """
    fit = axis_fit(s.ev, s.robot, s.kept, i)
    if fit is None:
        return
    seen = out.seen.setdefault(i, {})
    _note(seen, fit)
    _trace(s, i, fit)
    out.moving.discard(i)
    for rnd in range(SETTLE_ROUNDS + 1):
        loose = unsettled(fit, disagree=rnd == 0)
        off = [j for j, sl in enumerate(fit.slots) if sl.field is None
               and abs(fit.optimum[j] - sl.value) > OFF_OPTIMUM_Z * fit.within[j]]
        if not loose and not off:
            break
        if rnd == SETTLE_ROUNDS:
            out.moving.add(i)
            break
        # a step that does not lower the misfit: the values sit at its optimum (where the
        # linearisation points elsewhere, its distance is part of their errors)
        if joint_step(s, i, fit, list(loose), off) is None:
            break
        fit = axis_fit(s.ev, s.robot, s.kept, i)
        _note(seen, fit)
        _trace(s, i, fit)
    out.fits[i] = fit
    out.snapshot[i] = _snapshot(s.kept, i)


def _trace(s: Search, i: int, fit: AxisFit) -> None:
    """Say each slot's value, standard error and refits on each experiment alone."""
    s.say(f'  {s.robot.axes[i].name}: standard errors ' + ', '.join(
        f'{sl.label} {sl.value:.4g} +- {fit.se[j]:.3g} (within {fit.within[j]:.3g}, step '
        f'bias {fit.step_bias[j]:.3g}, '
        f'linearised optimum {fit.optimum[j]:.4g})' + ''.join(
            f' ({k} alone {a[j]:.4g} +- {e[j]:.3g})' for k, (a, e) in fit.alone.items())
        for j, sl in enumerate(fit.slots)))


def _note(seen: dict[tuple[int, str], list[float]], fit: AxisFit) -> None:
    """Add the slots' values and their refits on each experiment alone to ``seen``."""
    for j, sl in enumerate(fit.slots):
        vals = [sl.value] + [float(a[j]) for a, _ in fit.alone.values() if np.isfinite(a[j])]
        seen.setdefault(_key(fit, j), []).extend(vals)


def joint_step(s: Search, i: int, fit: AxisFit, loose: list[int], off: list[int] = ()
               ) -> list[int] | None:
    """
    Refit the loose scales jointly with their partners: one Gauss-Newton step (or half of it).

    The partners are the axis' scales whose estimates correlate with a loose one by at least
    TRADE_CORRELATION; the scales ``off`` their optimum join. The step is taken where it
    lowers the axis' misfit; a scale moves at most by a factor _MAX_FACTOR. Returns the slots
    refitted, or None when nothing was taken.
    """
    corr = np.nan_to_num(fit.correlation())
    scales = [j for j, sl in enumerate(fit.slots) if sl.magnitude]
    part = sorted({k for j in loose for k in scales
                   if k == j or abs(corr[j, k]) >= TRADE_CORRELATION} | set(off))
    J = fit.jacobian[:, part]
    dx = np.linalg.lstsq(J, -fit.residual, rcond=None)[0]
    x0 = fit.values()
    h = np.array([sl.step for sl in fit.slots])
    move = np.zeros(x0.size)
    move[part] = dx * h[part]
    # keep every scale within _MAX_FACTOR of its value (and on its side of 0)
    ratio = np.where(x0 != 0, (x0 + move) / np.where(x0 != 0, x0, 1.0), 1.0)
    shrink = [float((1 / _MAX_FACTOR - 1) / (r - 1)) for r in ratio if r < 1 / _MAX_FACTOR]
    shrink += [float((_MAX_FACTOR - 1) / (r - 1)) for r in ratio if r > _MAX_FACTOR]
    move *= min([1.0] + shrink)
    trial = [x0 + move, x0 + 0.5 * move]
    models = [built(model_with, s.robot, s.kept, fit.slots, x) for x in trial]
    s.ev.prefetch([m for m in models if m is not None])
    now = s.ev.loss(rebuild(s.robot, s.kept), i)
    loss = [loss_of(s.ev, m, i) for m in models]
    b = int(np.argmin(loss))
    names = [', '.join(fit.slots[j].label for j in js) or 'nothing' for js in (loose, off)]
    s.say(f'  {s.robot.axes[i].name}: {names[0]} unsettled, {names[1]} off its optimum; '
          'refitted jointly: ' + ', '.join(fit.slots[j].label for j in part)
          + f': misfit {now:.4g} -> {loss[b]:.4g} at ' + ', '.join(
              f'{fit.slots[j].label} {trial[b][j]:.4g}' for j in part))
    if not loss[b] < now:
        return None
    p = effects_with(fit.slots, trial[b])
    for c in s.kept:
        if id(c) in p:
            c.parameters = p[id(c)]
    s.ext = rebuild(s.robot, s.kept)
    s.cur = s.ev.misfit(s.ev.terms(s.ext))
    return part


def within_nominal(s: Search, out: Settled) -> None:
    """
    Drop an effect each of whose parameters lies within NOMINAL_Z standard errors of nominal.

    The nominal value of a parameter is the nominal model's (a stiffening gear's k2: the
    linear stiffness; a term's amplitude: 0); a parameter without one (a breakpoint) does not
    count. The effect keeps a not-determined entry per parameter saying so (the reason of
    its ``rejected`` entry).
    """
    dropped = []
    for i, fit in out.fits.items():
        axis = s.robot.axes[i]
        for c in [c for c in s.kept if c.axis_index == i]:
            near = []
            for j, sl in enumerate(fit.slots):
                if sl.effect is not c or not sl.magnitude:
                    continue
                nom = _nominal(axis, sl.key, sl.field)
                if nom is None:
                    continue
                near.append((sl, fit.se[j], abs(sl.value - nom) <= NOMINAL_Z * fit.se[j], nom))
            if near and all(n[2] for n in near):
                c.not_determined = [not_determined(
                    sl.label, sl.value, float(se),
                    f'within {NOMINAL_Z:g} standard errors ({se:.3g}) of the nominal {nom:.4g}')
                    for sl, se, _, nom in near]
                dropped.append(c)
    for c in dropped:
        s.say(f'  dropped {c.axis} {c.name}: within {NOMINAL_Z:g} standard errors of the '
              f'nominal model')
        s.kept.remove(c)
        c.gain = c.score = 0.0
    if dropped:
        s.ext = rebuild(s.robot, s.kept)
        s.cur = s.ev.misfit(s.ev.terms(s.ext))


def _nominal(axis: Any, key: str, fld: str | None) -> float | None:
    """Return the nominal model's value of a parameter (None: it has none to compare)."""
    if fld is not None:
        return 0.0 if fld == 'amplitude' else None
    if key == 'stiffness_k2':
        return float(axis.stiffness_k2 or axis.stiffness)
    v = getattr(axis, key, None)
    return float(v) if isinstance(v, (int, float)) and key != 'stiffness_breakpoint' else None


def final_errors(s: Search, out: Settled) -> bool:
    """
    Write the standard errors on the kept effects; label what has not settled.

    An axis whose effects the held-out check or a rival changed since :func:`settle` (a
    friction partner refitted without a dropped term) is settled again at its new values.
    Returns whether that moved the extended model (then its held-out misfit is stale).
    """
    judged = s.ext
    for i in range(s.robot.n_axes):
        if not any(c.axis_index == i for c in s.kept):
            continue
        if i not in out.fits or out.snapshot.get(i) != _snapshot(s.kept, i):
            settle_axis(s, i, out)
            if i not in out.fits:
                continue
        fit = out.fits[i]
        loose = unsettled(fit, moving=i in out.moving)
        errors: dict[int, dict[str, Any]] = {}
        labels: dict[int, list[NotDetermined]] = {}
        for j, sl in enumerate(fit.slots):
            se = float(fit.se[j])
            e = errors.setdefault(id(sl.effect), {})
            if sl.field is None:
                e[sl.key] = se
            else:
                terms = e.setdefault(sl.key, [None] * len(sl.effect.parameters[sl.key]))
                terms[-1] = {**(terms[-1] or {}), sl.field: se}
            if j in loose:
                seen = out.seen.get(i, {}).get(_key(fit, j), [])
                labels.setdefault(id(sl.effect), []).append(
                    not_determined(sl.label, sl.value, se, '; '.join(loose[j]), seen))
        for c in [c for c in s.kept if c.axis_index == i]:
            c.standard_error = {k: errors.get(id(c), {}).get(k) for k in c.parameters}
            if labels.get(id(c)):
                new = labelled(c, labels[id(c)])
                c.not_determined, c.score = new.not_determined, new.score
    return s.ext is not judged
