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
The unit of every model-file parameter: one table for the console, the reports and the docs.

Keys are the model-file keys of docs/CONTRACT.md §5 (and docs/model_file.md), plus the keys
inside a ``torque_ripple`` or ``gravity`` term and a ``second_mode`` mapping. Units are motor
side, SI: what the plant simulates and the diagnosis fits. :func:`with_unit` writes a value
for a person.
"""
from __future__ import annotations

import math

__all__ = ['PARAMETER_UNITS', 'unit_of', 'with_unit']

#: model-file key -> unit (motor side, SI)
PARAMETER_UNITS = {
    'motor_inertia': 'kg m^2',
    'link_inertia': 'kg m^2',
    'stiffness': 'N m/rad',
    'damping': 'N m s/rad',
    'viscous_friction': 'N m s/rad',
    'coulomb_friction': 'N m',
    'stiffness_k2': 'N m/rad',
    'stiffness_breakpoint': 'rad',
    'backlash': 'rad',
    'time_delay': 's',
    'gravity_torque': 'N m',
    'torque_limit': 'N m',
    'encoder_resolution': 'rad',
    'velocity_noise': 'rad/s',
    'torque_noise': 'N m',
    # inside a torque_ripple or gravity term
    'amplitude': 'N m',
    'spatial_frequency': '1/rad',
    'phase': 'rad',
    # inside a second_mode mapping (damping_ratio has no unit)
    'frequency_hz': 'Hz',
    'inertia': 'kg m^2',
}


def unit_of(key: str) -> str:
    """Return the unit of a model-file key ('' for a key without one, e.g. ``joints``)."""
    return PARAMETER_UNITS.get(key, '')


def with_unit(key: str, value: float, se: float | None = None) -> str:
    """
    Return ``value`` (and its standard error) with the key's unit, 4 significant digits.

    Examples
    --------
    >>> with_unit('coulomb_friction', 14.7812, 0.0512)
    '14.78 \u00b1 0.051 N m'
    >>> with_unit('stiffness_breakpoint', 0.00040113)
    '0.0004011 rad'

    """
    text = f'{value:.4g}'
    if se is not None and math.isfinite(se):
        text += f' \u00b1 {se:.2g}'
    unit = unit_of(key)
    return f'{text} {unit}' if unit else text
