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
The import map: its fields, unit names and checks (:func:`load_map`, :func:`check_map`).

The map format is described in :mod:`frf_ident.io.importer`, which reads a table with it.
"""
from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

from frf_ident.core.model.fields import expect_bool, expect_int
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.layout import check_layout
from frf_ident.io.yamlio import read_yaml_file

__all__ = ['CSV_KEYS', 'JOINT_KEYS', 'PathLike', 'SIGNALS', 'SIGNAL_KEYS', 'TIME_KEYS',
           'TOP_KEYS', 'UNITS', 'check_map', 'load_map']

PathLike = str | os.PathLike[str]
SIGNALS = ('position', 'velocity', 'effort', 'reference', 'excitation')
SIGNAL_KEYS = {'column', 'variable', 'row', 'col', 'scale', 'offset', 'derivative'}
JOINT_KEYS = {'name', 'units', *SIGNALS}
TOP_KEYS = {'frf_ident_map', 'description', 'csv', 'time', 'joints', 'inputs', 'outputs'}
TIME_KEYS = {'column', 'variable', 'row', 'col', 'scale', 'offset', 'sample_time', 'start',
             'range'}
CSV_KEYS = {'delimiter', 'header'}

UNITS: dict[str, float] = {
    'rad': 1.0, 'deg': math.pi / 180.0, 'rad/s': 1.0, 'deg/s': math.pi / 180.0,
    'rpm': 2.0 * math.pi / 60.0, 'rev': 2.0 * math.pi, 'm': 1.0, 'mm': 1e-3, 'um': 1e-6,
    'm/s': 1.0, 'mm/s': 1e-3, 's': 1.0, 'ms': 1e-3, 'us': 1e-6, 'ns': 1e-9,
    'Nm': 1.0, 'N m': 1.0, 'kNm': 1e3, 'mNm': 1e-3, 'N': 1.0, 'kN': 1e3,
}


def load_map(path: PathLike) -> dict[str, Any]:
    """
    Read and check a map file (format: :mod:`frf_ident.io.importer`).

    Parameters
    ----------
    path : str or os.PathLike
        The YAML map file.

    Returns
    -------
    dict
        The map.

    Raises
    ------
    FrfIdentInputError
        The file cannot be read, is not UTF-8 text, is not valid YAML, or fails
        :func:`check_map`.

    """
    path = Path(path)
    doc = read_yaml_file(path, 'map file')
    check_map(doc, str(path))
    return doc


def check_map(doc: Any, where: str = 'map') -> None:
    """
    Validate the structure of a map dict.

    Checks the version, the known fields (also inside ``csv``, ``time``, signals and
    ``units``), the time specification (exactly one of a time signal or ``sample_time``), every
    joint (unique name, effort, position or velocity), the types of boolean fields
    (``csv.header``, ``derivative``: YAML true or false only), ``row`` / ``col`` (integers
    >= 0) and the unit names in ``units`` (:data:`UNITS`).

    Parameters
    ----------
    doc : object
        The loaded map.
    where : str, optional
        Name of the map in error messages (e.g. its path).

    Raises
    ------
    FrfIdentInputError
        The map is malformed (one line naming the field).

    """
    if not isinstance(doc, dict):
        raise FrfIdentInputError(f'{where}: expected a mapping with frf_ident_map, time, '
                                 f'joints; got {type(doc).__name__}')
    if doc.get('frf_ident_map') != 1:
        raise FrfIdentInputError(f"{where}: frf_ident_map={doc.get('frf_ident_map')!r}; "
                                 f'expected 1 (the map format version)')
    _unknown(doc, TOP_KEYS, where)
    csv_opts = doc.get('csv')
    if csv_opts is not None:
        if not isinstance(csv_opts, dict):
            raise FrfIdentInputError(f'{where}: csv={csv_opts!r}; expected a mapping with '
                                     f'{", ".join(sorted(CSV_KEYS))}')
        _unknown(csv_opts, CSV_KEYS, f'{where}: csv')
        if csv_opts.get('header') is not None:
            expect_bool(f'{where}: csv.header', csv_opts['header'])
    time = doc.get('time')
    if not isinstance(time, dict):
        raise FrfIdentInputError(f'{where}: time={time!r}; expected a mapping with column or '
                                 f'sample_time')
    _unknown(time, TIME_KEYS, f'{where}: time')
    _check_signal(time, f'{where}: time')
    has_col = 'column' in time or 'variable' in time
    if has_col == ('sample_time' in time):
        raise FrfIdentInputError(f'{where}: time needs exactly one of column (a time signal) '
                                 f'or sample_time [s]')
    if 'inputs' in doc or 'outputs' in doc:        # a shaker / sensor layout
        check_layout(doc, where)
        return
    joints = doc.get('joints')
    if not isinstance(joints, list) or not joints:
        raise FrfIdentInputError(f'{where}: joints={joints!r}; expected a non-empty list')
    names: list[str] = []
    for k, j in enumerate(joints):
        jw = f'{where}: joints[{k}]'
        if not isinstance(j, dict) or not isinstance(j.get('name'), str) or not j['name']:
            raise FrfIdentInputError(f'{jw}: expected a mapping with a non-empty name')
        if j['name'] in names:
            raise FrfIdentInputError(f"{jw}: name={j['name']!r} is used twice")
        names.append(j['name'])
        _unknown(j, JOINT_KEYS, jw)
        if j.get('effort') is None:
            raise FrfIdentInputError(f"{jw} ({j['name']}): effort is required (the applied "
                                     f'motor torque u)')
        if j.get('position') is None and j.get('velocity') is None:
            raise FrfIdentInputError(f"{jw} ({j['name']}): map position or velocity (or both)")
        for sig in SIGNALS:
            spec = j.get(sig)
            if spec is not None and isinstance(spec, dict):
                _unknown(spec, SIGNAL_KEYS, f'{jw}.{sig}')
                _check_signal(spec, f"{jw} ({j['name']}).{sig}")
        _check_units(j.get('units'), f"{jw} ({j['name']}).units")


def _check_signal(spec: dict[str, Any], where: str) -> None:
    """Types of a signal's ``derivative`` (bool) and ``row`` / ``col`` (0-based indices)."""
    if 'derivative' in spec:
        expect_bool(f'{where}.derivative', spec['derivative'])
    for key in ('row', 'col'):
        if spec.get(key) is not None:
            expect_int(f'{where}.{key}', spec[key], 0)


def _check_units(units: Any, where: str) -> None:
    """``units``: a mapping of signal names to unit names of :data:`UNITS`."""
    if units is None:
        return
    if not isinstance(units, dict):
        raise FrfIdentInputError(f'{where}={units!r}; expected a mapping like '
                                 f'{{position: rad, velocity: rad/s, effort: N m}}')
    _unknown(units, set(SIGNALS), where)
    for sig, unit in units.items():
        if not isinstance(unit, str) or unit not in UNITS:
            raise FrfIdentInputError(f'{where}.{sig}={unit!r}: unknown unit; expected one of '
                                     f'{", ".join(UNITS)}')


def _unknown(d: dict[str, Any], allowed: set[str], where: str) -> None:
    extra = sorted(set(d) - allowed)
    if extra:
        raise FrfIdentInputError(f'{where}: unknown field {extra[0]!r}; expected one of '
                                 f'{", ".join(sorted(allowed))}')
