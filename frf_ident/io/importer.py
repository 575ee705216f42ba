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
Import measured data from other tools (CSV or MATLAB .mat tables) as a :class:`Recording`.

``frf-ident import FILE.csv|FILE.mat --map MAP.yaml --out BAG`` reads the table, applies the
map and writes a rosbag2 MCAP bag (:func:`frf_ident.bag.write_recording`, never overwriting).

Map file (YAML)
===============
::

    frf_ident_map: 1                  # format version (required)
    description: free text            # optional, copied into the recording's meta
    csv:                              # optional, CSV files only
      delimiter: ','                  #   default: sniffed among , ; tab, else whitespace
      header: true                    #   true/false; default: true when the first row is
                                      #   not numeric
    time:                             # either a time signal ...
      column: t                       #   CSV column name / 0-based index, or MAT variable
      scale: 1.0                      #   factor to seconds (e.g. 0.001 or ms for milliseconds)
      # sample_time: 0.001            # ... or a sample time [s]: t = start + k * sample_time
      # start: 0.0                    #   time of the first sample with sample_time [s]
      range: [0.0, 24.0]              # optional: keep samples with range[0] <= t <= range[1]
    joints:                           # one entry per joint / axis, in this order
      - name: joint_1                 # required, unique
        position: {column: q1, scale: deg}        # [rad] (or [m] for a prismatic axis)
        velocity: {column: dq1, scale: deg}       # [rad/s]; omit it to DIFFERENTIATE position
        effort: {column: tau1}                    # applied motor torque u [N m] (required)
        reference: {column: r1, scale: deg}       # optional velocity reference r [rad/s]
        excitation: {column: e1}                  # optional excitation part of r
        units: {position: rad, velocity: rad/s, effort: N m}   # optional, informational

Unknown keys are refused at every level; ``units`` values must be names of :data:`UNITS`;
boolean fields (``csv.header``, ``derivative``) take YAML ``true`` / ``false`` only. The map
and CSV files must be UTF-8 (a leading byte-order mark is dropped).

A *signal* is a column name (a plain string) or a mapping with

``column`` (alias ``variable``)
    CSV: header name or 0-based column index. MAT: variable name; a dotted path reaches
    into structs (``rec.act_pos_mot_deg``).
``row`` / ``col``
    0-based row or column (>= 0) of a 2-D MAT variable (time runs along the other
    dimension). A 1 x N or N x 1 vector accepts ``row: 0`` / ``col: 0`` (the MAT reader
    squeezes vectors and does not keep their orientation).
``scale``
    a number, a unit name converted to SI (``deg`` = pi/180, ``rpm``, ``mm``, ``ms``, ...;
    see :data:`UNITS`), the name of a scalar MAT variable (``gtau``), or a list of these
    multiplied together.
``offset``
    added after scaling.
``derivative``
    ``true``: differentiate after scaling (central differences, second-order one-sided at
    both ends), e.g. a position reference into a velocity reference.

Missing signals are derived and the derivation is recorded in ``Recording.meta['import']``:
no velocity -> central differences of position; no position -> trapezoidal integral of
velocity from 0. The time signal must be uniform (residual to a straight line below 5 % of a
sample); it is replaced by the exact grid ``t0 + k dt`` with dt snapped to whole nanoseconds
when that changes no time by more than 1 % of a sample. Negative times are shifted to start
at 0 (``meta['import']['time_shift_s']``).

Every problem is one :class:`FrfIdentInputError` line naming the file, field and value.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
import io
import math
import os
from pathlib import Path
from typing import Any, Callable

from frf_ident.core.model.fields import expect_bool, expect_int
from frf_ident.core.recording import Recording
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.layout import check_layout, layout_to_joints
from frf_ident.io.yamlio import read_utf8, read_yaml_file
import numpy as np

__all__ = ['CSV_KEYS', 'JOINT_KEYS', 'PathLike', 'SIGNALS', 'SIGNAL_KEYS', 'TIME_KEYS',
           'TOP_KEYS', 'Table', 'UNITS', 'check_map', 'import_table', 'load_map', 'read_table']

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


