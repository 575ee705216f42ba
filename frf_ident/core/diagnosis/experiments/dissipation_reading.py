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
Read an axis' extra dissipation both ways: motor-side viscous friction or gear damping.

A viscous friction acts on the motor's speed, a gear damping on the gear's deflection rate;
both damp the resonance, and where the axis' other effects are not yet in place either can
stand in for the other. The search reads them at different stages: the viscous friction from
the torque residual (stage 1), the damping with the linear parameters from the FRF shape
(stage 2), which judges it on top of the viscous term already taken. Offered on top, the
right damping doubles the dissipation and worsens the axis, so it is never taken in the
viscous term's place (pair scene 205727 of benchmarks/diagnosis_uncertainty.py: a damping
349 for the nominal 250 beside a stiffening gear, read at 320 in stage 2, was named a viscous
friction of 110 for the nominal 10). :func:`damping_or_viscous` offers the reading the axis
did not take in place of the one it took, both ways, refitted jointly with the axis' other
effects (:func:`.readings.duel`), and takes it only where its held-out gain over the model as
it stands exceeds the noise: a tie keeps the model as the search left it.
"""
from __future__ import annotations

from dataclasses import replace

from .readings import duel
from .search import Search
from ..common import Effect

__all__ = ['damping_or_viscous']


def damping_or_viscous(s: Search) -> None:
    """
    Offer a lost gear damping in a kept viscous friction's place, and the other way round.

    An axis that kept a viscous friction but no damping is offered the damping of its last
    parameter-mismatch candidate that read one (added to the axis' kept mismatch, if any);
    an axis whose kept mismatch holds a damping but that kept no viscous friction is offered
    its last viscous-friction candidate with the mismatch's damping dropped.
    """
    for i in range(s.robot.n_axes):
        name = s.robot.axes[i].name
        mine = [c for c in s.kept if c.axis_index == i]
        visc = next((c for c in mine if c.name == 'viscous_friction'), None)
        pm = next((c for c in mine if c.name == 'parameter_mismatch'), None)
        damped = pm is not None and 'damping' in pm.parameters
        if visc is not None and not damped:
            d = _offered(s, i, 'parameter_mismatch', 'damping')
            if d is None:
                continue
            why = (f'; the gear damping {d:.4g} N m s/rad the FRF shape read, offered in the '
                   f'place of the viscous friction the torque residual read')
            new = (replace(pm, parameters={**pm.parameters, 'damping': d},
                           evidence=pm.evidence + why) if pm is not None
                   else Effect('parameter_mismatch', name, 0.0, {'damping': d}, why[2:], i))
            duel(s, i, [visc] + ([pm] if pm is not None else []), [new], beyond_noise=True)
        elif visc is None and damped:
            v = _offered(s, i, 'viscous_friction', 'viscous_friction')
            if v is None:
                continue
            rest = {k: x for k, x in pm.parameters.items() if k != 'damping'}
            why = (f'the viscous friction {v:.4g} N m s/rad the torque residual read, offered '
                   f'in the place of the gear damping the FRF shape read')
            new = ([replace(pm, parameters=rest)] if rest else []) + [
                Effect('viscous_friction', name, 0.0, {'viscous_friction': v}, why, i)]
            duel(s, i, [pm], new, beyond_noise=True)


def _offered(s: Search, i: int, name: str, key: str) -> float | None:
    """Return the last positive ``key`` of axis i's offered, not kept, ``name`` candidates."""
    for c in reversed(s.cands + s.stage2_read):
        if (c.axis_index == i and c.name == name and all(c is not k for k in s.kept)
                and isinstance(c.parameters.get(key), float) and c.parameters[key] > 0):
            return float(c.parameters[key])
    return None
