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
model.yaml of `frf-ident fit --physical`: a model file with the fitted axes.

The fit gives five parameters per axis, the link coupling (coupled fit) and the delay; a
model file needs more (torque limits, friction, gravity, the controller's gains, the sample
rate). Those come from a base model file, ``--model``, else the embedded default model (the
demo robot of frf_ident/core/model/schema.py) — and the output says which, so that nobody
simulates their robot with the demo's gravity or gains unawares.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

from frf_ident.core.fit.physical import PARAMETERS
from frf_ident.core.model.params import RobotParams
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.io.model_file import load_model, save_model
import numpy as np

__all__ = ['DEFAULT_BASE', 'export_drive', 'FittedModel', 'hold_of', 'write_fitted_model']

#: how the output names the base when no --model was given
DEFAULT_BASE = 'the default model (the demo robot of frf_ident/core/model/schema.py)'


@dataclass(frozen=True)
class FittedModel:
    """
    The model file written and where its other keys came from.

    Attributes
    ----------
    path : Path
        model.yaml.
    base : str
        The model file the other keys came from (or :data:`DEFAULT_BASE`).
    lines : list of str
        What model.yaml holds and from where, for people.
    robot : RobotParams
        The model written (for the MJCF and URDF exports of :func:`export_drive`).

    """

    path: Path
    base: str
    lines: list[str]
    robot: RobotParams


def hold_of(model: str | Path | None) -> float:
    """Return half the sample period [s] of a model file (the zero-order hold's delay)."""
    return load_model(model)[1].dt / 2


def write_fitted_model(values: dict[str, dict[str, float]], coupling: np.ndarray | None,
                       delays: dict[str, float] | None, model: str | Path | None,
                       out: Path) -> FittedModel:
    """
    Write model.yaml: the base model with the fitted axes.

    Parameters
    ----------
    values : dict
        Each fitted axis -> its five parameters (model-file keys).
    coupling : ndarray or None
        The coupled fit's link coupling; None: left out of the file.
    delays : dict or None
        Each axis -> its fitted delay [s]; it becomes ``time_delay`` = delay less the half
        sample the zero-order hold of the model's sample rate adds by itself (at least 0).
        None: the delay was given, ``time_delay`` keeps the base's.
    model : str or Path or None
        The base model file; None: the embedded default.
    out : Path
        The output directory.

    Returns
    -------
    FittedModel
        The file, the base, and the lines saying what is fitted and what is not.

    """
    _, base, ctrl = load_model(model)
    name = str(model) if model is not None else DEFAULT_BASE
    names = base.joint_names
    pick = [names.index(n) if n in names else 0 for n in values]
    extra = {n: {} if delays is None else {'time_delay': max(delays[n] - base.dt / 2, 0.0)}
             for n in values}
    axes = [replace(base.axes[k], name=n, **dict(v, viscous_friction=max(
        v['viscous_friction'], 0.0)), **extra[n]) for (n, v), k in zip(values.items(), pick)]
    robot = replace(base, axes=axes, link_coupling=coupling)
    pi = PIVelocity(ctrl.kp[pick], ctrl.ki[pick], robot.torque_limits(), robot.dt,
                    sos=ctrl.sos[pick])
    how = ('fitted with the link coupling' if coupling is not None else
           'fitted per axis (link_coupling not fitted: left out)')
    path = save_model(out / 'model.yaml', robot, pi,
                      extra={'description': f'two-mass parameters {how} by frf-ident fit; '
                                            f'every other key from {name}'})
    fitted = (list(PARAMETERS) + (['time_delay'] if delays is not None else [])
              + (['link_coupling'] if coupling is not None else []))
    lines = [f'model.yaml: fitted {", ".join(fitted)}; every other key (torque_limit, '
             f'friction, gravity, sample_rate {1 / base.dt:g} Hz, the controller kp/ki) from '
             f'{name}' + ('' if model is not None else
                          ': give --model M.yaml to take them from your model file')]
    missing = [n for n in values if n not in names]
    if missing:
        lines.append(f'model.yaml: {", ".join(missing)} not in {name}: their other keys from '
                     f'its first axis {names[0]}')
    return FittedModel(path, name, lines, robot)


def export_drive(robot: RobotParams, out: Path, say: Callable[[str], None]) -> list[Path]:
    """
    Write the fitted drive terms as model.urdf and (with mujoco) model.xml, docs/mujoco.md.

    model.xml keeps the model file's MJCF rigid body when it names one (else one standalone
    two-mass chain per axis); every term it cannot hold is said in one line.
    """
    from frf_ident.io.urdf_drive import write_drive_urdf
    files = [write_drive_urdf(robot, out / 'model.urdf')]
    try:
        from frf_ident.io.mjcf.export import write_mjcf
    except ImportError:
        say("fit: model.xml (MJCF) left out: pip install 'frf_ident[mujoco]'")
        return files
    exp = write_mjcf(robot, out / 'model.xml')
    for line in exp.lines():
        say(f'  model.xml: {line}')
    return [exp.path] + files
