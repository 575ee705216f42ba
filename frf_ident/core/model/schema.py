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
The model-file structure (docs/CONTRACT.md §5) as plain dicts <-> typed parameters.

Parsing text (YAML) lives in :mod:`frf_ident.io.model_file`; this module only validates and
converts the loaded mapping, so the core stays free of I/O. Every error names the field and
what was expected.

Extensions beyond the contract (all optional, documented in docs/model_file.md):
- top level ``link_coupling``: symmetric n x n off-diagonal link inertia [kg m^2]
- top level ``simulation``: {substeps, velocity_from_encoder, seed}
- per axis ``gravity_torque``, ``gravity`` (configuration-dependent load, list of
  {amplitude, phase, joints}), ``encoder_resolution``, ``velocity_noise``, ``torque_noise``,
  ``second_mode`` ({frequency_hz, damping_ratio, inertia}: a link-side mass on a spring),
  ``urdf_inertia``, ``urdf_gravity`` (the axis' shares of the top-level ``urdf``'s inertia and
  Coriolis torque and of its gravity)
- top level ``urdf``: the robot's URDF (path), for ``urdf_inertia`` and ``urdf_gravity``
- ``controller.filters``: {axis name: list of second-order sections [b0, b1, b2, 1, a1, a2]}
  on the measured velocity, discrete at ``sample_rate`` (what ``frf-ident tune`` writes;
  :func:`controller_filters`, :func:`check_sections`)
