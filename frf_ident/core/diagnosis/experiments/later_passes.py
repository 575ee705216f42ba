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
The passes after the first reading of each stage: candidates read again on the model so far.

A candidate's share is judged against its axis' misfit at the time it is offered; once other
effects change the axis (an FRF-shape effect, a joint refit), some deserve another reading:
the stage-1 candidates on shaped axes (:func:`second_pass`), every axis' effects refitted
jointly (:func:`joint_refits`), a friction the joint refit's axis rejected before
(:func:`friction_after_refit`) and a ripple read on the refitted model (:func:`late_ripples`).
Stages of :func:`.pipeline.diagnose_experiments`.
"""
from __future__ import annotations

from .acceptance import accept, gravity_with_shape
from .candidates import ripple_again
from .refit import FRICTION, refit_friction, refit_jointly
from .search import Search
from ..thresholds import REFIT_REOFFER_FALL, UNEXPLAINED_RATIO

__all__ = ['friction_after_refit', 'joint_refits', 'late_ripples', 'second_pass']


def second_pass(s: Search) -> None:
    """
    Offer the stage-1 candidates again on axes an FRF-shape effect changed.

    A torque-residual effect masked by a large FRF-shape effect on the same axis (viscous
    friction next to backlash) gets another chance on top of the model so far; so does one on
    an axis still clearly above its floor once a coupled axis took an FRF-shape effect (its
    regression was biased through the link coupling). The regression read them against a model
    that lacked the FRF-shape effect: friction is refitted by simulation; a gravity candidate of
    a shaped axis is offered with the axis' effects refitted beside it.
    """
    ev, robot, kept = s.ev, s.robot, s.kept
    s.shaped = {k.axis_index for k in kept if k in s.stage2}
    fl = ev.floor_seen(s.cur)
    s.again = [c for c in s.stage1 if c not in kept
               and (c.axis_index in s.shaped
                    or (s.shaped and s.cur[c.axis_index] > UNEXPLAINED_RATIO * fl[c.axis_index]))
               and not any(k.name == c.name and k.axis == c.axis for k in kept)]
    if not s.again:
        return
    s.say('second pass over the torque-residual candidates of axes with FRF-shape effects '
          'or still above their floor next to one')
    for c in s.again:
        if c.name in FRICTION:
            r = refit_friction(ev, s.ext, c)
            c.parameters, c.evidence = r.parameters, r.evidence
    s.ext, s.cur = accept(ev, robot, kept, s.again, s.cur, s.say)
    for c in s.again:
        if c.name == 'gravity' and c not in kept and c.axis_index in s.shaped:
            s.ext, s.cur = gravity_with_shape(ev, robot, kept, c, s.cur, s.say)


def joint_refits(s: Search) -> None:
    """
    Refit each axis' effects jointly by simulation where their separate fits may not settle.

    An axis still clearly above its floor, an axis that took a second-pass effect (read against
    a model that lacked the axis' FRF-shape effect), and an axis whose effects were all fitted
    in stage 1 next to another axis' FRF-shape effect the model still lacked (the link coupling
    carried that misfit into its simulation; a stage-0 mismatch was in the model already). Its
    ripple amplitude is refitted only when the axis is above its floor or took a second-pass
    effect.
    """
    ev, robot, kept = s.ev, s.robot, s.kept
    second = {c.axis_index for c in s.again if c in kept}
    early = ({c.axis_index for c in kept if c not in s.stage2 and c not in s.stage0}
             - s.shaped) if s.shaped else set()
    for i in range(robot.n_axes):
        above = s.cur[i] > UNEXPLAINED_RATIO * ev.floor_seen(s.cur)[i]
        if any(c.axis_index == i for c in kept) and (i in second or i in early or above):
            before = float(s.cur[i])
            s.ext, s.cur = refit_jointly(ev, robot, kept, i, s.cur, s.say,
                                         ripple=above or i in second)
            s.refitted[i] = before


def friction_after_refit(s: Search) -> None:
    """
    Offer a rejected stage-1 friction again on an axis its joint refit brought much closer.

    A candidate's share is judged against its axis' misfit at the time: a motor-side viscous
    friction read on top of a spring whose damping had taken it removes a few percent of an
    axis still tens of floors above its noise, and is rejected; once the joint refit has
    brought the axis near its floor (by REFIT_REOFFER_FALL or more), the same friction, refitted
    by simulation on top, is judged again, and the axis refitted jointly with it where taken.
    """
    ev, robot, kept = s.ev, s.robot, s.kept
    fallen = {i for i, before in s.refitted.items()
              if s.cur[i] * REFIT_REOFFER_FALL <= before}
    late = [c for c in s.stage1 if c.axis_index in fallen and c.name in FRICTION
            and c not in kept and not any(k.name == c.name and k.axis == c.axis for k in kept)]
    if not late:
        return
    s.say('friction read again on axes the joint refit brought near their floor')
    for c in late:
        r = refit_friction(ev, s.ext, c)
        c.parameters, c.evidence = r.parameters, r.evidence
    s.ext, s.cur = accept(ev, robot, kept, late, s.cur, s.say)
    for i in sorted({c.axis_index for c in late if c in kept}):
        s.ext, s.cur = refit_jointly(ev, robot, kept, i, s.cur, s.say, ripple=False)


def late_ripples(s: Search) -> None:
    """
    Offer once more a ripple the stage-1 scan saw on a shaped axis, read on the refitted model.

    Read against a mismatched stiffness its amplitude and phase are biased; offered in the
    second pass, next to a mismatch still a few percent off, it worsens the axis.
    """
    late = [r for r in (ripple_again(s.ev, s.ext, i, s.stage1, s.kept)
                        for i in sorted(s.shaped)) if r is not None]
    s.ext, s.cur = accept(s.ev, s.robot, s.kept, late, s.cur, s.say) if late else (s.ext, s.cur)
    s.cands += late
