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
Two readings of one axis, judged on the held-out data.

The search takes effects one after the other, each fitted on top of the model of its time,
so an axis can end with one reading of what it shows where another explains the same
signature: a stiffer spring with a gap or a stiffening gear (:mod:`.spring_reading`), a
motor-side viscous friction or a gear damping (:mod:`.dissipation_reading`). :func:`duel`
refits the other reading jointly with the axis' other effects and takes it where the
held-out data prefer it.
"""
from __future__ import annotations

from dataclasses import replace

from frf_ident.core.model.params import RobotParams

from .acceptance import share_of_misfit
from .held_out import structure_left
from .noise_gain import held_out_gain
from .refit import rebuild, refit_jointly
from .search import Search
from ..common import Effect

__all__ = ['duel']


def duel(s: Search, i: int, old: list[Effect], new: list[Effect], *,
         beyond_noise: bool = False) -> bool:
    """
    Refit axis i with ``new`` in place of ``old``; take it where the held-out data prefer.

    Parameters
    ----------
    s : Search
        The search; its kept effects, model and misfit are updated when the reading is taken.
    i : int
        The axis.
    old : list of Effect
        The kept effects of the axis the reading replaces.
    new : list of Effect
        The reading (fresh effects; refitted jointly with the axis' other kept effects).
    beyond_noise : bool
        Take the reading only where its held-out gain over the model with ``old`` exceeds
        the noise (:func:`.noise_gain.held_out_gain`), not merely where its held-out misfit
        is lower: the model as it stands is kept on a tie.

    Returns
    -------
    bool
        Whether the reading was taken.

    """
    ev, robot = s.ev, s.robot
    others = [replace(k) for k in s.kept if all(k is not o for o in old)]
    trial = others + new
    ext, now = refit_jointly(ev, robot, trial, i, ev.misfit(ev.terms(rebuild(robot, trial))),
                             s.say)
    held = [float(ev.held_out_misfit(m)[i]) for m in (s.ext, ext)]
    was, then = (', '.join(f'{c.name} {_text(c)}' for c in cs) for cs in (old, new))
    s.say(f'  {robot.axes[i].name}: {was} vs {then} in their place on held-out data: '
          f'{held[0]:.4g} vs {held[1]:.4g}')
    s.cands += [c for c in new if all(c is not o for o in old)]
    if not held[1] < held[0] or _lacks_structure(s, i, new, ext):
        return False
    if beyond_noise:
        g = held_out_gain(ev, ext, s.ext, i)
        s.say(f'    the reading over the model as it stands: {g.describe()}')
        if not g.beyond_noise:
            return False
    for c in new:
        without = ev.misfit(ev.terms(rebuild(robot, [k for k in trial if k is not c])))
        c.gain = share_of_misfit(ev, without, now, i)[1]
        c.score = min(max(c.gain, 0.0), 1.0)
        c.evidence += (f'; refitted jointly with the other effects of the axis: '
                       f'{_text(c)}; held-out misfit {held[1]:.4g} (with {was}: {held[0]:.4g})')
    for c in old:
        c.evidence += f'; {then} in its place fits the held-out data better'
        c.gain = c.score = 0.0
    kept = [k for k in s.kept if all(k is not o for o in old)]
    for k, t in zip(kept, others):
        k.parameters = t.parameters
    s.kept[:] = kept + new
    s.ext, s.cur = ext, ev.misfit(ev.terms(ext))
    return True


def _lacks_structure(s: Search, i: int, new: list[Effect], ext: RobotParams) -> bool:
    """
    Return whether the reading's stiffness mismatch would be withdrawn as missing structure.

    A reading that puts the axis' stiffness into a parameter mismatch is judged by
    :func:`.held_out.structure_left` before it is taken: where the mismatch leaves its axis
    lacking structure, the closing stage would withdraw it, and the axis would lose the
    effects the reading replaced (CI scene 7189810: joint_3's stiffening gear beside a time
    delay and Coulomb friction, 888.6 held-out floors, read as a stiffer spring behind a gap at
    809.9; the mismatch withdrawn, none of the axis' three effects was named).
    """
    if not any(c.name == 'parameter_mismatch' and 'stiffness' in c.parameters for c in new):
        return False
    ev = s.ev
    sim = ev.simulate(ext)
    why = structure_left(s, i, ext, sim, ev.held_out_misfit(ext, sim),
                         ev.held_out_misfit(s.robot, s.sim0))
    if why is not None:
        s.say(f'  {s.robot.axes[i].name}: not taken: its stiffness mismatch leaves the axis '
              f'lacking structure ({why})')
    return why is not None


def _text(c: Effect) -> str:
    """Return an effect's scalar parameters (a mode's by name), as in the trace."""
    flat = {f'{k} {n}' if isinstance(v, dict) else k: x
            for k, v in c.parameters.items()
            for n, x in (v.items() if isinstance(v, dict) else [('', v)])}
    return ', '.join(f'{k} {v:.4g}' for k, v in flat.items() if isinstance(v, float))