"""
from __future__ import annotations

import copy
from dataclasses import asdict, fields
import math
from typing import Any

from frf_ident.core.model.fields import expect_bool, expect_int
from frf_ident.core.model.params import (
    AxisParams, MjcfSource, RobotParams, SECOND_MODE_KEYS, UrdfSource)
from frf_ident.errors import ModelFileError
import numpy as np

MODEL_VERSION = 1
_AXIS_KEYS = {f.name for f in fields(AxisParams)}
_TOP_KEYS = {'frf_ident_model', 'sample_rate', 'axes', 'controller', 'link_coupling',
             'simulation', 'description', 'mjcf', 'pose', 'urdf'}
_SIM_KEYS = {'substeps', 'velocity_from_encoder', 'seed'}
_CONTROLLER_KEYS = {'kind', 'kp', 'ki', 'filters'}
#: a pass-through section: pads an axis with fewer sections than another
PASS_SECTION = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
#: a filter chain must pass DC within this share: a velocity feedback that does not (a
#: high-pass, a gain) leaves the PI's integral without its measurement and is refused
DC_GAIN_TOLERANCE = 0.01


def _number(where: str, value: Any, *, allow_none: bool = False) -> float | None:
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ModelFileError(f'{where}: expected a finite number, got {value!r}')
    return float(value)


def axis_from_dict(d: dict[str, Any], index: int) -> AxisParams:
    """One ``axes[i]`` entry -> AxisParams (unknown keys are an error, naming the key)."""
    if not isinstance(d, dict):
        raise ModelFileError(f'axes[{index}]: expected a mapping, got {type(d).__name__}')
    unknown = set(d) - _AXIS_KEYS
    if unknown:
        raise ModelFileError(f'axes[{index}]: unknown key(s) {sorted(unknown)}; expected some '
                             f'of {sorted(_AXIS_KEYS)}')
    kw: dict[str, Any] = {}
    for key, val in d.items():
        where = f'axes[{index}].{key}'
        if key == 'name':
            kw[key] = str(val)
        elif key == 'torque_ripple':
            if not isinstance(val, list):
                raise ModelFileError(f'{where}: expected a list of {{amplitude, '
                                     f'spatial_frequency, phase}}, got {val!r}')
            rip = []
            for j, r in enumerate(val):
                if not isinstance(r, dict):
                    raise ModelFileError(f'{where}[{j}]: expected a mapping, got {r!r}')
                rip.append({k: _number(f'{where}[{j}].{k}', v) for k, v in r.items()})
            kw[key] = rip
        elif key == 'gravity':
            kw[key] = _gravity_terms(where, val)
        elif key == 'second_mode':
            kw[key] = _second_mode(where, val)
        elif key in ('stiffness_k2', 'stiffness_breakpoint'):
            kw[key] = _number(where, val, allow_none=True)
        else:
            kw[key] = _number(where, val)
    kw.setdefault('name', f'joint_{index + 1}')
    return AxisParams(**kw)


def _gravity_terms(where: str, val: Any) -> list[dict[str, Any]]:
    """``gravity``: list of {amplitude [N m], phase [rad], joints [names]}."""
    if not isinstance(val, list):
        raise ModelFileError(f'{where}: expected a list of {{amplitude, phase, joints}}, got '
                             f'{val!r}')
    out = []
    for j, g in enumerate(val):
        w = f'{where}[{j}]'
        if not isinstance(g, dict) or 'amplitude' not in g:
            raise ModelFileError(f'{w}: expected a mapping with amplitude [N m], optional '
                                 f'phase [rad] and joints [names], got {g!r}')
        unknown = set(g) - {'amplitude', 'phase', 'joints'}
        if unknown:
            raise ModelFileError(f'{w}: unknown key(s) {sorted(unknown)}; expected amplitude, '
                                 f'phase, joints')
        term: dict[str, Any] = {'amplitude': _number(f'{w}.amplitude', g['amplitude']),
                                'phase': _number(f'{w}.phase', g.get('phase', 0.0))}
        if g.get('joints') is not None:
            js = g['joints']
            if not isinstance(js, list) or not js or not all(isinstance(x, str) for x in js):
                raise ModelFileError(f'{w}.joints: expected a non-empty list of axis names, '
                                     f'got {js!r}')
            term['joints'] = list(js)
        out.append(term)
    return out


def _second_mode(where: str, val: Any) -> dict[str, float] | None:
    """``second_mode``: null, or {frequency_hz [Hz], damping_ratio [-], inertia [kg m^2]}."""
    if val is None:
        return None
    if not isinstance(val, dict) or set(val) != set(SECOND_MODE_KEYS):
        raise ModelFileError(f'{where}: expected a mapping with exactly '
                             f'{", ".join(SECOND_MODE_KEYS)}, got {val!r}')
    return {k: _number(f'{where}.{k}', val[k]) for k in SECOND_MODE_KEYS}


def robot_from_dict(d: dict[str, Any]) -> RobotParams:
    """Model-file mapping -> RobotParams (the plant part)."""
    if not isinstance(d, dict):
        raise ModelFileError(f'model: expected a mapping at top level, got {type(d).__name__}')
    version = d.get('frf_ident_model')
    if version != MODEL_VERSION:
        raise ModelFileError(f'frf_ident_model: expected {MODEL_VERSION}, got {version!r}')
    unknown = set(d) - _TOP_KEYS
    if unknown:
        raise ModelFileError(f'model: unknown top-level key(s) {sorted(unknown)}')
    axes_in = d.get('axes')
    if not isinstance(axes_in, list) or not axes_in:
        raise ModelFileError(f'axes: expected a non-empty list, got {axes_in!r}')
    axes = [axis_from_dict(a, i) for i, a in enumerate(axes_in)]
    first: dict[str, int] = {}
    for i, a in enumerate(axes):
        if a.name in first:
            raise ModelFileError(f'axes[{i}].name: {a.name!r} is used twice (also '
                                 f'axes[{first[a.name]}]); axis names must be unique')
        first[a.name] = i
    sim = d.get('simulation')
    if sim is None:
        sim = {}
    if not isinstance(sim, dict):
        raise ModelFileError(f'simulation: expected a mapping with {", ".join(sorted(_SIM_KEYS))}'
                             f', got {sim!r}')
    unknown = set(sim) - _SIM_KEYS
    if unknown:
        raise ModelFileError(f'simulation: unknown key(s) {sorted(unknown)}; expected some of '
                             f'{sorted(_SIM_KEYS)}')
    coupling = d.get('link_coupling')
    if coupling is not None:
        try:
            coupling = np.asarray(coupling, dtype=float)
        except (TypeError, ValueError):
            raise ModelFileError(f'link_coupling: expected an {len(axes)}x{len(axes)} matrix '
                                 f'of numbers, got {coupling!r}') from None
    return RobotParams(
        axes=axes, link_coupling=coupling, mjcf=mjcf_source_from_dict(d), urdf=_urdf(d),
        sample_rate=_number('sample_rate', d.get('sample_rate', RobotParams.sample_rate)),
        substeps=expect_int('simulation.substeps', sim.get('substeps', RobotParams.substeps),
                            1, ModelFileError),
        velocity_from_encoder=expect_bool('simulation.velocity_from_encoder',
                                          sim.get('velocity_from_encoder',
                                                  RobotParams.velocity_from_encoder),
                                          ModelFileError),
        seed=expect_int('simulation.seed', sim.get('seed', RobotParams.seed), 0,
                        ModelFileError))


def _urdf(d: dict[str, Any]) -> UrdfSource | None:
    """Return the model file's ``urdf`` (a path) as a UrdfSource, None without it."""
    path = d.get('urdf')
    if path is None:
        return None
    if not isinstance(path, str) or not path:
        raise ModelFileError(f'urdf: expected the path of a URDF file, got {path!r}')
    return UrdfSource(path)


