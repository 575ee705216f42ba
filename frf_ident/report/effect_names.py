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
An effect's name as a drives engineer says it, beside the report's key (issue 55).

report.json keeps the keys of docs/CONTRACT.md §7 (``torque_ripple``, ``velocity_from_encoder``);
the console and the HTML report write the cause in words next to the key, so a person reads
what the key means without the contract at hand.
"""
from __future__ import annotations

__all__ = ['effect_phrase', 'EFFECT_PHRASES']

#: report key -> the cause in a drives engineer's words (short: it sits on a console line)
EFFECT_PHRASES = {
    'coulomb_friction': 'Coulomb friction',
    'viscous_friction': 'viscous friction',
    'stiffness_nonlinearity': 'gear stiffening with load',
    'backlash': 'lost motion in the gear',
    'torque_ripple': 'position-locked torque ripple',
    'time_delay': 'time delay beyond the sensor',
    'gravity': 'gravity load varying with pose',
    'parameter_mismatch': 'nominal parameters off',
    'velocity_from_encoder': 'velocity from encoder differences, half a sample late',
    'quantisation': 'encoder quantisation',
    'second_mode': 'a second, link-side resonance',
    'pose_dependent_inertia': 'load inertia changing with the pose',
}


def effect_phrase(name: str) -> str:
    """
    Return ``name`` with its phrase in brackets (a key without a phrase: itself).

    Examples
    --------
    >>> effect_phrase('velocity_from_encoder')
    'velocity_from_encoder (velocity from encoder differences, half a sample late)'
    >>> effect_phrase('something_new')
    'something_new'

    """
    phrase = EFFECT_PHRASES.get(name)
    return f'{name} ({phrase})' if phrase else name
