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
Checks of typed fields in loaded configuration mappings (model files, import maps).

YAML reads ``"false"`` or ``"no"`` (quoted) as strings and ``1.7`` as a float; Python's
``bool('false')`` is True and ``int(1.7)`` is 1. These checks accept only the intended type and
raise one line naming the field and the value otherwise.
"""
from __future__ import annotations

from numbers import Integral
from typing import Any

from frf_ident.errors import FrfIdentInputError
import numpy as np

__all__ = ['expect_bool', 'expect_int']


def expect_bool(where: str, value: Any,
                error: type[FrfIdentInputError] = FrfIdentInputError) -> bool:
    """
    Return ``value`` if it is a boolean (YAML ``true`` / ``false``), else raise.

    Parameters
    ----------
    where : str
        The field, for the message (e.g. ``'simulation.velocity_from_encoder'``).
    value : object
        The loaded value.
    error : type, optional
        The :class:`~frf_ident.errors.FrfIdentInputError` subclass to raise.

    Returns
    -------
    bool
        ``value``.

    Raises
    ------
    FrfIdentInputError
        (``error``) ``value`` is not a bool, e.g. the quoted string ``'false'``.

    """
    if not isinstance(value, (bool, np.bool_)):
        raise error(f'{where}: expected true or false, got {value!r}')
    return bool(value)


def expect_int(where: str, value: Any, minimum: int | None = None,
               error: type[FrfIdentInputError] = FrfIdentInputError) -> int:
    """
    Return ``value`` if it is an integer (not a bool) of at least ``minimum``, else raise.

    Parameters
    ----------
    where : str
        The field, for the message (e.g. ``'simulation.seed'``).
    value : object
        The loaded value (a Python or numpy integer).
    minimum : int, optional
        The smallest value allowed.
    error : type, optional
        The :class:`~frf_ident.errors.FrfIdentInputError` subclass to raise.

    Returns
    -------
    int
        ``value``.

    Raises
    ------
    FrfIdentInputError
        (``error``) ``value`` is not an integer (a float such as 1.7, a string, a bool) or is
        below ``minimum``.

    """
    what = 'an integer' if minimum is None else f'an integer >= {minimum}'
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Integral):
        raise error(f'{where}: expected {what}, got {value!r}')
    if minimum is not None and value < minimum:
        raise error(f'{where}: expected {what}, got {value!r}')
    return int(value)
