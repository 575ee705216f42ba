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
The experiment procedures of Section 7 as schedules of phases (closed loop, velocity reference).

A procedure is a list of :class:`Phase` objects. ``excite`` phases carry a precomputed velocity
reference and an experiment segment; ``move`` phases bring an axis back to a position relative
to the operating point (their reference is computed when the phase starts, from the measured
position, by :func:`move_plan`); ``settle`` phases hold still. The offline runner
(:mod:`frf_ident.core.simulation.runner`) and the excitation node execute the same phases, so
simulation and the node graph run identical experiments.

This module holds the phase and the move plan; the procedures, each in its own module:

- :mod:`frf_ident.core.excitation.multisine_procedure` — Sec. 4.4/7: odd random multisine on a
  constant velocity (amplitude <= 0.75 of it, every axis within +-4 deg), n_p realisations x
  n_q periods, MIMO by eq. 9, plus one constant-velocity-only run for periodic-disturbance
  compensation.
- :mod:`frf_ident.core.excitation.chirp_iteration` — Sec. 5.3 (eqs. 17-19): MIMO chirps (eq. 26
  phases) whose reference is iterated until the plant input reaches the desired torque
  amplitudes (Table 1).
- :mod:`frf_ident.core.excitation.plan_checks` — the refusals of settings and plans (band,
  finite settings, position bound, torque bound).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass
class Phase:
    """
    One step of a procedure.

    kind: 'excite' (reference given, no feedback), 'move' (to ``target`` [rad] relative to the
    operating point; reference and position plan computed at run time by :func:`move_plan`,
    executed with position feedback) or 'settle' (hold the position reached, with position
    feedback).
    ``reference`` is the total velocity reference (constant velocity + excitation),
    ``excitation`` the excitation part; both (n_samples, n_axes).
    """

    kind: str
    n_samples: int
    reference: np.ndarray | None = None
    excitation: np.ndarray | None = None
    segment: dict[str, Any] | None = None
    target: np.ndarray | None = None


def move_reference(q_now: np.ndarray, q_target: np.ndarray, n_samples: int,
                   dt: float) -> np.ndarray:
    """
    Velocity reference of a minimum-jerk move from q_now to q_target in n_samples.

    v(s) = dq / T * 30 s^2 (1 - s)^2 with s = t / T integrates exactly to dq.
    """
    T = n_samples * dt
    s = (np.arange(n_samples) + 0.5) / n_samples
    shape = 30.0 * s ** 2 * (1.0 - s) ** 2
    return np.outer(shape, (np.asarray(q_target) - np.asarray(q_now)) / T)


POSITION_GAIN = 2.5    # [1/s] position feedback on the reference in move/settle phases; well
#                        below the rigid-body velocity-loop bandwidth kp/(Jm+Jo) ~ 7-11 rad/s


def move_plan(q_now: np.ndarray, q_target: np.ndarray, n_samples: int, dt: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """
    Feed-forward velocity and planned position (absolute) of a move from q_now to q_target.

    The executor adds POSITION_GAIN (plan - q) to the reference, so the robot ends on the
    target despite friction, ripple and gravity, and every segment starts where the
    compensation run started (Sec. 4.4 E needs the same position trajectory).
    """
    ref = move_reference(q_now, q_target, n_samples, dt)
    plan = np.asarray(q_now, dtype=float) + np.cumsum(ref, axis=0) * dt
    return ref, plan
