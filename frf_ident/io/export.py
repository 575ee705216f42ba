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
Export a FrequencyResponse to other tools, and read it back.

The object is :class:`~frf_ident.core.estimation.frd.FrequencyResponse`.

Formats (chosen by the file suffix in :func:`write_frf` / :func:`read_frf`):

``.json``
    ``FrequencyResponse.to_dict()``: ``{inputs, outputs, freq_hz, re, im[, noise_variance,
    total_variance][, meta]}`` with re/im shaped (n_out, n_in, n_freq) — the same layout as
    ``frf-ident estimate``'s ``frf.json``.
``.mat``
    MATLAB v5 file ready for the System Identification Toolbox::

        S = load('frf.mat');
        G = idfrd(S.ResponseData, S.Frequency, 0, 'FrequencyUnit', S.FrequencyUnit, ...
                  'InputName', S.InputName, 'OutputName', S.OutputName);
        % with variances: G.CovarianceData = S.CovarianceData;

    Variables: ``ResponseData`` (ny, nu, nf) complex, ``Frequency`` (nf, 1) [Hz],
    ``FrequencyUnit`` 'Hz', ``InputName`` / ``OutputName`` (n, 1) cell arrays of char, ``Ts`` 0
    (continuous-time frequency axis), and when present ``NoiseVariance`` / ``TotalVariance``
    (ny, nu, nf) real (variance of the complex estimate, E|P_hat - P|^2) plus
    ``CovarianceData`` (ny, nu, nf, 2, 2): the covariance of [Re, Im] assuming a circular
    error (var / 2 on the diagonal), from the total variance if present, else the noise
    variance. ``Meta`` holds the JSON text of ``frf.meta``.
``.csv``
    Long format, one row per channel and frequency, header
    ``output,input,freq_hz,re,im[,noise_variance,total_variance]``; values with 17 significant
    digits (exact round trip); ``meta`` is not stored.

