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
MuJoCo's linearisation of an MJCF robot at its pose: the nominal FRF and our parameters of it.

:func:`transition` linearises one sample of the simulation at rest (``mujoco.mjd_transitionFD``
over MuJoCo's own step, composed over the substeps of a sample with the command held);
:func:`nominal_frf` is its discrete FRF from the axes' torques to their motor-side velocities,
(n, n, n_freq) as python-control's FRD. :func:`axis_values` reads the MJCF in our parameters
(docs/CONTRACT.md §5 keys) through :data:`~frf_ident.io.mjcf.drive_map.MAPPING`: the drive terms
from the joints, the link side from M(q), g(q) and dg/dq at the pose in link coordinates.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.io.mjcf.drive_map import MODE_SUFFIX, rigid_split
from frf_ident.io.mjcf.link_mode import read_mode
from frf_ident.io.mjcf.robot import MjcfRobot
import mujoco
import numpy as np

__all__ = ['Linearisation', 'axis_values', 'nominal_frf', 'transition']

#: relative finite-difference step of mjd_transitionFD (centred) and of the gravity gradient
FD_EPS = 1e-6


@dataclass
class Linearisation:
    """
    One sample of the MJCF linearised: x_{k+1} = A x_k + B u_k, y_k = C x_k.

    u [N m] the axes' torques, y their motor-side velocities [rad/s], x MuJoCo's
    (dq, qvel, act); ``dt`` the sample period [s].
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    dt: float

    def frf(self, freq_hz: np.ndarray) -> np.ndarray:
        """Return C (z I - A)^-1 B at z = exp(j 2 pi f dt), shape (n_out, n_in, n_freq)."""
        f = np.asarray(freq_hz, dtype=float)
        z = np.exp(2j * np.pi * f * self.dt)
        eye = np.eye(self.A.shape[0])
        out = np.empty((self.C.shape[0], self.B.shape[1], f.size), dtype=complex)
        for k, zk in enumerate(z):
            out[:, :, k] = self.C @ np.linalg.solve(zk * eye - self.A, self.B)
        return out


def transition(robot: MjcfRobot, dt: float) -> Linearisation:
    """
    Linearise one sample of period ``dt`` at rest at the pose.

    Parameters
    ----------
    robot : MjcfRobot
        The prepared MJCF.
    dt : float
        Sample period [s] (a whole number of MuJoCo time steps).

    Returns
    -------
    Linearisation
        A over one sample (the step's A to the power of the substeps), B the held command's
        effect over the sample per N m (ctrl = u / gear).

    """
    m = robot.model
    d = mujoco.MjData(m)
    rest = robot.rest()
    d.qpos[:] = rest.qpos
    d.ctrl[robot.actuator] = rest.hold / robot.gear
    mujoco.mj_forward(m, d)
    nx = 2 * m.nv + m.na
    a = np.zeros((nx, nx))
    b = np.zeros((nx, m.nu))
    mujoco.mjd_transitionFD(m, d, FD_EPS, True, a, b, None, None)
    b = b[:, robot.actuator] / robot.gear
    steps = robot.substeps(dt)
    big_a, big_b = np.eye(nx), np.zeros_like(b)
    for _ in range(steps):
        big_a, big_b = a @ big_a, a @ big_b + b
    c = np.zeros((robot.n_axes, nx))
    c[np.arange(robot.n_axes), m.nv + robot.vadr] = 1.0
    return Linearisation(big_a, big_b, c, dt)


def nominal_frf(robot: MjcfRobot, dt: float, freq_hz: np.ndarray) -> np.ndarray:
    """Return the discrete FRF of :func:`transition` at ``freq_hz``, (n, n, n_freq)."""
    return transition(robot, dt).frf(freq_hz)


def _link_coordinates(robot: MjcfRobot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    T with x = T z: MuJoCo's dofs from (motor angles of the elastic axes, link angles).

    A rigid axis' one dof is its link angle; an elastic axis' link angle is motor + relative.
    Returns T (nv, n_el + n) and the columns of the motor angles and of the link angles.
    """
    m = robot.model
    el = np.flatnonzero(robot.elastic)
    n = robot.n_axes
    t = np.zeros((m.nv, el.size + n))
    motor_cols = np.arange(el.size)
    link_cols = el.size + np.arange(n)
    for c, i in enumerate(el):      # motor dof = q_m, relative dof = q_o - q_m
        t[robot.vadr[i], c] = 1.0
        t[robot.link_vadr[i], c] = -1.0
        t[robot.link_vadr[i], link_cols[i]] = 1.0
    for i in np.flatnonzero(~robot.elastic):
        t[robot.vadr[i], link_cols[i]] = 1.0
    return t, motor_cols, link_cols


def _link_gravity(robot: MjcfRobot, qpos: np.ndarray, t: np.ndarray,
                  link_cols: np.ndarray) -> np.ndarray:
    """Generalized gravity in link coordinates at rest (qvel = 0)."""
    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    mujoco.mj_forward(m, d)
    return (t.T @ d.qfrc_bias)[link_cols]


def _second_mode(inertia: float, stiffness: float, damping: float) -> dict[str, float]:
    """Return the model file's ``second_mode`` of a mode hinge's inertia, spring, damper."""
    w = np.sqrt(stiffness / inertia)
    return {'frequency_hz': float(w / (2 * np.pi)),
            'damping_ratio': float(damping / (2 * inertia * w)), 'inertia': float(inertia)}


def axis_values(robot: MjcfRobot, fs: float) -> tuple[list[dict], np.ndarray]:
    """
    Return our parameters of the MJCF at rest at its pose (MJCF -> ours, docs/mujoco.md).

    Per axis the docs/CONTRACT.md §5 keys: ``motor_inertia`` (armature), ``link_inertia``
    (M(q) in link coordinates), ``stiffness`` and ``damping`` (link-side hinge),
    ``viscous_friction`` (motor-side damping), ``coulomb_friction`` (frictionloss),
    ``torque_limit`` (gear x ctrlrange), ``gravity_torque`` and ``gravity`` (g(q0) and
    dg/dq at the pose q0 as terms dg/dq sin(q - q0), in the MJCF's own joint coordinates, so
    positions are the plant's), ``second_mode`` where the axis has the mode hinge (its inertia
    is in ``link_inertia``: the mode at rest moves with the link); a rigid joint by
    :func:`~frf_ident.io.mjcf.drive_map.rigid_split` (approximate).

    Returns
    -------
    axes : list of dict
        One mapping per axis.
    inertia : ndarray, shape (n, n)
        The link inertia matrix (its off-diagonal is ``link_coupling``).

    """
    m = robot.model
    rest = robot.rest()
    d = mujoco.MjData(m)
    d.qpos[:] = rest.qpos
    mujoco.mj_forward(m, d)
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, full)
    t, motor_cols, link_cols = _link_coordinates(robot)
    mz = t.T @ full @ t
    inertia = mz[np.ix_(link_cols, link_cols)].copy()
    g0 = _link_gravity(robot, rest.qpos, t, link_cols)
    grad = np.zeros((robot.n_axes, robot.n_axes))
    for j in range(robot.n_axes):
        dz = np.zeros(t.shape[1])
        dz[link_cols[j]] = FD_EPS
        qp, qm = rest.qpos.copy(), rest.qpos.copy()
        mujoco.mj_integratePos(m, qp, t @ dz, 1.0)
        mujoco.mj_integratePos(m, qm, -(t @ dz), 1.0)
        grad[:, j] = (_link_gravity(robot, qp, t, link_cols)
                      - _link_gravity(robot, qm, t, link_cols)) / (2 * FD_EPS)
    axes = []
    el_index = {int(i): c for c, i in zip(motor_cols, np.flatnonzero(robot.elastic))}
    for i, name in enumerate(robot.axes):
        v = robot.vadr[i]
        arm = float(m.dof_armature[v])
        entry = {'name': name, 'viscous_friction': float(m.dof_damping[v]),
                 'coulomb_friction': float(m.dof_frictionloss[v]),
                 'torque_limit': float(robot.torque_limit[i])}
        if robot.elastic[i]:
            lv = robot.link_vadr[i]
            entry.update(motor_inertia=float(mz[el_index[i], el_index[i]]),
                         link_inertia=float(inertia[i, i]),
                         stiffness=float(m.jnt_stiffness[m.dof_jntid[lv]]),
                         damping=float(m.dof_damping[lv]))
        else:
            jm, jo, k = rigid_split(float(inertia[i, i]) - arm, arm, fs)
            inertia[i, i] = jo
            entry.update(motor_inertia=jm, link_inertia=jo, stiffness=k, damping=0.0)
        mj = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name + MODE_SUFFIX)
        if mj >= 0:
            entry['second_mode'] = _second_mode(*read_mode(m, mj))
        entry['gravity_torque'] = float(g0[i])
        # in the MJCF's joint coordinates: G sin(q_j - q0_j) = dg/dq (q_j - q0_j) near q0
        entry['gravity'] = [{'amplitude': float(grad[i, j]),
                             'phase': -float(robot.pose[robot.axes[j]]),
                             'joints': [robot.axes[j]]}
                            for j in range(robot.n_axes)
                            if abs(grad[i, j]) > 1e-9 * max(np.abs(grad).max(), 1e-300)]
        axes.append(entry)
    return axes, inertia
