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

This module assembles the recording from the mapped signals; the map's fields, unit names and
checks live in :mod:`frf_ident.io.import_map`, reading the file in :mod:`frf_ident.io.table`,
one mapped signal and the time grid in :mod:`frf_ident.io.table_signals`.
"""
from __future__ import annotations

import os
from typing import Any, Callable

from frf_ident.core.recording import Recording
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.import_map import check_map, load_map, PathLike, SIGNALS, UNITS
from frf_ident.io.layout import layout_to_joints
from frf_ident.io.table import read_table, Table
from frf_ident.io.table_signals import (derivative, integral, mapped_signal, time_axis,
                                        time_range, time_source, uniform_grid)
import numpy as np

#: ``UNITS`` stays importable from here: docs/import_maps.md names it by this module path.
__all__ = ['UNITS', 'import_table']


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
        n_rows = mapped_signal(table, first, f'{map_name}: {joints[0]["name"]}', None).size
    t_raw = time_axis(table, tspec, n_rows, f'{map_name}: time')
    keep = time_range(t_raw, tspec.get('range'), f'{map_name}: time.range')
    t, dt = uniform_grid(t_raw[keep], f'{map_name}: time ({time_source(tspec, table)})')
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


def _import_joint(table: Table, joint: dict[str, Any], j: int, n: int, keep: np.ndarray,
                  dt: float, cols: dict[str, np.ndarray], info: dict[str, Any],
                  map_name: str, derive: bool = True) -> None:
    name = joint['name']
    for sig in SIGNALS:
        spec = joint.get(sig)
        if spec is None:
            continue
        where = f'{map_name}: joints[{j}] ({name}).{sig}'
        x = mapped_signal(table, spec, where, n)[keep]
        if isinstance(spec, dict) and spec.get('derivative'):    # a bool: check_map
            x = derivative(x, dt)
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
        x = derivative(x, dt) if steps > 0 else integral(x - np.mean(x), dt)
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
        'velocity': ('position', derivative, 'central differences of position'),
        'position': ('velocity', integral, 'trapezoidal integral of velocity from 0'),
    }
    for target, (source, fn, text) in derive.items():
        if np.isnan(cols[target][:, j]).all() and not np.isnan(cols[source][:, j]).all():
            cols[target][:, j] = fn(cols[source][:, j], dt)
            info['derived'][f'{name}.{target}'] = text


def _optional(a: np.ndarray) -> np.ndarray | None:
    return None if np.isnan(a).all() else a