The python-control object comes from :func:`to_control` (``control.FrequencyResponseData``
with ``fresp`` = response, ``omega`` = 2 pi freq_hz, channel labels = names).
"""
from __future__ import annotations

import csv
import json
import os
from pathlib import Path
from typing import Any

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.jsonable import jsonable
from frf_ident.errors import FrfIdentInputError
import numpy as np

__all__ = ['CSV_COLUMNS', 'FORMATS', 'PathLike', 'VARIANCES', 'from_control', 'read_csv',
           'read_frf', 'read_json', 'read_mat', 'to_control', 'write_csv', 'write_frf',
           'write_json', 'write_mat']

PathLike = str | os.PathLike[str]
CSV_COLUMNS = ('output', 'input', 'freq_hz', 're', 'im')
VARIANCES = ('noise_variance', 'total_variance')
_MAT_VARIANCES = {'noise_variance': 'NoiseVariance', 'total_variance': 'TotalVariance'}


# --------------------------------------------------------------------------- python-control

def to_control(frf: FrequencyResponse):
    """
    Convert ``frf`` to a python-control ``FrequencyResponseData``.

    Parameters
    ----------
    frf : FrequencyResponse
        The response.

    Returns
    -------
    control.FrequencyResponseData
        Omega in rad/s, channels labelled with the names; variances are not kept.

    Raises
    ------
    ImportError
        The optional python-control package is not installed.

    """
    return frf.to_control()


def from_control(obj: Any) -> FrequencyResponse:
    """
    Convert a python-control ``FrequencyResponseData`` to a FrequencyResponse.

    Parameters
    ----------
    obj : control.FrequencyResponseData
        The response (omega in rad/s, channel labels).

    Returns
    -------
    FrequencyResponse
        Frequencies in Hz, the labels as names, no variances.

    """
    return FrequencyResponse.from_control(obj)


# --------------------------------------------------------------------------- JSON

def write_json(frf: FrequencyResponse, path: PathLike) -> Path:
    """
    Write ``frf.to_dict()`` as JSON (exact: floats are written with repr).

    Parameters
    ----------
    frf : FrequencyResponse
        The response.
    path : str or os.PathLike
        File to write (overwritten; :func:`write_frf` refuses existing files).

    Returns
    -------
    Path
        ``path``.

    """
    path = Path(path)
    path.write_text(json.dumps(frf.to_dict()) + '\n')
    return path


def read_json(path: PathLike) -> FrequencyResponse:
    """
    Read a JSON FRF written by :func:`write_json` or ``frf-ident estimate``.

    Parameters
    ----------
    path : str or os.PathLike
        The JSON file.

    Returns
    -------
    FrequencyResponse
        The response with its variances and ``meta``.

    Raises
    ------
    FrfIdentInputError
        The file cannot be read, is not a JSON object with ``freq_hz``, ``re`` and ``im``, or
        its shapes do not agree (the message names the file).

    """
    path = Path(path)
    try:
        d = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError) as exc:
        raise FrfIdentInputError(f'cannot read FRF file {str(path)!r}: {exc}') from None
    except json.JSONDecodeError as exc:
        raise FrfIdentInputError(f'FRF file {str(path)!r} is not valid JSON: {exc}') from None
    if not isinstance(d, dict):
        raise FrfIdentInputError(f'FRF file {str(path)!r}: expected a JSON object, '
                                 f'got {type(d).__name__}')
    for key in ('freq_hz', 're', 'im'):
        if key not in d:
            raise FrfIdentInputError(f'FRF file {str(path)!r} lacks the field {key!r} '
                                     f'(expected inputs, outputs, freq_hz, re, im)')
    return _build(path, lambda: FrequencyResponse.from_dict(d))


# --------------------------------------------------------------------------- MATLAB

def _cellstr(names: list[str]) -> np.ndarray:
    cell = np.empty((len(names), 1), dtype=object)
    for k, name in enumerate(names):
        cell[k, 0] = str(name)
    return cell


def write_mat(frf: FrequencyResponse, path: PathLike) -> Path:
    """
    Write a MATLAB v5 .mat file with the variables ``idfrd`` takes (see the module doc).

    Parameters
    ----------
    frf : FrequencyResponse
        The response.
    path : str or os.PathLike
        File to write (overwritten; :func:`write_frf` refuses existing files).

    Returns
    -------
    Path
        ``path``.

    """
    from scipy.io import savemat
    path = Path(path)
    data: dict[str, Any] = {
        'ResponseData': frf.response,
        'Frequency': frf.freq_hz.reshape(-1, 1),
        'FrequencyUnit': 'Hz',
        'InputName': _cellstr(frf.inputs),
        'OutputName': _cellstr(frf.outputs),
        'Ts': 0.0,
        'Meta': json.dumps(jsonable(frf.meta)),
    }
    for attr, var in _MAT_VARIANCES.items():
        if getattr(frf, attr) is not None:
            data[var] = getattr(frf, attr)
    var = frf.variance()
    if var is not None:
        cov = np.zeros(var.shape + (2, 2))
        cov[..., 0, 0] = cov[..., 1, 1] = 0.5 * var
        data['CovarianceData'] = cov
    savemat(path, data, do_compression=True, oned_as='column')
    return path


def _mat_names(path: Path, d: dict[str, Any], key: str, n: int) -> list[str]:
    if key not in d:
        return []
    names = [str(np.asarray(v).reshape(-1)[0]) if np.asarray(v).size else ''
             for v in np.asarray(d[key], dtype=object).reshape(-1)]
    if len(names) != n:
        raise FrfIdentInputError(f'FRF file {str(path)!r}: {key} has {len(names)} names, '
                                 f'ResponseData needs {n}')
    return names


def read_mat(path: PathLike) -> FrequencyResponse:
    """
    Read a .mat FRF written by :func:`write_mat` (or any file with ResponseData/Frequency).

    Parameters
    ----------
    path : str or os.PathLike
        The MAT file; ``FrequencyUnit`` 'rad/s' (or 'rad/TimeUnit') is converted to Hz.

    Returns
    -------
    FrequencyResponse
        The response with the variances and ``Meta`` the file holds.

    Raises
    ------
    FrfIdentInputError
        The file cannot be read, lacks ``ResponseData`` or ``Frequency``, has another
        frequency unit, or its names or shapes do not agree (the message names the file).

    """
    from scipy.io import loadmat
    path = Path(path)
    try:
        d = loadmat(path, squeeze_me=False)
    except Exception as exc:  # scipy raises several types for bad files
        raise FrfIdentInputError(f'cannot read MAT file {str(path)!r}: {exc}') from None
    for key in ('ResponseData', 'Frequency'):
        if key not in d:
            raise FrfIdentInputError(f'MAT file {str(path)!r} lacks the variable {key!r} '
                                     f'(expected ResponseData (ny, nu, nf) and Frequency)')
    resp = np.asarray(d['ResponseData'])
    freq = np.asarray(d['Frequency'], dtype=float).reshape(-1)
    if resp.ndim == 2 and resp.shape[1] == freq.size and resp.shape[0] == 1:
        resp = resp.reshape(1, 1, -1)
    unit = _mat_text(d.get('FrequencyUnit'), 'Hz')
    if unit in ('rad/s', 'rad/TimeUnit'):
        freq = freq / (2 * np.pi)
    elif unit != 'Hz':
        raise FrfIdentInputError(f'MAT file {str(path)!r}: FrequencyUnit={unit!r}; '
                                 f"expected 'Hz' or 'rad/s'")
    n_out, n_in = resp.shape[:2] if resp.ndim == 3 else (1, 1)
    meta = json.loads(_mat_text(d.get('Meta'), '{}') or '{}')
    var = {attr: (np.asarray(d[key], dtype=float).reshape(resp.shape) if key in d else None)
           for attr, key in _MAT_VARIANCES.items()}
    return _build(path, lambda: FrequencyResponse(
        freq, resp, _mat_names(path, d, 'InputName', n_in),
        _mat_names(path, d, 'OutputName', n_out), var['noise_variance'],
        var['total_variance'], meta))


def _mat_text(value: Any, default: str) -> str:
    if value is None:
        return default
    arr = np.asarray(value).reshape(-1)
    return str(arr[0]) if arr.size else default


# --------------------------------------------------------------------------- CSV

def write_csv(frf: FrequencyResponse, path: PathLike) -> Path:
    """
    Write the long-format CSV (one row per output, input and frequency).

    Parameters
    ----------
    frf : FrequencyResponse
        The response; its ``meta`` is not stored.
    path : str or os.PathLike
        File to write (overwritten; :func:`write_frf` refuses existing files).

    Returns
    -------
    Path
        ``path``.

    """
    path = Path(path)
    extra = [v for v in VARIANCES if getattr(frf, v) is not None]
    with path.open('w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(list(CSV_COLUMNS) + extra)
        for o, out in enumerate(frf.outputs):
            for i, inp in enumerate(frf.inputs):
                p = frf.response[o, i]
                cols = [getattr(frf, v)[o, i] for v in extra]
                for k, f in enumerate(frf.freq_hz):
                    w.writerow([out, inp, repr(float(f)), repr(float(p[k].real)),
                                repr(float(p[k].imag))] + [repr(float(c[k])) for c in cols])
    return path


def read_csv(path: PathLike) -> FrequencyResponse:
    """
    Read a long-format CSV FRF written by :func:`write_csv`.

    Channels are ordered by first appearance; every channel must list the same frequencies.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    FrequencyResponse
        The response with the variance columns the file has.

    Raises
    ------
    FrfIdentInputError
        The file cannot be read, is empty, lacks a column, holds a non-number, or its
        channels differ in frequencies or do not cover every output/input pair.

    """
    path = Path(path)
    try:
        with path.open(newline='') as fh:
            rows = list(csv.reader(fh))
    except (OSError, UnicodeDecodeError) as exc:
        raise FrfIdentInputError(f'cannot read CSV file {str(path)!r}: {exc}') from None
    if not rows:
        raise FrfIdentInputError(f'CSV file {str(path)!r} is empty')
    header = [h.strip() for h in rows[0]]
    missing = [c for c in CSV_COLUMNS if c not in header]
    if missing:
        raise FrfIdentInputError(f'CSV file {str(path)!r}: header lacks {missing}; expected '
                                 f'{",".join(CSV_COLUMNS)}[,noise_variance,total_variance]')
    col = {name: header.index(name) for name in header}
    extra = [v for v in VARIANCES if v in col]
    table: dict[tuple[str, str], list[list[float]]] = {}
    outputs: list[str] = []
    inputs: list[str] = []
    for line, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        out, inp = row[col['output']], row[col['input']]
        try:
            vals = [float(row[col[c]]) for c in ('freq_hz', 're', 'im', *extra)]
        except (ValueError, IndexError):
            raise FrfIdentInputError(f'CSV file {str(path)!r} line {line}: expected numbers in '
                                     f'freq_hz, re, im, got {row!r}') from None
        outputs += [out] if out not in outputs else []
        inputs += [inp] if inp not in inputs else []
        table.setdefault((out, inp), []).append(vals)
    return _csv_frf(path, table, outputs, inputs, extra)


def _csv_frf(path: Path, table: dict[tuple[str, str], list[list[float]]], outputs: list[str],
             inputs: list[str], extra: list[str]) -> FrequencyResponse:
    if not table:
        raise FrfIdentInputError(f'CSV file {str(path)!r} has no data rows')
    first = np.asarray(next(iter(table.values())))
    freq = first[:, 0]
    arr = np.full((len(outputs), len(inputs), freq.size, 3 + len(extra)), np.nan)
    for (out, inp), vals in table.items():
        v = np.asarray(vals)
        if v.shape[0] != freq.size or not np.array_equal(v[:, 0], freq):
            raise FrfIdentInputError(f'CSV file {str(path)!r}: channel {inp} -> {out} has '
                                     f'other frequencies than the first channel')
        arr[outputs.index(out), inputs.index(inp)] = v
    if np.isnan(arr[..., 1]).any():
        raise FrfIdentInputError(f'CSV file {str(path)!r}: not every output/input pair is '
                                 f'listed ({len(table)} of {len(outputs) * len(inputs)})')
    var = {v: arr[..., 3 + k] for k, v in enumerate(extra)}
    return _build(path, lambda: FrequencyResponse(
        freq, arr[..., 1] + 1j * arr[..., 2], inputs, outputs,
        var.get('noise_variance'), var.get('total_variance')))


# --------------------------------------------------------------------------- dispatch

FORMATS = {'.json': (write_json, read_json), '.mat': (write_mat, read_mat),
           '.csv': (write_csv, read_csv)}


def _format(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise FrfIdentInputError(f'FRF file {str(path)!r}: unknown format {suffix or "(none)"!r};'
                                 f' expected one of {", ".join(FORMATS)}')
    return suffix


def write_frf(frf: FrequencyResponse, path: PathLike, *, overwrite: bool = False) -> Path:
    """
    Write ``frf`` in the format given by the suffix of ``path`` (.json, .mat, .csv).

    Missing parent directories are created.

    Parameters
    ----------
    frf : FrequencyResponse
        The response.
    path : str or os.PathLike
        File to write; its suffix selects the format.
    overwrite : bool, optional
        Replace an existing file (default: refuse).

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    FrfIdentInputError
        The suffix is not .json, .mat or .csv, or the file exists and ``overwrite`` is
        false.

    """
    path = Path(path)
    writer = FORMATS[_format(path)][0]
    if path.exists() and not overwrite:
        raise FrfIdentInputError(f'{str(path)!r} exists; refusing to overwrite '
                                 f'(pass overwrite=True or choose another path)')
    path.parent.mkdir(parents=True, exist_ok=True)
    return writer(frf, path)


def read_frf(path: PathLike) -> FrequencyResponse:
    """
    Read an FRF file written by :func:`write_frf` (format from the suffix).

    Parameters
    ----------
    path : str or os.PathLike
        A .json, .mat or .csv file.

    Returns
    -------
    FrequencyResponse
        The response.

    Raises
    ------
    FrfIdentInputError
        The suffix is unknown, the file does not exist, or the reader refuses it (see
        :func:`read_json`, :func:`read_mat`, :func:`read_csv`).

    """
    path = Path(path)
    reader = FORMATS[_format(path)][1]
    if not path.is_file():
        raise FrfIdentInputError(f'FRF file {str(path)!r} does not exist')
    return reader(path)


def _build(path: Path, make) -> FrequencyResponse:
    """Run a FrequencyResponse constructor, turning shape errors into one input-error line."""
    try:
        return make()
    except FrfIdentInputError:
        raise
    except (ValueError, TypeError, KeyError) as exc:
        raise FrfIdentInputError(f'FRF file {str(path)!r}: {exc}') from None
