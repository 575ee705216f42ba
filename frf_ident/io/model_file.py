"""
Model files (docs/CONTRACT.md §5) and plant plug-ins (docs/CONTRACT.md §4): loading and saving.

YAML I/O lives here so :mod:`frf_ident.core.model.schema` stays free of file handling. Errors
name the file and the field (one line, CLI exit status 2).
"""
from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.model.schema import (controller_from_dict, default_model_dict, robot_from_dict,
                                         robot_to_dict)
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.errors import FrfIdentInputError, ModelFileError
from frf_ident.io.yamlio import load_yaml
import yaml


def read_model_dict(path: str | Path) -> dict[str, Any]:
    """Parse a model file into a mapping (no validation beyond YAML syntax)."""
    p = Path(path)
    try:
        text = p.read_text()
    except FileNotFoundError:
        raise ModelFileError(f'{p}: model file not found') from None
    except OSError as exc:
        raise ModelFileError(f'{p}: cannot read model file ({exc.strerror})') from None
    try:
        d = load_yaml(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        where = f' line {mark.line + 1}' if mark else ''
        raise ModelFileError(f'{p}:{where} not valid YAML ({getattr(exc, "problem", exc)})') \
            from None
    if not isinstance(d, dict):
        raise ModelFileError(f'{p}: expected a mapping with frf_ident_model, axes, ...')
    return d


def load_model(path: str | Path | None) -> tuple[dict[str, Any], RobotParams, PIVelocity]:
    """Model file -> (mapping, robot parameters, controller). None: the embedded default."""
    d = default_model_dict() if path is None else read_model_dict(path)
    try:
        robot = robot_from_dict(d)
        ctrl = controller_from_dict(d, robot)
    except ModelFileError as exc:
        raise ModelFileError(f'{path or "default model"}: {exc}') from None
    return d, robot, ctrl


def save_model(path: str | Path, robot: RobotParams, controller: PIVelocity | None = None,
               extra: dict[str, Any] | None = None) -> Path:
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
    (docs/CONTRACT.md §4).
    """
    if not spec:
        return FlexibleJointPlant(robot_from_dict(model))
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
    plant = cls(model)
    for attr in ('dt', 'joint_names', 'reset', 'step'):
        if not hasattr(plant, attr):
            raise FrfIdentInputError(f'--plant {spec!r}: the plant lacks {attr!r} '
                                     f'(docs/CONTRACT.md §4)')
    return plant