# --------------------------------------------------------------------------- tables

@dataclass
class Table:
    """
    A loaded CSV or MAT file; :meth:`column` returns its raw arrays.

    Made by :func:`read_table`.

    Parameters
    ----------
    path : Path
        The file (named in error messages).
    kind : {'csv', 'mat'}
        The format.
    data : ndarray or dict
        CSV: the values, shape (rows, columns), NaN for empty fields. MAT: the variables as
        ``scipy.io.loadmat`` returns them (squeezed, structs as objects).
    header : list of str, optional
        CSV column names, None without a header row.

    """

    path: Path
    kind: str  # 'csv' | 'mat'
    data: Any
    header: list[str] | None = None

    def name(self) -> str:
        """
        Return the file name used in error messages.

        Returns
        -------
        str
            The path as text.

        """
        return str(self.path)

    def column(self, ref: Any, where: str) -> np.ndarray:
        """
        Return the raw CSV column or MAT variable named by ``ref``.

        Parameters
        ----------
        ref : str or int
            CSV: header name or 0-based column index. MAT: variable name, a dotted path
            reaching into structs.
        where : str
            The map field being read, for error messages.

        Returns
        -------
        ndarray
            The column (CSV) or the variable as a float array (MAT, any shape).

        Raises
        ------
        FrfIdentInputError
            ``ref`` is not found, out of range or not numeric (the message names the file,
            the field and what exists).

        """
        return self._csv_column(ref, where) if self.kind == 'csv' else self._mat_var(ref, where)

    def _csv_column(self, ref: Any, where: str) -> np.ndarray:
        ncol = self.data.shape[1]
        if isinstance(ref, bool) or not isinstance(ref, (int, str)):
            raise FrfIdentInputError(f'{where}: column={ref!r} must be a header name or a '
                                     f'0-based index in {self.name()}')
        if isinstance(ref, int):
            if not 0 <= ref < ncol:
                raise FrfIdentInputError(f'{where}: column={ref} is out of range: '
                                         f'{self.name()} has {ncol} columns (0-based)')
            return self.data[:, ref]
        if self.header is None or ref not in self.header:
            have = 'no header row' if self.header is None else \
                f'columns {", ".join(self.header[:12])}{" ..." if ncol > 12 else ""}'
            raise FrfIdentInputError(f'{where}: column={ref!r} not found in {self.name()} '
                                     f'({have})')
        return self.data[:, self.header.index(ref)]

    def _mat_var(self, ref: Any, where: str) -> np.ndarray:
        if not isinstance(ref, str) or not ref:
            raise FrfIdentInputError(f'{where}: variable={ref!r} must be a MAT variable name '
                                     f'(dotted path into structs) in {self.name()}')
        obj: Any = self.data
        done: list[str] = []
        for part in ref.split('.'):
            if not (isinstance(obj, dict) or hasattr(obj, '_fieldnames')):
                raise FrfIdentInputError(f'{where}: variable={ref!r} not found in '
                                         f'{self.name()}: {".".join(done)} is not a struct '
                                         f'(it is {_describe(obj)}), so it has no field '
                                         f'{part!r}')
            obj = _mat_member(obj, part)
            if obj is None:
                scope = '.'.join(done) or 'the file'
                raise FrfIdentInputError(f'{where}: variable={ref!r} not found in '
                                         f'{self.name()} (no {part!r} in {scope}; it has '
                                         f'{", ".join(_mat_members(self.data, done)[:15])})')
            done.append(part)
        if np.iscomplexobj(obj):
            raise FrfIdentInputError(f'{where}: variable={ref!r} in {self.name()} is complex; '
                                     f'expected real samples (map its real part into a '
                                     f'variable of its own)')
        try:
            return np.asarray(obj, dtype=float)
        except (TypeError, ValueError):
            raise FrfIdentInputError(f'{where}: variable={ref!r} in {self.name()} is not '
                                     f'numeric ({type(obj).__name__})') from None

    def scalar(self, ref: str, where: str) -> float:
        """
        Return a scalar MAT variable used as a scale factor.

        Parameters
        ----------
        ref : str
            Variable name (dotted path into structs).
        where : str
            The map field being read, for error messages.

        Returns
        -------
        float
            The value.

        Raises
        ------
        FrfIdentInputError
            The table is a CSV file (no variables), or the variable is missing, not numeric
            or not one finite value.

        """
        if self.kind != 'mat':
            raise FrfIdentInputError(f'{where}: scale={ref!r} is not a unit '
                                     f'({", ".join(UNITS)}) and {self.name()} has no variables')
        v = self._mat_var(ref, where)
        if v.size != 1:
            raise FrfIdentInputError(f'{where}: scale variable {ref!r} in {self.name()} must be '
                                     f'a scalar, got shape {v.shape}')
        value = float(v.reshape(-1)[0])
        if not math.isfinite(value):
            raise FrfIdentInputError(f'{where}: scale variable {ref!r} in {self.name()} is not '
                                     f'finite ({value}); expected a finite number')
        return value


