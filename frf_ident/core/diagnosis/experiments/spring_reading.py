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
Read an axis' bent spring both ways: a stiffening gear from nominal, or a stiffness with a gap.

Beyond its bends a joint spring is a line: stiffness k_a with a dead zone of total gap g
carries k_a (delta - g/2), a stiffening gear (eq. 2) of k_a below the breakpoint bs and k2
beyond it k2 delta - (k2 - k_a) bs; both together k2 delta - O with the offset
O = k2 g / 2 + (k2 - k_a) bs. A stiffening gear from the nominal stiffness k1 with k2 and
bs = O / (k2 - k1) is the same line, and so is the stiffness k2 behind a gap 2 O / k2; they
differ only within the bends. So a parameter mismatch that changed the linear stiffness with
a backlash or stiffening on top (the search takes them one after the other: the stiffening
candidate of the first round is fitted without the damping the mismatch also carries, and
loses the held-out duel to it) is one reading of the curve and the stiffening gear from
nominal with the mismatch's other parameters the other; a stiffening gear alone may stand in
for a stiffer spring with a backlash the same way. :func:`gap_or_stiffening` refits the
other reading jointly and keeps the one the held-out data prefer (seed 3687644 of
benchmarks/diagnosis_uncertainty.py, a stiffening gear with a damping mismatch, was named a
mismatched stiffness with a backlash of 1.31e-4 +- 2.1e-6 rad; scene 9135 of kind mismatch,
a stiffness 19 % up with a gap of 7.8e-5 rad, a stiffening gear). A reading that puts the
stiffness into a parameter mismatch is taken only where the closing stage would keep that
mismatch (:func:`.held_out.structure_left`): withdrawn there as missing structure, it would
take the axis' other effects with it.
"""
from __future__ import annotations

from dataclasses import replace

from .readings import duel
from .search import Search
from ..common import Effect, SPRING_SHAPES

__all__ = ['as_backlash', 'as_stiffening', 'gap_or_stiffening']

#: the effects that may carry a linear stiffness change beside their own parameters: a
#: parameter mismatch, and a second mode fitted with its axis' linear parameters
#: (:func:`.second_mode.take_second_mode`)
STIFFNESS_HOLDERS = ('parameter_mismatch', 'second_mode')


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


def as_backlash(k1: float, k2: float, bs: float) -> tuple[float, float] | None:
    """
    Return (stiffness, gap) of the linear spring with a backlash on the line of a stiffening.

    The stiffening gear from k1 to ``k2`` beyond ``bs`` carries k2 delta - (k2 - k1) bs beyond
    it: a stiffness k2 behind a dead zone of total gap 2 (k2 - k1) bs / k2. None where k2
    does not exceed k1.

    >>> k, gap = as_backlash(3.0e5, 3.573e5, 2.554e-4)
    >>> round(k), round(gap, 7)
    (357300, 8.19e-05)
    """
    if not k2 > k1 or not bs > 0:
        return None
    return k2, 2.0 * (k2 - k1) * bs / k2


def gap_or_stiffening(s: Search) -> None:
    """
    Offer the other reading of an axis' bent spring; keep the one the held-out data prefer.

    An axis with a parameter mismatch of the stiffness (or a second mode fitted with one) and
    a backlash or a stiffening on top is offered that effect without its stiffness plus the
    stiffening gear of :func:`as_stiffening`; an axis with a stiffening gear from the nominal
    stiffness alone is offered a stiffness mismatch plus the backlash of :func:`as_backlash`.
    The reading is refitted jointly by simulation (:func:`.refit.refit_jointly`) and replaces
    the axis' effects where its held-out misfit is lower and, where it holds a stiffness
    mismatch, that mismatch leaves no structure missing on the axis (:func:`.readings.duel`).
    """
    for i in range(s.robot.n_axes):
        mine = [c for c in s.kept if c.axis_index == i]
        pm = next((c for c in mine if c.name == 'parameter_mismatch'), None)
        held = next((c for c in mine if c.name in STIFFNESS_HOLDERS
                     and 'stiffness' in c.parameters), None)
        bent = {c.name: c for c in mine if c.name in SPRING_SHAPES}
        k1 = float(s.robot.axes[i].stiffness)
        if held is not None and bent:
            st = bent.get('stiffness_nonlinearity')
            shape = as_stiffening(
                k1, float(held.parameters['stiffness']),
                float(bent['backlash'].parameters['backlash']) if 'backlash' in bent else 0.0,
                *((float(st.parameters['stiffness_k2']),
                   float(st.parameters['stiffness_breakpoint'])) if st is not None else ()))
            if shape is not None:
                duel(s, i, [held, *bent.values()], _stiffening_reading(s, i, held, shape))
        elif list(bent) == ['stiffness_nonlinearity']:
            st = bent['stiffness_nonlinearity']
            line = as_backlash(k1, float(st.parameters['stiffness_k2']),
                               float(st.parameters['stiffness_breakpoint']))
            if line is not None:
                duel(s, i, [st] + ([pm] if pm is not None else []),
                     _backlash_reading(s, i, pm, line))


def _stiffening_reading(s: Search, i: int, held: Effect, shape: tuple[float, float]
                        ) -> list[Effect]:
    """Return the stiffness holder without its stiffness (if anything is left) and the gear."""
    rest = {k: v for k, v in held.parameters.items() if k != 'stiffness'}
    st = Effect('stiffness_nonlinearity', held.axis, 0.0,
                {'stiffness_k2': shape[0], 'stiffness_breakpoint': shape[1]},
                f'a stiffness mismatched to {held.parameters["stiffness"]:.4g} N m/rad with a '
                f'spring shape on top is, beyond its bends, the line of a stiffening gear from '
                f'the nominal {s.robot.axes[i].stiffness:.4g} N m/rad', i)
    return ([replace(held, parameters=rest)] if rest else []) + [st]


def _backlash_reading(s: Search, i: int, pm: Effect | None, line: tuple[float, float]
                      ) -> list[Effect]:
    """Return a stiffness mismatch (added to the axis' mismatch, if any) and the backlash."""
    name = s.robot.axes[i].name
    why = (f'a stiffening gear from the nominal {s.robot.axes[i].stiffness:.4g} N m/rad is, '
           f'beyond its breakpoint, the line of a stiffness {line[0]:.4g} N m/rad behind a '
           f'dead zone')
    mm = (replace(pm, parameters={**pm.parameters, 'stiffness': line[0]}) if pm is not None
          else Effect('parameter_mismatch', name, 0.0, {'stiffness': line[0]}, why, i))
    return [mm, Effect('backlash', name, 0.0, {'backlash': line[1]}, why, i)]