def mjcf_source_from_dict(d: dict[str, Any]) -> MjcfSource | None:
    """
    Return the model file's ``mjcf`` and ``pose`` as an MjcfSource (None without ``mjcf``).

    ``mjcf``: the MJCF file; ``pose``: a keyframe name, or a mapping joint name -> position
    [rad] (with an optional ``keyframe`` entry it is applied over).
    """
    path, pose = d.get('mjcf'), d.get('pose')
    if path is None:
        if pose is not None:
            raise ModelFileError('pose: only a model with mjcf (an MJCF file) takes a pose')
        return None
    if not isinstance(path, str) or not path:
        raise ModelFileError(f'mjcf: expected the path of an MJCF file, got {path!r}')
    if pose is None or isinstance(pose, str):
        return MjcfSource(path, pose or None, {})
    if not isinstance(pose, dict):
        raise ModelFileError(f'pose: expected a keyframe name or a mapping joint name -> '
                             f'position [rad], got {pose!r}')
    key = pose.get('keyframe')
    if key is not None and not isinstance(key, str):
        raise ModelFileError(f'pose.keyframe: expected a keyframe name, got {key!r}')
    joints = {str(k): _number(f'pose.{k}', v) for k, v in pose.items() if k != 'keyframe'}
    return MjcfSource(path, key, joints)