def _describe(obj: Any) -> str:
    """Short description of a MAT value for messages, e.g. ``a 6x2501 double array``."""
    if isinstance(obj, np.ndarray):
        shape = 'x'.join(str(n) for n in obj.shape) or 'scalar'
        return f'a {shape} {obj.dtype} array'
    return f'a {type(obj).__name__}'


def _mat_member(obj: Any, part: str) -> Any:
    if isinstance(obj, dict):
        return obj.get(part)
    if hasattr(obj, '_fieldnames'):
        return getattr(obj, part, None) if part in obj._fieldnames else None
    return None


def _mat_members(data: dict[str, Any], path: list[str]) -> list[str]:
    obj: Any = data
    for part in path:
        obj = _mat_member(obj, part)
    if isinstance(obj, dict):
        return [k for k in obj if not k.startswith('__')]
    return list(getattr(obj, '_fieldnames', []))


def read_table(path: PathLike, csv_options: dict[str, Any] | None = None) -> Table:
    """
    Load a .csv or .mat file (format from the suffix).

    Parameters
    ----------
    path : str or os.PathLike
        The file: .mat, or .csv / .txt / .tsv / .dat for text tables.
    csv_options : dict, optional
        The map's ``csv`` section (``delimiter``, ``header``); default: sniffed.

    Returns
    -------
    Table
        The loaded table.

    Raises
    ------
    FrfIdentInputError
        The file does not exist, has an unknown suffix or cannot be parsed (MATLAB v7.3,
        ragged or non-numeric CSV rows, a bad delimiter).

    """
    path = Path(path)
    if not path.is_file():
        raise FrfIdentInputError(f'data file {str(path)!r} does not exist')
    suffix = path.suffix.lower()
    if suffix == '.mat':
        return _read_mat(path)
    if suffix in ('.csv', '.txt', '.tsv', '.dat'):
        return _read_csv(path, csv_options or {})
    raise FrfIdentInputError(f'data file {str(path)!r}: unknown format {suffix or "(none)"!r}; '
                             f'expected .csv or .mat')


def _read_mat(path: Path) -> Table:
    from scipy.io import loadmat
    try:
        data = loadmat(path, squeeze_me=True, struct_as_record=False)
    except NotImplementedError:
        raise FrfIdentInputError(f'MAT file {str(path)!r} is MATLAB v7.3 (HDF5); save it with '
                                 f"save(..., '-v7') or export a CSV") from None
    except Exception as exc:  # scipy raises several types for damaged files
        raise FrfIdentInputError(f'cannot read MAT file {str(path)!r}: {exc}') from None
    return Table(path, 'mat', data)


