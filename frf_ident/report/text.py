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

from typing import Any, Mapping

__all__ = ['plain']


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
