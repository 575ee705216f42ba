"""Test-only plant plug-in (docs/CONTRACT.md §4) with hidden effects the diagnosis cannot see.

``HiddenPlant(model_dict)`` is the model's own simulation plus the changes in the module-level
``HIDDEN`` (or the JSON in the environment variable FRF_HIDDEN, for the CLI):
{axis_index: {model-file key: value}}. It subclasses FlexibleJointPlant so the runner keeps
its compiled speed. :func:`draw_effect` draws one effect with random plausible parameters.
"""
from __future__ import annotations

import json
import os
from dataclasses import replace

import numpy as np

from frf_ident.core.model.schema import robot_from_dict
from frf_ident.core.model.params import RobotParams
from frf_ident.core.simulation.plant import FlexibleJointPlant

from benchmarks.diagnosis import draw_effect  # noqa: E402,F401  (the same draws)

HIDDEN: dict[int, dict] = {}
NOISE = 2e-5     # velocity noise of the "real" robot [rad/s]


def hidden_robot(model: dict, hidden: dict[int, dict]) -> RobotParams:
    robot = robot_from_dict(model)
    axes = [replace(a, velocity_noise=max(a.velocity_noise, NOISE)) for a in robot.axes]
    for i, ch in hidden.items():
        axes[int(i)] = replace(axes[int(i)], **ch)
    return replace(robot, axes=axes, seed=int(os.environ.get('FRF_HIDDEN_SEED', '3')))


class HiddenPlant(FlexibleJointPlant):
    def __init__(self, config: dict | None = None) -> None:
        hidden = HIDDEN or {int(k): v for k, v in
                            json.loads(os.environ.get('FRF_HIDDEN', '{}')).items()}
        super().__init__(hidden_robot(config, hidden))
