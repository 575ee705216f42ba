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
One mapped signal and the time grid, read from a :class:`~frf_ident.io.table.Table`.

:func:`mapped_signal` selects, scales and offsets a column or variable; :func:`time_axis`,
:func:`time_range` and :func:`uniform_grid` turn the time signal into the exact uniform grid;
:func:`derivative` and :func:`integral` derive a missing signal.
"""
from __future__ import annotations

import math
from typing import Any

from frf_ident.errors import FrfIdentInputError
from frf_ident.io.import_map import UNITS
from frf_ident.io.table import Table
import numpy as np

__all__ = ['derivative', 'integral', 'mapped_signal', 'time_axis', 'time_range', 'time_source',
           'uniform_grid']


def mapped_signal(table: Table, spec: Any, where: str, n: int | None) -> np.ndarray:
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

def time_axis(table: Table, spec: dict[str, Any], n_rows: int,
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
    return mapped_signal(table, {k: v for k, v in spec.items() if k not in ('range', 'start')},
                         where, None)


def time_source(spec: dict[str, Any], table: Table) -> str:
    """Where the time comes from, for messages: ``column 't' in d.csv``."""
    if 'sample_time' in spec:
        return f"sample_time={spec['sample_time']!r} s"
    key = 'column' if 'column' in spec else 'variable'
    return f'{key} {spec[key]!r} in {table.name()}'


def uniform_grid(t: np.ndarray, where: str) -> tuple[np.ndarray, float]:
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


def derivative(x: np.ndarray, dt: float) -> np.ndarray:
    """Central differences inside, second-order one-sided differences at both ends."""
    return np.gradient(x, dt, edge_order=2)


def integral(v: np.ndarray, dt: float) -> np.ndarray:
    """Trapezoidal integral from 0."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)])


def time_range(t: np.ndarray, rng: Any, where: str) -> np.ndarray:
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