def _read_csv(path: Path, opts: dict[str, Any]) -> Table:
    text = read_utf8(path, 'CSV file')   # utf-8-sig: Excel's "CSV UTF-8" starts with a BOM
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith('#')]
    if not lines:
        raise FrfIdentInputError(f'CSV file {str(path)!r} has no data')
    rows = _split_rows(lines, opts.get('delimiter'), path)
    header_opt = opts.get('header')
    if header_opt is not None:
        header_opt = expect_bool('map field csv.header', header_opt)
    has_header = header_opt if header_opt is not None else not _numeric_row(rows[0])
    header = [h.strip() for h in rows[0]] if has_header else None
    body = rows[1:] if has_header else rows
    width = len(rows[0])
    values = np.empty((len(body), width))
    first = 2 if has_header else 1
    for k, row in enumerate(body):
        if len(row) != width:
            raise FrfIdentInputError(f'CSV file {str(path)!r} data row {k + first}: '
                                     f'{len(row)} fields, the first row has {width}')
        try:
            values[k] = [float(v) if v.strip() else np.nan for v in row]
        except ValueError:
            raise FrfIdentInputError(f'CSV file {str(path)!r} data row {k + first}: '
                                     f'non-numeric value in {row!r}') from None
    return Table(path, 'csv', values, header)


def _split_rows(lines: list[str], delimiter: str | None, path: Path) -> list[list[str]]:
    if delimiter is None:
        delimiter = _guess_delimiter(lines[:20])
    if delimiter is None or delimiter == ' ':
        return [ln.split() for ln in lines]
    if not isinstance(delimiter, str) or len(delimiter) != 1:
        raise FrfIdentInputError(f'map field csv.delimiter={delimiter!r} must be one character '
                                 f'(reading {str(path)!r})')
    return list(csv.reader(io.StringIO('\n'.join(lines)), delimiter=delimiter))


def _guess_delimiter(lines: list[str]) -> str | None:
    """
    Guess the CSV delimiter.

    The first of , ; tab that occurs equally often (and at all) in every sampled line, else
    the one most frequent in the first line, else None (whitespace).
    """
    cands = (',', ';', '\t')
    for cand in cands:
        counts = {ln.count(cand) for ln in lines}
        if len(counts) == 1 and counts.pop() > 0:
            return cand
    best = max(cands, key=lines[0].count)
    return best if lines[0].count(best) else None


def _numeric_row(row: list[str]) -> bool:
    try:
        [float(v) for v in row if v.strip()]
    except ValueError:
        return False
    return True


# --------------------------------------------------------------------------- map

