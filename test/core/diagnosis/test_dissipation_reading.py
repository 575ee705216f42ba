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
Which reading of an axis' dissipation is offered in place of the one it kept.

The duel itself (simulation, held-out gain) runs on real scenes: pair seed 205727 in
test/app/test_diagnose_uncertainty.py. Here the offers are checked against what the search
read: the damping of the mismatch that read one (not of a later round's mismatch without it),
put into the axis' kept mismatch; the viscous friction in the place of a kept damping, the
mismatch's other parameters kept; nothing where the axis kept both or neither.
"""
from types import SimpleNamespace

from frf_ident.core.diagnosis.common import Effect
from frf_ident.core.diagnosis.experiments import dissipation_reading
import pytest


def _e(name, params, axis=2):
    return Effect(name, f'joint_{axis + 1}', 0.0, dict(params), 'read', axis)


@pytest.fixture
def offers(monkeypatch):
    """Record the duels offered instead of simulating them."""
    seen = []
    monkeypatch.setattr(dissipation_reading, 'duel',
                        lambda s, i, old, new, beyond_noise: seen.append(
                            (i, old, new, beyond_noise)))
    return seen


def _search(kept, cands=(), read=()):
    axes = [SimpleNamespace(name=f'joint_{i + 1}') for i in range(3)]
    return SimpleNamespace(robot=SimpleNamespace(n_axes=3, axes=axes), kept=list(kept),
                           cands=list(cands), stage2_read=list(read))


def test_a_kept_viscous_friction_meets_the_damping_the_frf_shape_read(offers):
    visc = _e('viscous_friction', {'viscous_friction': 110.2})
    early = _e('parameter_mismatch', {'motor_inertia': 14.5, 'stiffness': 1.87e5,
                                      'damping': 320.0})
    late = _e('parameter_mismatch', {'motor_inertia': 10.7, 'link_inertia': 41.2})
    dissipation_reading.damping_or_viscous(_search([visc], [late], [early, late]))
    [(i, old, new, beyond)] = offers
    assert i == 2 and old == [visc] and beyond
    assert [(c.name, c.parameters) for c in new] == [('parameter_mismatch', {'damping': 320.0})]


def test_the_damping_joins_the_axis_kept_mismatch(offers):
    visc = _e('viscous_friction', {'viscous_friction': 110.2})
    pm = _e('parameter_mismatch', {'stiffness': 1.95e5})
    read = _e('parameter_mismatch', {'damping': 355.0})
    dissipation_reading.damping_or_viscous(_search([visc, pm], [], [read]))
    [(_, old, new, _)] = offers
    assert old == [visc, pm]
    assert [c.parameters for c in new] == [{'stiffness': 1.95e5, 'damping': 355.0}]


def test_a_kept_damping_meets_the_viscous_friction_the_residual_read(offers):
    pm = _e('parameter_mismatch', {'link_inertia': 40.0, 'damping': 500.0}, axis=0)
    visc = _e('viscous_friction', {'viscous_friction': 33.0}, axis=0)
    dissipation_reading.damping_or_viscous(_search([pm], [visc]))
    [(i, old, new, _)] = offers
    assert i == 0 and old == [pm]
    assert [(c.name, c.parameters) for c in new] == [
        ('parameter_mismatch', {'link_inertia': 40.0}),
        ('viscous_friction', {'viscous_friction': 33.0})]


def test_nothing_is_offered_where_the_axis_kept_both_or_nothing_was_read(offers):
    both = [_e('viscous_friction', {'viscous_friction': 20.0}),
            _e('parameter_mismatch', {'damping': 300.0})]
    dissipation_reading.damping_or_viscous(
        _search(both, [_e('parameter_mismatch', {'damping': 310.0})]))
    # a viscous friction kept, but no mismatch read a damping (or read it at 0)
    dissipation_reading.damping_or_viscous(
        _search([both[0]], [_e('parameter_mismatch', {'damping': 0.0})]))
    assert offers == []
