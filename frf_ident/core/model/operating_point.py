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
The robot linearised at an operating point: link inertia, coupling and gravity of a pose.

Around a pose q0 an identification experiment moves each axis by a few degrees (Saupe &
Knoblach 2015, Sec. 2 D: +-4 deg), so the link side is the pose's: the inertia matrix M(q0)
(diagonal -> ``link_inertia``, off-diagonal -> ``link_coupling``) and the gravity load
g(q0) + dg/dq (q - q0). The simulation's link coordinates are q - q0 (0 at the pose): the
constant g(q0) becomes ``gravity_torque`` and each gradient entry K_ij a ``gravity`` term
K_ij sin(q_j - q0_j), which is K_ij (q_j - q0_j) to 0.08 % over +-4 deg. The drive side
(motor inertia, stiffness, damping, friction, limits) does not depend on the pose.
The arrays come from the kinematics (frf_ident.io.kinematics); this module is numpy only.
"""
from __future__ import annotations

from dataclasses import replace

from frf_ident.core.model.params import RobotParams
import numpy as np

__all__ = ['GRADIENT_FLOOR', 'robot_at_pose']

#: gradient entries below this share of the largest |dg/dq| are rounding of zero (pinocchio
#: gives ~1e-14 N m/rad for joints gravity cannot load) and get no gravity term
GRADIENT_FLOOR = 1e-9


def robot_at_pose(robot: RobotParams, inertia: np.ndarray, gravity: np.ndarray,
                  gravity_gradient: np.ndarray) -> RobotParams:
    """
    Return ``robot`` with the link side of one pose (coordinates relative to the pose).

    Parameters
    ----------
    robot : RobotParams
        The robot; its drive side is kept, its link inertia, coupling, ``gravity_torque`` and
        ``gravity`` terms are replaced.
    inertia : ndarray, shape (n, n)
        M(q0) [kg m^2], symmetric positive definite, in axis order.
    gravity : ndarray, shape (n,)
        g(q0) [N m]: the load that holds the pose.
    gravity_gradient : ndarray, shape (n, n)
        dg/dq at q0 [N m/rad].

    Returns
    -------
    RobotParams
        The linearised robot (validated again: M(q0) must be positive definite).

    """
    m = np.asarray(inertia, dtype=float)
    g = np.asarray(gravity, dtype=float)
    k = np.asarray(gravity_gradient, dtype=float)
    names = robot.joint_names
    k = np.where(np.abs(k) > GRADIENT_FLOOR * np.abs(k).max(initial=0.0), k, 0.0)
    axes = []
    for i, a in enumerate(robot.axes):
        terms = [{'amplitude': float(k[i, j]), 'phase': 0.0, 'joints': [names[j]]}
                 for j in range(robot.n_axes) if k[i, j] != 0.0]
        axes.append(replace(a, link_inertia=float(m[i, i]), gravity_torque=float(g[i]),
                            gravity=terms))
    return replace(robot, axes=axes, link_coupling=m.copy())