def load_map(path: PathLike) -> dict[str, Any]:
    """
    Read and check a map file (see the module docstring for the format).

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


# --------------------------------------------------------------------------- signals

def _signal(table: Table, spec: Any, where: str, n: int | None) -> np.ndarray:
    """Raw (N,) samples of one mapped signal, scaled and offset (not differentiated)."""
    if isinstance(spec, (str, int)) and not isinstance(spec, bool):
        spec = {'column': spec}
    if not isinstance(spec, dict):
        raise FrfIdentInputError(f'{where}={spec!r}: expected a column name or a mapping '
                                 f'with column, scale, ...')
    ref = spec.get('column', spec.get('variable'))
    if ref is None:
        raise FrfIdentInputError(f'{where}: needs column (or variable)')
    x = _select(table.column(ref, where), spec, f'{where} ({table.kind} {ref!r})', table, n)
    x = x * _scale(table, spec.get('scale', 1.0), f'{where}.scale')
    off = spec.get('offset', 0.0)
    if isinstance(off, bool) or not isinstance(off, (int, float)) or not math.isfinite(off):
        raise FrfIdentInputError(f'{where}.offset={off!r} must be a finite number')
    return x + float(off)


def _select(v: np.ndarray, spec: dict[str, Any], where: str, table: Table,
            n: int | None) -> np.ndarray:
    row, col = spec.get('row'), spec.get('col')      # integers >= 0: check_map
    if row is not None and col is not None:
        raise FrfIdentInputError(f'{where}: give row or col, not both')
    if v.ndim == 2 and (row is not None or col is not None):
        axis, idx = (0, row) if row is not None else (1, col)
        if not 0 <= idx < v.shape[axis]:
            key = 'row' if axis == 0 else 'col'
            raise FrfIdentInputError(f'{where}: {key}={idx} is out of range for shape '
                                     f'{v.shape} (0-based)')
        v = v[idx] if axis == 0 else v[:, idx]
    elif v.ndim == 1 and table.kind == 'mat' and (row is not None or col is not None):
        # the MAT reader squeezes 1 x N and N x 1 variables to (N,): index 0 is the vector
        key, idx = ('row', row) if row is not None else ('col', col)
        if idx != 0:
            raise FrfIdentInputError(f'{where}: {key}={idx} is out of range: the variable is '
                                     f'a vector (1 x {v.size} or {v.size} x 1); use {key} 0 '
                                     f'or omit it')
    elif row is not None or col is not None:
        raise FrfIdentInputError(f'{where}: row/col given but the data has shape {v.shape}')
    if v.ndim != 1:
        hint = ' (give row or col)' if v.ndim == 2 else ''
        raise FrfIdentInputError(f'{where}: shape {v.shape} is not a signal{hint}')
    if n is not None and v.size != n:
        raise FrfIdentInputError(f'{where}: {v.size} samples, the time signal of '
                                 f'{table.name()} has {n}')
    return v.astype(float)


def _scale(table: Table, scale: Any, where: str) -> float:
    items = scale if isinstance(scale, list) else [scale]
    factor = 1.0
    for item in items:
        if isinstance(item, bool):
            raise FrfIdentInputError(f'{where}={item!r}: expected a number, unit or variable')
        if isinstance(item, (int, float)):
            value = float(item)
        elif isinstance(item, str):
            value = UNITS[item] if item in UNITS else table.scalar(item, where)
        else:
            raise FrfIdentInputError(f'{where}={item!r}: expected a number, unit or variable')
        if not math.isfinite(value) or value == 0:
            raise FrfIdentInputError(f'{where}={item!r} gives {value}; need finite, non-zero')
        factor *= value
    return factor


# --------------------------------------------------------------------------- time

def _time_axis(table: Table, spec: dict[str, Any], n_rows: int,
               where: str) -> np.ndarray:
    """Measured (or generated) sample times [s]."""
    if 'sample_time' in spec:
        dt, t0 = spec['sample_time'], spec.get('start', 0.0)
        for key, val in (('sample_time', dt), ('start', t0)):
            if isinstance(val, bool) or not isinstance(val, (int, float)) \
                    or not math.isfinite(val):
                raise FrfIdentInputError(f'{where}.{key}={val!r} must be a finite number [s]')
        if dt <= 0:
            raise FrfIdentInputError(f'{where}.sample_time={dt!r} must be positive [s]')
        return float(t0) + np.arange(n_rows) * float(dt)
    return _signal(table, {k: v for k, v in spec.items() if k not in ('range', 'start')},
                   where, None)


def _time_source(spec: dict[str, Any], table: Table) -> str:
    """Where the time comes from, for messages: ``column 't' in d.csv``."""
    if 'sample_time' in spec:
        return f"sample_time={spec['sample_time']!r} s"
    key = 'column' if 'column' in spec else 'variable'
    return f'{key} {spec[key]!r} in {table.name()}'


def _uniform_grid(t: np.ndarray, where: str) -> tuple[np.ndarray, float]:
    """Exact grid t0 + k dt replacing a measured uniform time vector. Returns (t, dt)."""
    n = t.size
    if n < 3:
        raise FrfIdentInputError(f'{where}: {n} samples; need at least 3')
    if not np.all(np.isfinite(t)):
        raise FrfIdentInputError(f'{where}: {int(np.sum(~np.isfinite(t)))} non-finite times')
    steps = np.diff(t)
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0])
        raise FrfIdentInputError(f'{where}: time does not increase at sample {k + 1} '
                                 f'(t={float(t[k]):.9g} s -> {float(t[k + 1]):.9g} s)')
    k = np.arange(n, dtype=float)
    dt, t0 = np.polyfit(k, t, 1)
    res = t - (t0 + dt * k)
    worst = int(np.argmax(np.abs(res)))
    if abs(res[worst]) > 0.05 * dt:
        raise FrfIdentInputError(
            f'{where}: time is not uniformly sampled: sample {worst} (t={t[worst]:.6g} s) is '
            f'{abs(res[worst]) / dt:.2f} samples off the grid dt={dt:.6g} s (a gap or jitter); '
            f'use time.range to import a uniform part')
    dt_ns = round(dt * 1e9) * 1e-9
    if dt_ns > 0 and abs(dt_ns - dt) * n < 0.01 * dt:
        dt = dt_ns
    t0 = round(float(t[0]) * 1e9) * 1e-9
    return t0 + np.arange(n) * dt, float(dt)


def _derivative(x: np.ndarray, dt: float) -> np.ndarray:
    """Central differences inside, second-order one-sided differences at both ends."""
    return np.gradient(x, dt, edge_order=2)


def _integral(v: np.ndarray, dt: float) -> np.ndarray:
    """Trapezoidal integral from 0."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)])


