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
Input/output layouts in an import map: a shaker and many sensors, many actuators and one sensor.

Besides ``joints`` (each with its own torque and motion), a map may give ``inputs`` and
``outputs``, each signal once::

    inputs:                          # the excitation(s): force, torque, voltage ...
      - name: shaker
        signal: {column: F}          # a signal as in joints (column, scale, offset, ...)
        unit: N                      # optional: shown on the axes
    outputs:                         # the responses, each kept as measured
      - name: acc_1
        signal: {column: a1}
        quantity: acceleration       # position | velocity | acceleration (required)
        unit: m/s^2                  # optional: shown on the axes
        derive: velocity             # optional: differentiate / integrate to this quantity

:func:`layout_to_joints` turns the layout into the joints the importer reads: an input is a
channel with its effort and no motion, an output one with its motion and no effort (no
zero-scale trick in the map). ``Recording.meta['layout']`` lists the inputs and outputs with
their quantity and unit, and the estimators use the outputs only as outputs. An FRF is the
output quantity over the input: an acceleration over a force is an accelerance.
"""
from __future__ import annotations

from typing import Any

from frf_ident.errors import FrfIdentInputError

__all__ = ['DERIVE', 'LADDERS', 'LAYOUT_INPUT_KEYS', 'LAYOUT_OUTPUT_KEYS', 'QUANTITIES',
           'check_layout', 'layout_to_joints', 'signal_key']

#: what an output can be; the estimators treat every output alike (kept as measured)
QUANTITIES = ('position', 'velocity', 'acceleration')
#: derive: (from, to) -> how many time derivatives (negative: integrals)
DERIVE = {('position', 'velocity'): 1, ('velocity', 'acceleration'): 1,
          ('position', 'acceleration'): 2, ('velocity', 'position'): -1,
          ('acceleration', 'velocity'): -1, ('acceleration', 'position'): -2}
#: units of position, velocity and acceleration, for the unit of a derived output
LADDERS = (('m', 'm/s', 'm/s^2'), ('mm', 'mm/s', 'mm/s^2'), ('rad', 'rad/s', 'rad/s^2'),
           ('deg', 'deg/s', 'deg/s^2'))
LAYOUT_INPUT_KEYS = {'name', 'signal', 'unit'}
LAYOUT_OUTPUT_KEYS = {'name', 'signal', 'quantity', 'unit', 'derive'}


def signal_key(spec: Any) -> tuple:
    """
    Identify the data a signal refers to (column or variable, row, col).

    Parameters
    ----------
    spec : str or int or dict
        A signal of a map.

    Returns
    -------
    tuple
        Hashable key: two signals with the same key read the same data.

    """
    if not isinstance(spec, dict):
        return (spec, None, None)
    return (spec.get('column', spec.get('variable')), spec.get('row'), spec.get('col'))


def _entries(doc: dict[str, Any], key: str, allowed: set[str], where: str) -> list[dict]:
    items = doc.get(key)
    if not isinstance(items, list) or not items:
        raise FrfIdentInputError(f'{where}: {key}={items!r}; expected a non-empty list')
    for k, it in enumerate(items):
        w = f'{where}: {key}[{k}]'
        if not isinstance(it, dict) or not isinstance(it.get('name'), str) or not it['name']:
            raise FrfIdentInputError(f'{w}: expected a mapping with a non-empty name')
        unknown = sorted(set(it) - allowed)
        if unknown:
            raise FrfIdentInputError(f"{w} ({it['name']}): unknown key(s) {unknown}; expected "
                                     f'{sorted(allowed)}')
        if it.get('signal') is None:
            raise FrfIdentInputError(f"{w} ({it['name']}): signal is required (a column or a "
                                     f'mapping with column, scale, ...)')
    return items


def check_layout(doc: dict[str, Any], where: str) -> None:
    """
    Check the ``inputs`` / ``outputs`` of a map (one line naming the field).

    Parameters
    ----------
    doc : dict
        The map.
    where : str
        The map's name in messages.

    Raises
    ------
    FrfIdentInputError
        Both joints and a layout, only one of inputs / outputs, a missing signal or
        quantity, an unknown quantity or derive, a name or signal used twice.

    """
    if 'joints' in doc:
        raise FrfIdentInputError(f'{where}: joints and inputs/outputs both given; expected '
                                 f'one layout (joints, or inputs with outputs)')
    ins = _entries(doc, 'inputs', LAYOUT_INPUT_KEYS, where)
    outs = _entries(doc, 'outputs', LAYOUT_OUTPUT_KEYS, where)
    names: set[str] = set()
    seen: dict[tuple, str] = {}
    for key, items in (('inputs', ins), ('outputs', outs)):
        for k, it in enumerate(items):
            w = f"{where}: {key}[{k}] ({it['name']})"
            if it['name'] in names:
                raise FrfIdentInputError(f"{w}: name={it['name']!r} is used twice")
            names.add(it['name'])
            sk = signal_key(it['signal'])
            if sk in seen:
                raise FrfIdentInputError(f'{w}: signal {sk[0]!r} is already {seen[sk]}; a map '
                                         f'refers to a signal once')
            seen[sk] = f"{key[:-1]} {it['name']!r}"
            if key == 'outputs':
                q = it.get('quantity')
                if q not in QUANTITIES:
                    raise FrfIdentInputError(f'{w}: quantity={q!r}; expected one of '
                                             f'{list(QUANTITIES)}')
                d = it.get('derive')
                if d is not None and (q, d) not in DERIVE:
                    raise FrfIdentInputError(f'{w}: derive={d!r} from {q}; expected one of '
                                             f'{[b for a, b in DERIVE if a == q]}')


def layout_to_joints(doc: dict[str, Any]) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """
    Return the joints the importer reads for a layout, and ``meta['layout']``.

    An input becomes a channel whose effort is the input signal, an output one whose
    velocity is the output signal (after ``derive``); the others are zero.

    Parameters
    ----------
    doc : dict
        A map with ``inputs`` and ``outputs`` (checked by :func:`check_layout`).

    Returns
    -------
    tuple
        (joints: list of {'name', 'effort' | 'velocity', 'derive_steps'}, layout meta:
        {'inputs': [{name, unit}], 'outputs': [{name, quantity, unit, measured}]}).

    """
    joints, meta_in, meta_out = [], [], []
    for it in doc['inputs']:
        joints.append({'name': it['name'], 'effort': it['signal'], 'derive_steps': 0})
        meta_in.append({'name': it['name'], 'unit': it.get('unit', '')})
    for it in doc['outputs']:
        q = it['quantity']
        target = it.get('derive') or q
        steps = DERIVE.get((q, target), 0)
        joints.append({'name': it['name'], 'velocity': it['signal'], 'derive_steps': steps})
        meta_out.append({'name': it['name'], 'quantity': target, 'measured': q,
                         'unit': it.get('unit', '') if steps == 0 else
                         _derived_unit(it.get('unit', ''), steps)})
    return joints, {'inputs': meta_in, 'outputs': meta_out}


def _derived_unit(unit: str, steps: int) -> str:
    """Return the unit after ``steps`` time derivatives (negative: integrals), '' if unknown."""
    for ladder in LADDERS:
        if unit in ladder:
            k = ladder.index(unit) + steps
            return ladder[k] if 0 <= k < len(ladder) else ''
    return ''
