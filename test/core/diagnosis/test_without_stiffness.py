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
A parameter mismatch pending beside a spring shape just taken loses its stiffness part.

Pair scene 284825 of benchmarks/diagnosis_uncertainty.py (a stiffening gear and a damping
mismatch on joint_3): the mismatch read by the linear FRF fit carried a stiffness x1.11 beside
the damping; once the stiffening was taken that part counted the spring twice, and the
damping lost the held-out duel to a viscous friction 14x its nominal value.
"""
from frf_ident.core.diagnosis.common import Effect
from frf_ident.core.diagnosis.experiments.acceptance import without_stiffness


def _pm(params, axis=2):
    return Effect('parameter_mismatch', f'joint_{axis + 1}', 0.0, dict(params), 'read', axis)


def test_the_stiffness_part_goes_once_the_axis_took_a_spring_shape():
    for shape in ('stiffness_nonlinearity', 'backlash'):
        took = Effect(shape, 'joint_3', 0.0, {}, '', 2)
        out = without_stiffness(_pm({'stiffness': 1.33e5, 'damping': 396.0}), took)
        assert out.parameters == {'damping': 396.0}
        assert f'once the axis took a {shape}' in out.evidence
        # nothing left: the candidate goes
        assert without_stiffness(_pm({'stiffness': 1.33e5}), took) is None


def test_everything_else_stays_as_it_is():
    pm = _pm({'stiffness': 1.33e5, 'damping': 396.0})
    spring = Effect('stiffness_nonlinearity', 'joint_3', 0.0, {}, '', 2)
    assert without_stiffness(pm, None) is pm                           # the axis took nothing
    assert without_stiffness(pm, Effect('viscous_friction', 'joint_3', 0.0, {}, '', 2)) is pm
    assert without_stiffness(_pm(pm.parameters, axis=1), spring).parameters == pm.parameters
    visc = Effect('viscous_friction', 'joint_3', 0.0, {'viscous_friction': 10.0}, '', 2)
    assert without_stiffness(visc, spring) is visc
    assert without_stiffness(_pm({'damping': 396.0}), spring).parameters == {'damping': 396.0}
