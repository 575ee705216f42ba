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
Model files (docs/CONTRACT.md §5) and plant plug-ins (docs/CONTRACT.md §4): loading and saving.

YAML I/O lives here so :mod:`frf_ident.core.model.schema` stays free of file handling. Errors
name the file and the field (one line, CLI exit status 2).
"""
from __future__ import annotations

from dataclasses import replace
import importlib
from pathlib import Path
from typing import Any

from frf_ident.core.model.params import RobotParams, UrdfSource
from frf_ident.core.model.schema import default_model_dict, robot_from_dict, robot_to_dict
from frf_ident.core.simulation.controller import controller_from_dict, PIVelocity
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.errors import FrfIdentInputError, ModelFileError
from frf_ident.io.yamlio import read_yaml_file
import yaml

__all__ = ['MUJOCO', 'dry_run_plant', 'load_model', 'load_plant', 'read_model_dict',
           'save_model', 'with_urdf']

#: the plant spec that simulates an MJCF in MuJoCo (``mujoco`` or ``mujoco:FILE.xml``)
MUJOCO = 'mujoco'


def _mujoco_plant(spec: str, model: dict[str, Any]) -> Any:
    """Return MuJoCo's plant for ``--plant mujoco[:FILE.xml]``, or say what to install."""
    try:
        from frf_ident.io.mjcf.plant import MujocoPlant
    except ImportError as err:
        raise FrfIdentInputError(f'--plant {spec}: needs the mujoco package ({err}); pip '
                                 "install 'frf_ident[mujoco]'") from err
    _, _, file = spec.partition(':')
    return MujocoPlant(model, mjcf=file or None)


def read_model_dict(path: str | Path) -> dict[str, Any]:
    """
    Parse a model file into a mapping (no validation beyond YAML syntax).

    Floats follow YAML 1.2 (``1.5e5`` is a number, see :mod:`frf_ident.io.yamlio`).

    Parameters
    ----------
    path : str or Path
        The model file.

    Returns
    -------
    dict
        The top-level mapping.

    Raises
    ------
    ModelFileError
        The file is missing or unreadable, not UTF-8 text, not valid YAML (the line is
        named), or not a mapping.

    """
    p = Path(path)
    d = read_yaml_file(p, 'model file', ModelFileError)
    if not isinstance(d, dict):
        raise ModelFileError(f'{p}: expected a mapping with frf_ident_model, axes, ...')
    return d


def load_model(path: str | Path | None) -> tuple[dict[str, Any], RobotParams, PIVelocity]:
    """
    Load and validate a model file (docs/CONTRACT.md §5).

    A model naming an MJCF (``mjcf``) is returned with its axes filled from the MJCF at the
    pose (:func:`frf_ident.io.mjcf.nominal.view_dict`; the mapping's ``mjcf`` made absolute).

    Parameters
    ----------
    path : str or Path or None
        The model file; None loads the embedded default 3-axis model.

    Returns
    -------
    model : dict
        The mapping as read.
    robot : RobotParams
        The robot parameters.
    controller : PIVelocity
        The velocity controller the model describes.

    Raises
    ------
    ModelFileError
        The file cannot be read or a field is invalid (the message names file and field).

    """
    d = default_model_dict() if path is None else read_model_dict(path)
    if path is not None and 'mjcf' in d:
        d = _mjcf_view(d, Path(path))
    try:
        robot = robot_from_dict(d)
        if robot.urdf is not None:
            robot = with_urdf(robot, Path(path).parent if path is not None else Path.cwd())
        ctrl = controller_from_dict(d, robot)
        if robot.mjcf is not None:      # an MJCF starts at its pose, not at q = 0
            ctrl.reset(robot.gravity_load([robot.mjcf.pose[a] for a in robot.joint_names]))
    except ModelFileError as exc:
        raise ModelFileError(f'{path or "default model"}: {exc}') from None
    return d, robot, ctrl


def with_urdf(robot: RobotParams, base: Path) -> RobotParams:
    """
    Return the model with its ``urdf`` read: the path made absolute, its evaluator attached.

    A relative path is taken from ``base`` (the model file's folder). pinocchio evaluates the
    URDF (:meth:`frf_ident.io.kinematics.Kinematics.inertial_torque`).
    """
    from frf_ident.io.kinematics import load_kinematics
    p = Path(robot.urdf.file)
    p = p if p.is_absolute() else (base / p).resolve()
    try:
        kin = load_kinematics(p, robot.joint_names)
    except FrfIdentInputError as err:
        raise ModelFileError(f'urdf: {err}') from err
    return replace(robot, urdf=UrdfSource(str(p), kin))