# --------------------------------------------------------------------------- import

def import_table(path: PathLike, map: dict[str, Any] | PathLike) -> Recording:  # noqa: A002
    """
    Read a CSV or MAT table with a map (dict or YAML path) into a :class:`Recording`.

    ``Recording.meta['import']`` records the source, the map, the time handling and which
    signals were derived (e.g. velocity by central differences of position).

    Parameters
    ----------
    path : str or os.PathLike
        The data file (.csv or .mat).
    map : dict or str or os.PathLike
        The map (see the module docstring), or the path of its YAML file.

    Returns
    -------
    Recording
        Uniformly sampled signals of the mapped joints, without experiment segments.

    Raises
    ------
    FrfIdentInputError
        The map or data are unusable: a missing or non-numeric signal, a wrong length,
        non-finite values, a non-uniform time signal (the message names file, field and
        value).

    """
    if isinstance(map, dict):
        mp, map_name = map, 'map'
        check_map(mp, map_name)
    else:
        mp, map_name = load_map(map), str(map)       # load_map checks it
    table = read_table(path, mp.get('csv'))
    tspec = mp['time']
    joints, layout = (mp['joints'], None) if 'joints' in mp else layout_to_joints(mp)
    n_rows = table.data.shape[0] if table.kind == 'csv' else None
    if n_rows is None and 'sample_time' in tspec:   # MAT: the first channel's signal sets N
        first = joints[0].get('effort', joints[0].get('velocity'))
        n_rows = _signal(table, first, f'{map_name}: {joints[0]["name"]}', None).size
    t_raw = _time_axis(table, tspec, n_rows, f'{map_name}: time')
    keep = _time_range(t_raw, tspec.get('range'), f'{map_name}: time.range')
    t, dt = _uniform_grid(t_raw[keep], f'{map_name}: time ({_time_source(tspec, table)})')
    shift = 0.0
    if t[0] < 0:
        shift, t = -float(t[0]), t - t[0]
    info: dict[str, Any] = {'source': os.path.basename(table.name()), 'format': table.kind,
                            'map': mp, 'dt_s': dt, 'samples': int(t.size), 'derived': {}}
    if shift:
        info['time_shift_s'] = shift
    if tspec.get('range') is not None:
        info['time_range_s'] = [float(t_raw[keep][0]), float(t_raw[keep][-1])]
    cols = {sig: np.full((t.size, len(joints)), np.nan) for sig in SIGNALS}
    for j, joint in enumerate(joints):
        if layout is not None:
            _layout_channel(table, joint, j, t_raw.size, keep, dt, cols, info, map_name)
        else:
            _import_joint(table, joint, j, t_raw.size, keep, dt, cols, info, map_name)
    meta = {'import': info}
    if mp.get('description'):
        meta['description'] = str(mp['description'])
    units = {jt['name']: jt['units'] for jt in joints if jt.get('units')}
    if layout is not None:
        meta['layout'] = layout
        units = {**{c['name']: {'effort': c['unit']} for c in layout['inputs']},
                 **{c['name']: {'velocity': c['unit']} for c in layout['outputs']}}
    if units:
        meta['units'] = units
    return Recording(t, [jt['name'] for jt in joints], cols['position'], cols['velocity'],
                     cols['effort'], _optional(cols['reference']), _optional(cols['excitation']),
                     [], meta)


