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
"""Report values written for a person: 4 significant digits, ``name value`` instead of dicts."""
from __future__ import annotations

from typing import Any, Mapping, TYPE_CHECKING

from frf_ident.core.model.units import with_unit

if TYPE_CHECKING:
    from frf_ident.core.diagnosis.records import NotDetermined

__all__ = ['not_determined_text', 'parameters_text', 'plain']


def plain(value: Any) -> str:
    """
    Write a report value for a person: floats to 4 significant digits, no braces or quotes.

    Parameters
    ----------
    value : Any
        A number, string, list or dict from report.json.

    Returns
    -------
    str
        E.g. ``amplitude 4.01, spatial_frequency 122.3, phase 0.4`` for a ripple term.

    """
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, float):
        return f'{value:.4g}'
    if isinstance(value, Mapping):
        return ', '.join(f'{k} {plain(v)}' for k, v in value.items())
    if isinstance(value, (list, tuple)):
        inner = [plain(v) for v in value]
        return '; '.join(inner) if any(isinstance(v, Mapping) for v in value) \
            else '[' + ', '.join(inner) + ']'
    return str(value)


def parameters_text(parameters: Mapping[str, Any], standard_error: Mapping[str, Any] | None = None
                    ) -> str:
    """
    Write an effect's parameters for a person: ``key value +- se unit``, terms one by one.

    Parameters
    ----------
    parameters : mapping
        Model-file keys to values; a ``torque_ripple`` or ``gravity`` value is a list of terms
        (dicts of ``amplitude``, ``spatial_frequency``/``phase``, ``joints``), a
        ``second_mode`` one mapping (``frequency_hz``, ``damping_ratio``, ``inertia``).
    standard_error : mapping, optional
        The same keys to standard errors (a list of ``{'amplitude': se}`` or None per term, a
        mapping for a ``second_mode``).

    Returns
    -------
    str
        E.g. ``coulomb_friction 14.78 +- 0.051 N m`` or ``torque_ripple amplitude 4.014 N m,
        spatial_frequency 122.3 1/rad, phase 0.3243 rad``.

    """
    se = standard_error or {}
    parts = []
    for key, value in parameters.items():
        if isinstance(value, (list, tuple)):
            errs = se.get(key) or [None] * len(value)
            parts += [f'{key} ' + _term(term, err) for term, err in zip(value, errs)]
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            parts.append(f'{key} {with_unit(key, float(value), _number(se.get(key)))}')
        elif isinstance(value, Mapping):
            parts.append(f'{key} ' + _term(value, se.get(key)))
        else:
            parts.append(f'{key} {plain(value)}')
    return '; '.join(parts)


def _term(term: Mapping[str, Any], err: Mapping[str, Any] | None) -> str:
    """Write one ripple, gravity or second-mode term: its keys with units, the joints it sums."""
    out = []
    for k, v in term.items():
        if k == 'joints':
            out.append('of ' + ' + '.join(v))
        else:
            out.append(f'{k} {with_unit(k, float(v), _number((err or {}).get(k)))}')
    return ', '.join(out)


def _number(x: Any) -> float | None:
    """Return a standard error as a float, None where there is none."""
    return float(x) if isinstance(x, (int, float)) and not isinstance(x, bool) else None


def not_determined_text(entry: NotDetermined) -> tuple[str, str]:
    """
    Write a parameter the record does not determine, and the experiment that would.

    Parameters
    ----------
    entry : NotDetermined
        The effect's ``not_determined`` entry.

    Returns
    -------
    (str, str)
        E.g. ``viscous_friction not determined by this record: 45 to 1146 N m s/rad (standard
        error 180, 54 % of the value)`` and ``a slower multisine or constant-velocity runs at
        several speeds would determine it``.

    """
    key = entry.parameter.split()[-1]
    lo, hi = entry.value_range
    return (f'{entry.parameter} not determined by this record: {lo:.4g} to '
            f'{with_unit(key, hi)} ({entry.reason})',
            f'{entry.experiment} would determine it')