def _mjcf_view(d: dict[str, Any], path: Path) -> dict[str, Any]:
    """Return a model naming an MJCF with the MJCF's values filled in (docs/model_file.md)."""
    try:
        from frf_ident.io.mjcf.nominal import view_dict
    except ImportError as err:
        raise ModelFileError(f'{path}: mjcf: needs the mujoco package ({err}); pip install '
                             "'frf_ident[mujoco]'") from err
    try:
        return view_dict(d, path.parent)
    except ModelFileError as exc:
        raise ModelFileError(f'{path}: {exc}') from None


def dry_run_plant(model: dict[str, Any], robot: RobotParams) -> Any:
    """
    Return the plant a plan's torque is predicted on: MuJoCo's for a model naming an MJCF.

    A model with ``mjcf`` is predicted on its MJCF (noiseless), not on our parameters of it
    (a rigid joint's spring there is an approximation, docs/mujoco.md); None for any other
    model (the prediction then runs our plant of ``robot``).
    """
    if robot.mjcf is None:
        return None
    quiet = dict(model, axes=[{k: v for k, v in a.items() if not k.endswith('_noise')}
                              for a in model['axes']])
    return _mujoco_plant(MUJOCO, quiet)


def save_model(path: str | Path, robot: RobotParams, controller: PIVelocity | None = None,
               extra: dict[str, Any] | None = None) -> Path:
    """
    Write a model file (docs/CONTRACT.md §5) that :func:`load_model` reads back.

    Parameters
    ----------
    path : str or Path
        File to write (overwritten).
    robot : RobotParams
        The robot parameters.
    controller : PIVelocity, optional
        The controller to store with them.
    extra : dict, optional
        Further top-level keys (e.g. a description), added last.

    Returns
    -------
    Path
        ``path``.

    """
    d = robot_to_dict(robot, controller)
    if extra:
        d.update(extra)
    p = Path(path)
    p.write_text(yaml.safe_dump(d, sort_keys=False, default_flow_style=None))
    return p


def load_plant(spec: str | None, model: dict[str, Any]) -> Any:
    """
    Instantiate the plant: the model's own simulation or a plug-in.

    A plug-in ``'package.module:Class'`` is constructed with the model mapping as its config
    (docs/CONTRACT.md §4); ``'mujoco'`` simulates the model's MJCF in MuJoCo,
    ``'mujoco:FILE.xml'`` another MJCF (:class:`~frf_ident.io.mjcf.plant.MujocoPlant`).

    Parameters
    ----------
    spec : str or None
        ``'package.module:Class'``, ``'mujoco'``, ``'mujoco:FILE.xml'``, or None / empty for
        the model's :class:`~frf_ident.core.simulation.plant.FlexibleJointPlant`.
    model : dict
        The model mapping (from :func:`load_model`).

    Returns
    -------
    object
        The plant, with ``dt``, ``joint_names``, ``reset`` and ``step``.

    Raises
    ------
    FrfIdentInputError
        ``spec`` is malformed, its module cannot be imported, lacks the class, or the plant
        lacks one of the §4 attributes.

    """
    if not spec:
        return FlexibleJointPlant(robot_from_dict(model))
    if spec == MUJOCO or spec.startswith(MUJOCO + ':'):
        return _mujoco_plant(spec, model)
    mod_name, sep, cls_name = spec.partition(':')
    if not sep or not mod_name or not cls_name:
        raise FrfIdentInputError(f"--plant {spec!r}: expected 'package.module:Class'")
    try:
        mod = importlib.import_module(mod_name)
    except ImportError as exc:
        raise FrfIdentInputError(f'--plant {spec!r}: cannot import {mod_name!r} ({exc})') \
            from None
    cls = getattr(mod, cls_name, None)
    if cls is None:
        raise FrfIdentInputError(f'--plant {spec!r}: module {mod_name!r} has no {cls_name!r}')
    if not callable(cls):
        raise FrfIdentInputError(f'--plant {spec!r}: {cls_name!r} is a {type(cls).__name__}, '
                                 f'not a class taking the model mapping (docs/CONTRACT.md §4)')
    try:
        plant = cls(model)
    except TypeError as exc:
        raise FrfIdentInputError(f'--plant {spec!r}: {cls_name}(model) failed ({exc}); a plant '
                                 f'takes the model mapping (docs/CONTRACT.md §4)') from exc
    for attr in ('dt', 'joint_names', 'reset', 'step'):
        if not hasattr(plant, attr):
            raise FrfIdentInputError(f'--plant {spec!r}: the plant lacks {attr!r} '
                                     f'(docs/CONTRACT.md §4)')
    return plant