def _time_range(t: np.ndarray, rng: Any, where: str) -> np.ndarray:
    if rng is None:
        return np.ones(t.size, dtype=bool)
    ok = (isinstance(rng, list) and len(rng) == 2
          and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in rng)
          and rng[0] < rng[1])
    if not ok:
        raise FrfIdentInputError(f'{where}={rng!r}; expected [start, end] in seconds, '
                                 f'start < end')
    keep = (t >= rng[0]) & (t <= rng[1])
    if keep.sum() < 3:
        raise FrfIdentInputError(f'{where}={rng!r} keeps {int(keep.sum())} samples of the data '
                                 f'spanning {t[0]:.6g} .. {t[-1]:.6g} s')
    return keep


def _import_joint(table: Table, joint: dict[str, Any], j: int, n: int, keep: np.ndarray,
                  dt: float, cols: dict[str, np.ndarray], info: dict[str, Any],
                  map_name: str, derive: bool = True) -> None:
    name = joint['name']
    for sig in SIGNALS:
        spec = joint.get(sig)
        if spec is None:
            continue
        where = f'{map_name}: joints[{j}] ({name}).{sig}'
        x = _signal(table, spec, where, n)[keep]
        if isinstance(spec, dict) and spec.get('derivative'):    # a bool: check_map
            x = _derivative(x, dt)
            info['derived'][f'{name}.{sig}'] = 'central differences of the mapped signal'
        bad = ~np.isfinite(x)
        if bad.any():
            raise FrfIdentInputError(f'{where}: {int(bad.sum())} non-finite values (first at '
                                     f'sample {int(np.flatnonzero(bad)[0])}) in '
                                     f'{table.name()}')
        cols[sig][:, j] = x
    if derive:
        _derive(cols, j, dt, name, info)


def _layout_channel(table: Table, joint: dict[str, Any], j: int, n: int, keep: np.ndarray,
                    dt: float, cols: dict[str, np.ndarray], info: dict[str, Any],
                    map_name: str) -> None:
    """
    Read one input or output of a layout; the signals it does not have are zero.

    Nothing is derived as for a joint (a sensor's signal is no joint velocity whose position
    a robot would have): only the ``derive`` the map asks for.
    """
    name = joint['name']
    _import_joint(table, {k: v for k, v in joint.items() if k != 'derive_steps'}, j, n, keep,
                  dt, cols, info, map_name, derive=False)
    steps = joint['derive_steps']
    x = cols['velocity'][:, j]
    for _ in range(abs(steps)):
        x = _derivative(x, dt) if steps > 0 else _integral(x - np.mean(x), dt)
    if steps:
        cols['velocity'][:, j] = x
        info['derived'][f'{name}.output'] = (f'{abs(steps)} time '
                                             f'{"derivative" if steps > 0 else "integral"}(s) '
                                             f'of the measured signal')
    for sig in ('position', 'velocity', 'effort'):
        col = cols[sig][:, j]
        if np.isnan(col).all():
            cols[sig][:, j] = 0.0


def _derive(cols: dict[str, np.ndarray], j: int, dt: float, name: str,
            info: dict[str, Any]) -> None:
    derive: dict[str, tuple[str, Callable[[np.ndarray, float], np.ndarray], str]] = {
        'velocity': ('position', _derivative, 'central differences of position'),
        'position': ('velocity', _integral, 'trapezoidal integral of velocity from 0'),
    }
    for target, (source, fn, text) in derive.items():
        if np.isnan(cols[target][:, j]).all() and not np.isnan(cols[source][:, j]).all():
            cols[target][:, j] = fn(cols[source][:, j], dt)
            info['derived'][f'{name}.{target}'] = text


def _optional(a: np.ndarray) -> np.ndarray | None:
    return None if np.isnan(a).all() else a
