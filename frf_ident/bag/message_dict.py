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
ROS 2 messages for the bag writers: the shared Jazzy typestore and CDR bytes from a dict.

:func:`typestore` is built once (message definitions and RIHS01 hashes); :func:`serialize_dict`
builds a message of any Jazzy type from a (possibly nested, partial) dict of its fields.
"""
from __future__ import annotations

from typing import Any, Mapping

from frf_ident.errors import BagError
import numpy as np
from rosbags.typesys import get_typestore, Stores
from rosbags.typesys.store import Typestore

__all__ = ['serialize_dict', 'typestore']

_TYPESTORE: Typestore | None = None


def typestore() -> Typestore:
    """Return the shared ROS 2 Jazzy typestore, built once."""
    global _TYPESTORE
    if _TYPESTORE is None:
        _TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
    return _TYPESTORE


def serialize_dict(msg_type: str, fields: Mapping[str, Any]) -> bytes:
    """CDR bytes of ``msg_type`` built from a (possibly nested, partial) dict of fields."""
    ts = typestore()
    try:
        msg = _build(ts, msg_type, fields)
        return bytes(ts.serialize_cdr(msg, msg_type))
    except BagError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise BagError(f'cannot serialise {msg_type=} from {sorted(fields)}: {exc}') from None


_BASE_DTYPES = {'float64': 'f8', 'float32': 'f4', 'int8': 'i1', 'uint8': 'u1', 'int16': 'i2',
                'uint16': 'u2', 'int32': 'i4', 'uint32': 'u4', 'int64': 'i8', 'uint64': 'u8',
                'byte': 'u1', 'char': 'u1', 'bool': 'bool'}


def _build(ts: Typestore, msg_type: str, d: Mapping[str, Any]) -> Any:
    if msg_type not in ts.fielddefs:
        raise BagError(f'unknown message type {msg_type=}')
    cls = ts.types[msg_type]
    kwargs = {name: _value(ts, spec, d.get(name)) for name, spec in ts.fielddefs[msg_type][1]}
    unknown = set(d) - set(kwargs)
    if unknown:
        raise BagError(f'{msg_type} has no field(s) {sorted(unknown)}')
    return cls(**kwargs)


def _value(ts: Typestore, spec: tuple[Any, Any], v: Any) -> Any:
    kind, arg = spec
    kind = int(kind)
    if kind == 2:  # NAME: nested message
        return _build(ts, arg, v or {})
    if kind == 1:  # BASE
        base = arg[0]
        if base == 'string':
            return '' if v is None else str(v)
        if base == 'bool':
            return bool(v)
        return (float(v) if v is not None else 0.0) if base.startswith('float') else int(v or 0)
    elem, _ = arg  # ARRAY (3) / SEQUENCE (4)
    items = [] if v is None else v
    if int(elem[0]) == 1 and elem[1][0] in _BASE_DTYPES:
        return np.asarray(items, dtype=_BASE_DTYPES[elem[1][0]])
    return [_value(ts, elem, x) for x in items]