def controller_gains(d: dict[str, Any], robot: RobotParams) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the ``controller`` section's velocity-PI gains (kp, ki), one per axis, checked.

    :func:`frf_ident.core.simulation.controller.controller_from_dict` builds the controller.
    """
    c = d.get('controller')
    if not isinstance(c, dict):
        raise ModelFileError(f'controller: expected a mapping with kind, kp, ki, got {c!r}')
    if c.get('kind', 'pi_velocity') != 'pi_velocity':
        raise ModelFileError(f"controller.kind: expected 'pi_velocity', got {c.get('kind')!r}")
    unknown = set(c) - _CONTROLLER_KEYS
    if unknown:
        raise ModelFileError(f'controller: unknown key(s) {sorted(unknown)}; expected some of '
                             f'{sorted(_CONTROLLER_KEYS)}')
    n = robot.n_axes
    gains = {}
    for key in ('kp', 'ki'):
        val = c.get(key)
        vals = val if isinstance(val, list) else [val] * n
        if len(vals) != n:
            raise ModelFileError(f'controller.{key}: expected {n} values (one per axis), got '
                                 f'{len(vals)}')
        gains[key] = np.array([_number(f'controller.{key}[{i}]', v)
                               for i, v in enumerate(vals)])
        if np.any(gains[key] < 0):
            raise ModelFileError(f'controller.{key}: gains must be >= 0, got '
                                 f'{gains[key].tolist()}')
    return gains['kp'], gains['ki']


def check_sections(sections: np.ndarray) -> str | None:
    """
    Return what is wrong with one axis' chain of filter sections, or None when it is usable.

    A usable chain has rows [b0, b1, b2, 1, a1, a2] of finite numbers, every section stable
    (its poles inside the unit circle) and a DC gain within DC_GAIN_TOLERANCE of 1.

    Parameters
    ----------
    sections : ndarray, shape (n_sections, 6)
        The chain.

    Returns
    -------
    str or None
        One sentence naming the section and the problem.

    """
    sec = np.asarray(sections, dtype=float)
    if sec.ndim != 2 or sec.shape[1] != 6:
        return f'expected rows of 6 numbers [b0, b1, b2, 1, a1, a2], got shape {sec.shape}'
    for k, row in enumerate(sec):
        if not np.all(np.isfinite(row)):
            return f'section {k}: not all numbers are finite'
        if row[3] != 1.0:
            return f'section {k}: a0 must be 1 (normalised), got {row[3]:g}'
        if np.any(np.abs(np.roots(row[3:])) >= 1.0):
            return f'section {k}: unstable (a pole on or outside the unit circle)'
    dc = float(np.prod(sec[:, :3].sum(axis=1) / sec[:, 3:].sum(axis=1))) if len(sec) else 1.0
    if abs(dc - 1.0) > DC_GAIN_TOLERANCE:
        return (f'DC gain {dc:.4g}: a filter on the measured velocity must pass DC (1 within '
                f'{DC_GAIN_TOLERANCE:g}), or the integral loses its measurement')
    return None


def controller_filters(d: dict[str, Any], robot: RobotParams) -> np.ndarray:
    """
    Return ``controller.filters`` as sos (n, n_sections, 6), pass-through sections as padding.

    Parameters
    ----------
    d : dict
        The model-file mapping.
    robot : RobotParams
        Its robot (the axis names).

    Returns
    -------
    ndarray, shape (n, n_sections, 6)
        No sections without ``filters``.

    Raises
    ------
    ModelFileError
        Not a mapping of axis names to lists of usable sections (:func:`check_sections`).

    """
    spec = (d.get('controller') or {}).get('filters')
    n = robot.n_axes
    if spec is None:
        return np.zeros((n, 0, 6))
    if not isinstance(spec, dict):
        raise ModelFileError(f'controller.filters: expected a mapping {{axis name: list of '
                             f'[b0, b1, b2, 1, a1, a2]}}, got {spec!r}')
    names = robot.joint_names
    chains = [np.zeros((0, 6))] * n
    for name, sections in spec.items():
        where = f'controller.filters.{name}'
        if name not in names:
            raise ModelFileError(f'{where}: no axis of that name (axes {names})')
        try:
            sec = np.asarray(sections if sections else np.zeros((0, 6)), dtype=float)
        except (TypeError, ValueError):
            raise ModelFileError(f'{where}: expected a list of [b0, b1, b2, 1, a1, a2], got '
                                 f'{sections!r}') from None
        problem = check_sections(sec)
        if problem is not None:
            raise ModelFileError(f'{where}: {problem}')
        chains[names.index(name)] = sec
    m = max(len(x) for x in chains)
    return np.array([np.vstack([x, np.tile(PASS_SECTION, (m - len(x), 1))]) for x in chains]
                    ).reshape(n, m, 6)


def robot_to_dict(robot: RobotParams, controller: Any = None) -> dict[str, Any]:
    """
    Convert RobotParams (+ controller) to a model-file mapping (inverse of robot_from_dict).

    ``controller``: a velocity PI with ``kp`` and ``ki`` arrays (a
    :class:`frf_ident.core.simulation.controller.PIVelocity`, its ``sos`` filters written as
    ``filters``), or None.
    """
    axes = []
    for a in robot.axes:
        ad = asdict(a)
        ad['torque_ripple'] = [dict(r) for r in a.torque_ripple]
        ad['gravity'] = [dict(g) for g in a.gravity]
        if not ad['gravity']:
            del ad['gravity']
        for key in ('urdf_inertia', 'urdf_gravity'):
            if not ad[key]:
                del ad[key]
        if a.second_mode is None:
            del ad['second_mode']
        else:
            ad['second_mode'] = {k: float(a.second_mode[k]) for k in SECOND_MODE_KEYS}
        axes.append(ad)
    d: dict[str, Any] = {'frf_ident_model': MODEL_VERSION, 'sample_rate': robot.sample_rate,
                         'axes': axes}
    if robot.link_coupling is not None:
        d['link_coupling'] = np.asarray(robot.link_coupling).tolist()
    d['simulation'] = {'substeps': int(robot.substeps),
                       'velocity_from_encoder': bool(robot.velocity_from_encoder),
                       'seed': int(robot.seed)}
    if robot.mjcf is not None:
        d['description'] = f'{robot.mjcf.file} linearised at its pose, in our parameters'
    if robot.urdf is not None:
        d['urdf'] = robot.urdf.file
    if controller is not None:
        d['controller'] = {'kind': 'pi_velocity', 'kp': controller.kp.tolist(),
                           'ki': controller.ki.tolist()}
        sos = getattr(controller, 'sos', np.zeros((robot.n_axes, 0, 6)))
        chains = {a.name: [row.tolist() for row in sos[i]
                           if not np.array_equal(row, PASS_SECTION)]
                  for i, a in enumerate(robot.axes)}
        chains = {k: v for k, v in chains.items() if v}
        if chains:
            d['controller']['filters'] = chains
    return d


# Realistic base axes (1-3) of a 6-axis heavy-payload industrial robot near a fixed pose,
# inertias and torques referred to the link side as in the paper's example (Sec. 6): first
# resonances 11-16 Hz, antiresonances 5-8 Hz, link inertial coupling between the axes.
DEFAULT_MODEL: dict[str, Any] = {
    'frf_ident_model': 1,
    'description': 'base axes 1-3 of a 6-axis industrial robot (nominal, linear)',
    'sample_rate': 1000.0,
    'simulation': {'substeps': 1, 'velocity_from_encoder': False, 'seed': 0},
    'link_coupling': [[0.0, 12.0, 8.0], [12.0, 0.0, 35.0], [8.0, 35.0, 0.0]],
    'axes': [
        {'name': 'joint_1', 'motor_inertia': 35.0, 'link_inertia': 150.0, 'stiffness': 1.5e5,
         'damping': 400.0, 'viscous_friction': 20.0, 'torque_limit': 300.0},
        {'name': 'joint_2', 'motor_inertia': 40.0, 'link_inertia': 250.0, 'stiffness': 3.0e5,
         'damping': 600.0, 'viscous_friction': 25.0, 'torque_limit': 400.0,
         'gravity_torque': 120.0},
        {'name': 'joint_3', 'motor_inertia': 15.0, 'link_inertia': 60.0, 'stiffness': 1.2e5,
         'damping': 250.0, 'viscous_friction': 10.0, 'torque_limit': 300.0,
         'gravity_torque': 40.0},
    ],
    'controller': {'kind': 'pi_velocity', 'kp': [1500.0, 2000.0, 800.0],
                   'ki': [6000.0, 8000.0, 3200.0]},
}


def default_model_dict() -> dict[str, Any]:
    return copy.deepcopy(DEFAULT_MODEL)


def default_robot() -> RobotParams:
    return robot_from_dict(default_model_dict())
