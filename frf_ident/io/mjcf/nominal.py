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
A model file naming an MJCF (``mjcf: robot.xml``): its mapping in our parameters.

The model file gives the MJCF, the ``pose``, the axes by joint name and the controller gains;
:func:`view_dict` fills every axis with the MJCF's values at rest at the pose
(:func:`~frf_ident.io.mjcf.linear.axis_values`) and ``link_coupling`` with M(q), so the
commands that take a model (``fit``, ``loop``, the plans' safety check) read it as they read a
YAML model; ``identify`` simulates the MJCF itself (``--plant mujoco``), and
:func:`~frf_ident.io.mjcf.linear.nominal_frf` is its nominal FRF.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from frf_ident.core.model.schema import mjcf_source_from_dict
from frf_ident.errors import MjcfError
from frf_ident.io.mjcf.linear import axis_values
from frf_ident.io.mjcf.robot import load_robot, MjcfRobot

__all__ = ['MJCF_AXIS_KEYS', 'load_mjcf_robot', 'view_dict']

#: the axis keys a model file with ``mjcf`` may give: the rest comes from the MJCF
#: (``torque_limit`` may lower the MJCF's; the others are the measurement's, not the MJCF's)
MJCF_AXIS_KEYS = ('name', 'torque_limit', 'encoder_resolution', 'velocity_noise',
                  'torque_noise')


def load_mjcf_robot(d: dict[str, Any]) -> MjcfRobot:
    """Return the prepared MJCF of a model mapping with ``mjcf`` (its path already resolved)."""
    src = mjcf_source_from_dict(d)
    names = [str(a.get('name')) for a in d['axes']]
    return load_robot(src, names)


def view_dict(d: dict[str, Any], base: Path) -> dict[str, Any]:
    """
    Return the model mapping with every axis filled from the MJCF (its path made absolute).

    Parameters
    ----------
    d : dict
        The model file's mapping, with ``mjcf``.
    base : Path
        The model file's folder (``mjcf`` is relative to it).

    Returns
    -------
    dict
        A §5 mapping that :func:`~frf_ident.core.model.schema.robot_from_dict` reads.

    Raises
    ------
    MjcfError
        An axis gives a drive key (the MJCF holds it) or has no name; the MJCF does not fit.

    """
    out = dict(d)
    if not isinstance(d.get('mjcf'), str):
        raise MjcfError(f'mjcf: expected the path of an MJCF file, got {d.get("mjcf")!r}')
    out['mjcf'] = str((base / d['mjcf']).resolve())
    axes = d.get('axes')
    if not isinstance(axes, list) or not axes:
        raise MjcfError(f'axes: expected a non-empty list of {{name: <MJCF joint>}}, got '
                        f'{axes!r}')
    for i, a in enumerate(axes):
        if not isinstance(a, dict) or 'name' not in a:
            raise MjcfError(f'axes[{i}]: expected a mapping with the name of an MJCF joint, '
                            f'got {a!r}')
        extra = sorted(set(a) - set(MJCF_AXIS_KEYS))
        if extra:
            raise MjcfError(f'axes[{i}] ({a["name"]}): {extra} come from the MJCF with mjcf: '
                            f'(docs/mujoco.md); a model file with mjcf takes only '
                            f'{list(MJCF_AXIS_KEYS)}')
    if 'link_coupling' in d:
        raise MjcfError('link_coupling: comes from the MJCF (its M(q) at the pose) with mjcf:')
    robot = load_mjcf_robot(out)
    fs = float(d.get('sample_rate', 1000.0))
    robot.substeps(1.0 / fs)
    values, inertia = axis_values(robot, fs)
    merged = []
    for a, v in zip(axes, values):
        entry = dict(v)
        for key in MJCF_AXIS_KEYS[2:]:
            if key in a:
                entry[key] = a[key]
        if 'torque_limit' in a:
            entry['torque_limit'] = min(float(a['torque_limit']), entry['torque_limit'])
        merged.append(entry)
    out['axes'] = merged
    out['link_coupling'] = inertia.tolist()
    # the start pose written out joint by joint: the controller starts with the axes' holding
    # torque, and another MJCF of the same robot (--plant mujoco:FILE.xml) starts there too
    out['pose'] = dict(robot.pose)
    return out
