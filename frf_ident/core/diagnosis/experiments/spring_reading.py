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
Read a stiffness a mismatch changed, bent by a spring shape, as a stiffening gear from nominal.

Beyond its bends a joint spring is a line: stiffness k_a with a dead zone of total gap g
carries k_a (delta - g/2), a stiffening gear (eq. 2) of k_a below the breakpoint bs and k2
beyond it k2 delta - (k2 - k_a) bs; both together k2 delta - O with the offset
O = k2 g / 2 + (k2 - k_a) bs. A stiffening gear from the nominal stiffness k1 with k2 and
bs = O / (k2 - k1) is the same line, and differs only within its breakpoint. So a parameter
mismatch that changed the linear stiffness with a backlash or stiffening on top (the search
takes them one after the other: the stiffening candidate of the first round is fitted without
the damping the mismatch also carries, and loses the held-out duel to it) is one reading of
the curve; the stiffening gear from nominal with the mismatch's other parameters is the
other. :func:`gap_or_stiffening` refits the second jointly and keeps the one the held-out data
prefer (seed 3687644 of benchmarks/diagnosis_uncertainty.py, a stiffening gear with a damping
mismatch, was named a mismatched stiffness with a backlash of 1.31e-4 +- 2.1e-6 rad).
"""
from __future__ import annotations

from dataclasses import replace

from frf_ident.core.model.params import RobotParams

from .acceptance import share_of_misfit
from .refit import rebuild, refit_jointly
from .search import Search
from ..common import Effect

__all__ = ['as_stiffening', 'gap_or_stiffening']

#: the effects that bend the joint spring (read again here on top of a mismatched stiffness)
SHAPES = ('backlash', 'stiffness_nonlinearity')


def as_stiffening(k1: float, k_a: float, gap: float = 0.0, k2: float | None = None,
                  bs: float = 0.0) -> tuple[float, float] | None:
    """
    Return (k2, bs) of the stiffening gear from k1 with the spring's line beyond its bends.

    The spring: stiffness ``k_a``, a dead zone of total ``gap`` and, where ``k2`` is given, a
    stiffening to ``k2`` beyond ``bs``. None where its outer stiffness does not exceed k1 or
    its line has no offset (no stiffening gear from k1 bends the spring that way).

    >>> k2, bs = as_stiffening(1.2e5, 1.92e5, 1.31e-4)
    >>> round(k2), round(bs, 7)
    (192000, 0.0001747)
    >>> as_stiffening(1.2e5, 1.2e5, k2=1.92e5, bs=1e-4)
    (192000.0, 0.0001)
    """
    k_out = k_a if k2 is None else k2
    offset = k_out * gap / 2.0 + (k_out - k_a) * bs
    if not k_out > k1 or not offset > 0:
        return None
    return k_out, offset / (k_out - k1)


def gap_or_stiffening(s: Search) -> None:
    """
    Offer a stiffening gear from nominal in place of a mismatched stiffness a shape bends.

    Per axis that holds a parameter mismatch of the stiffness and a backlash or a stiffening:
    the mismatch without its stiffness plus the stiffening gear of :func:`as_stiffening`,
    refitted jointly by simulation (:func:`.refit.refit_jointly`), in place of the mismatch's
    stiffness and the shapes, where its held-out misfit is lower.
    """
    for i in range(s.robot.n_axes):
        pm = next((c for c in s.kept if c.axis_index == i and c.name == 'parameter_mismatch'
                   and 'stiffness' in c.parameters), None)
        bent = {c.name: c for c in s.kept if c.axis_index == i and c.name in SHAPES}
        if pm is None or not bent:
            continue
        st = bent.get('stiffness_nonlinearity')
        shape = as_stiffening(
            float(s.robot.axes[i].stiffness), float(pm.parameters['stiffness']),
            float(bent['backlash'].parameters['backlash']) if 'backlash' in bent else 0.0,
            *((float(st.parameters['stiffness_k2']), float(st.parameters['stiffness_breakpoint']))
              if st is not None else ()))
        if shape is not None:
            _duel(s, i, pm, list(bent.values()), shape)


def _duel(s: Search, i: int, pm: Effect, bent: list[Effect], shape: tuple[float, float]
          ) -> None:
    """Refit the stiffening reading of axis i and take it where the held-out data prefer it."""
    ev, robot = s.ev, s.robot
    rest = {k: v for k, v in pm.parameters.items() if k != 'stiffness'}
    was = ' and '.join(f'{c.name} {_text(c)}' for c in bent)
    st = Effect('stiffness_nonlinearity', pm.axis, 0.0,
                {'stiffness_k2': shape[0], 'stiffness_breakpoint': shape[1]},
                f'a stiffness mismatched to {pm.parameters["stiffness"]:.4g} N m/rad with {was} '
                f'on top is, beyond its bends, the line of a stiffening gear from the nominal '
                f'{robot.axes[i].stiffness:.4g} N m/rad', i)
    others = [replace(k) for k in s.kept if k is not pm and all(k is not b for b in bent)]
    mm = [replace(pm, parameters=rest)] if rest else []
    trial = others + mm + [st]
    ext, new = refit_jointly(ev, robot, trial, i, ev.misfit(ev.terms(rebuild(robot, trial))),
                             s.say)
    held = [float(ev.misfit(ev.terms(m, held_out=True))[i]) for m in (s.ext, ext)]
    s.say(f'  {pm.axis}: mismatched stiffness with {was} vs a stiffening gear from nominal '
          f'in their place on held-out data: {held[0]:.4g} vs {held[1]:.4g}')
    s.cands.append(st)
    if not held[1] < held[0]:
        return
    without = ev.misfit(ev.terms(_without(robot, trial, st)))
    st.gain = share_of_misfit(ev, without, new, i)[1]
    st.score = min(max(st.gain, 0.0), 1.0)
    st.evidence += (f'; refitted jointly with the other effects of the axis: k2 = '
                    f'{st.parameters["stiffness_k2"]:.4g} N m/rad beyond bs = '
                    f'{st.parameters["stiffness_breakpoint"]:.3g} rad; held-out misfit '
                    f'{held[1]:.4g} (with the mismatched stiffness {held[0]:.4g})')
    for c in bent:
        c.evidence += ('; a stiffening gear from the nominal stiffness fits the held-out '
                       'data better')
        c.gain = c.score = 0.0
    if mm:
        pm.parameters = mm[0].parameters
    else:
        pm.gain = pm.score = 0.0
    s.kept[:] = [k for k in s.kept if all(k is not b for b in bent) and (mm or k is not pm)]
    for k, t in zip([k for k in s.kept if k is not pm], others):
        k.parameters = t.parameters
    s.kept.append(st)
    s.ext, s.cur = ext, ev.misfit(ev.terms(ext))


def _text(c: Effect) -> str:
    """Return an effect's scalar parameters, as in the trace."""
    return ', '.join(f'{k} {v:.4g}' for k, v in c.parameters.items() if isinstance(v, float))


def _without(robot: RobotParams, trial: list[Effect], st: Effect) -> RobotParams:
    """Return the model of ``trial`` without the stiffening gear ``st``."""
    return rebuild(robot, [k for k in trial if k is not st])
