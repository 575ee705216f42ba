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
A campaign whose resonances move with the pose: exact sampled FRFs plus Monte-Carlo noise.

The robot is config/model_3axis_resonant.yaml (stiff, lightly damped gears, a 3 ms drive
delay) with heavier drives: motor inertias (referred to the link side) four times the model
file's, as large as the link inertias (a high gear ratio), the gears four times as stiff and
damped to keep the resonances near 40-60 Hz at about 1 % damping (:func:`campaign_robot`).
Its link inertia matrix (diagonal and coupling) is scaled by a factor per pose, as reach and
payload change it: over 0.5-2 every axis's first resonance moves by 30-40 %. Each pose's
FRF is the exact FRF of the sampled loop (zero-order hold and delay,
:func:`frf_ident.core.simulation.analytic.robot_frf_sampled`, independent of the estimators
and of ``tune``) plus circular complex Gaussian noise of a given relative standard deviation,
whose variance the FRF file carries. Used by test/app/test_tune_campaign.py and the ``tune``
bench section.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.model.params import RobotParams
from frf_ident.core.simulation.analytic import robot_frf_sampled
from frf_ident.core.simulation.linear import state_space
from frf_ident.io.export import write_frf
from frf_ident.io.model_file import load_model
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
#: the robot of the campaign
MODEL = ROOT / 'config' / 'model_3axis_resonant.yaml'
#: measured lines [Hz]: 0.5 Hz apart up to 120 Hz (the delay's phase crossover lies near 70 Hz)
FREQ_HZ = np.arange(2.0, 120.01, 0.5)


#: the drives of the campaign robot against the model file's: motor inertia, stiffness, damping
DRIVE_FACTORS = {'motor_inertia': 4.0, 'stiffness': 4.0, 'damping': 3.2}


def campaign_robot() -> RobotParams:
    """Return the campaign's robot at scale 1 (the model file with the heavier drives)."""
    robot = load_model(MODEL)[1]
    return replace(robot, axes=[replace(a, **{k: getattr(a, k) * v
                                              for k, v in DRIVE_FACTORS.items()})
                                for a in robot.axes])


def pose_robot(scale: float, robot: RobotParams | None = None) -> RobotParams:
    """Return the campaign robot with its link inertia matrix scaled by ``scale``."""
    robot = robot or campaign_robot()
    m = robot.link_inertia_matrix() * scale
    axes = [replace(a, link_inertia=float(m[i, i])) for i, a in enumerate(robot.axes)]
    return replace(robot, axes=axes, link_coupling=m)


def resonances_hz(robot: RobotParams) -> np.ndarray:
    """Return the undamped natural frequencies of the linear robot [Hz], ascending."""
    ev = np.linalg.eigvals(state_space(robot)[0])
    f = np.abs(ev[ev.imag > 1e-6]) / (2 * np.pi)
    return np.sort(f)


def true_frf(robot: RobotParams, freq_hz: np.ndarray = FREQ_HZ) -> np.ndarray:
    """Return the exact sampled FRF torque -> motor velocity, shape (n, n, n_freq)."""
    return robot_frf_sampled(robot, freq_hz)


def measured(robot: RobotParams, rel_sd: float, rng: np.random.Generator,
             freq_hz: np.ndarray = FREQ_HZ) -> FrequencyResponse:
    """Return the exact FRF plus noise of relative standard deviation ``rel_sd``."""
    p = true_frf(robot, freq_hz)
    var = (rel_sd * np.abs(p)) ** 2
    noise = (rng.standard_normal(p.shape) + 1j * rng.standard_normal(p.shape)) * np.sqrt(var / 2)
    names = robot.joint_names
    return FrequencyResponse(freq_hz, p + noise, inputs=[f'tau_m/{n}' for n in names],
                             outputs=[f'dq_m/{n}' for n in names], noise_variance=var)


def write_campaign(root: Path, scales, rel_sd: float = 0.01, seed: int = 0) -> list[Path]:
    """Write one folder with frf.json per scale (a campaign ``tune`` reads); return them."""
    rng = np.random.default_rng(seed)
    base = campaign_robot()
    out = []
    for k, s in enumerate(scales):
        d = root / f'pose_{k}_x{s:.2f}'
        d.mkdir(parents=True, exist_ok=True)
        write_frf(measured(pose_robot(s, base), rel_sd, rng), d / 'frf.json')
        out.append(d)
    return out
