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
Read a CSV or MATLAB .mat file into a :class:`Table` of raw columns or variables.

:func:`read_table` picks the reader from the suffix; :meth:`Table.column` returns one raw
column (CSV) or variable (MAT, a dotted path reaches into structs).
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
import io
import math
from pathlib import Path
from typing import Any

from frf_ident.core.model.fields import expect_bool
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.import_map import PathLike, UNITS
from frf_ident.io.yamlio import read_utf8
import numpy as np

__all__ = ['Table', 'read_table']


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
