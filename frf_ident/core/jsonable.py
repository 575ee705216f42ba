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
"""Numpy values as plain JSON values: the one conversion used by every file writer."""
from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ['json_default', 'jsonable']


def jsonable(obj: Any) -> Any:
    """
    Recursively convert numpy arrays and scalars (and complex numbers) to plain Python.

    Parameters
    ----------
    obj : object
        Dict, list, tuple, numpy array or scalar, complex, or a plain value.

    Returns
    -------
    object
        The same structure with lists for arrays, Python scalars for numpy scalars, and
        ``{'re': ..., 'im': ...}`` for complex values; dict keys become strings.

    """
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        if np.iscomplexobj(obj):
            return {'re': obj.real.tolist(), 'im': obj.imag.tolist()}
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, complex):
        return {'re': obj.real, 'im': obj.imag}
    return obj


def json_default(obj: Any) -> Any:
    """
    Convert a numpy array or scalar for :func:`json.dumps` (its ``default=`` hook).

    Parameters
    ----------
    obj : object
        The value json could not serialise.

    Returns
    -------
    object
        :func:`jsonable` of ``obj`` for a numpy array or scalar.

    Raises
    ------
    TypeError
        For anything else, as json.dumps expects.

    """
    if isinstance(obj, (np.ndarray, np.generic)):
        return jsonable(obj)
    raise TypeError(f'not JSON serialisable: {type(obj).__name__}')
