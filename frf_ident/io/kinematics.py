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
The link side of a robot from its URDF, evaluated with pinocchio: plain arrays for the core.

:func:`load_kinematics` reads a URDF (pinocchio's ``buildModelFromUrdf``; the ``pin`` package,
extra ``[kinematics]``) and :meth:`Kinematics.at` gives, at joint positions q [rad], the
joint-space inertia matrix M(q) (CRBA), the generalized gravity g(q) [N m] (the torque that
holds the pose) and its gradient dg/dq [N m/rad]: the numbers
:func:`frf_ident.core.model.operating_point.robot_at_pose` linearises the simulated link side
with. Inertial parameters in the URDF are link-side values (gear ratios already applied), as
in the model file. :func:`read_poses` reads a poses file for ``frf-ident identify --poses``.

:meth:`Kinematics.gravity_basis` gives the gravity's base regressor for the diagnosis: the
columns of pinocchio's joint-torque regressor at rest (``computeJointTorqueRegressor`` with
zero velocity and acceleration) that are linearly independent over the configuration space,
divided by each joint's gear ratio (the URDF's ``<transmission>`` ``mechanicalReduction``,
1 without one) when the recorded torque is the motor's.

The inertia matrix is linear in the links' inertial parameters (pinocchio's dynamic
parameters, 10 per link: m, m c, the inertia about the joint frame's origin):
:meth:`Kinematics.inertia_regressor` gives that linear map at a pose (from
``computeJointTorqueRegressor`` with gravity off and unit accelerations),
:meth:`Kinematics.with_parameters` the kinematics with other inertial parameters and
:meth:`Kinematics.write_urdf` a URDF that holds them: what the global pose model of
``frf-ident fit`` fits and writes. :meth:`Kinematics.inertial_torque` gives the inertia and
Coriolis torque along a record (RNEA minus gravity, motor side) and
:meth:`Kinematics.gravity_torque` its gravity: what a model file's ``urdf_inertia`` and
``urdf_gravity`` take a share of.
"""
from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path
from typing import Any, Sequence
import xml.etree.ElementTree as ET

from frf_ident.errors import FrfIdentInputError
from frf_ident.io.share import share_dir
from frf_ident.io.yamlio import read_yaml_file
import numpy as np

__all__ = ['DEMO_URDF', 'PARAMETERS_PER_LINK', 'Kinematics', 'LinkSide', 'load_kinematics',
           'read_poses']

#: urdf/ file of the project's 3-axis demo robot (config/model_3axis.yaml at its home pose)
DEMO_URDF = 'robot_3axis_demo.urdf'

#: pinocchio's dynamic parameters of one link: m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz
#: (the inertia about the joint frame's origin)
PARAMETERS_PER_LINK = 10


@dataclass(frozen=True)
class LinkSide:
    """
    The link side at one pose: what the linearised simulation needs.

    Attributes
    ----------
    q : ndarray, shape (n,)
        The pose [rad], in the order of ``joint_names``.
    inertia : ndarray, shape (n, n)
        Joint-space inertia matrix M(q) [kg m^2], symmetric.
    gravity : ndarray, shape (n,)
        Generalized gravity g(q) [N m]: the link-side torque that holds the pose.
    gravity_gradient : ndarray, shape (n, n)
        dg/dq at q [N m/rad]: row i is how axis i's load changes with each joint.

    """

    q: np.ndarray
    inertia: np.ndarray
    gravity: np.ndarray
    gravity_gradient: np.ndarray


class Kinematics:
    """
    A URDF's joints, limits and link-side dynamics, evaluated with pinocchio.

    Parameters
    ----------
    model : pinocchio.Model
        The model built from the URDF.
    source : str
        Where it came from (for messages).
    joint_names : sequence of str
        The axes in the caller's order; each must be a one-DOF joint of the URDF, and
        together they must be all of its joints.
    reduction : sequence of float, optional
        Per axis (``joint_names`` order) the gear ratio motor : joint; default 1.

    Raises
    ------
    FrfIdentInputError
        A name is not a joint of the URDF, or the URDF has joints not named.

    """

    def __init__(self, model: Any, source: str, joint_names: Sequence[str],
                 reduction: Sequence[float] | None = None) -> None:
        import pinocchio as pin
        self._pin, self.model, self.source = pin, model, source
        self.data = model.createData()
        urdf_joints = list(model.names[1:])
        missing = [j for j in joint_names if j not in urdf_joints]
        extra = [j for j in urdf_joints if j not in joint_names]
        if missing or extra or model.nq != len(urdf_joints):
            raise FrfIdentInputError(
                f'{source}: joints {urdf_joints} (one revolute DOF each expected) do not '
                f'match the model axes {list(joint_names)}')
        self.joint_names = list(joint_names)
        # model joint k (1-based) holds configuration index idx_qs; map our order onto it
        self.index = np.array([model.joints[model.getJointId(j)].idx_q for j in joint_names])
        self.lower = np.asarray(model.lowerPositionLimit)[self.index]
        self.upper = np.asarray(model.upperPositionLimit)[self.index]
        self.effort = np.asarray(model.effortLimit)[self.index]
        self.reduction = np.ones(len(joint_names)) if reduction is None else \
            np.asarray(reduction, dtype=float)
        self._base: np.ndarray | None = None

    def _regressor(self, q: np.ndarray) -> np.ndarray:
        """Return the full gravity regressor (n, 10 x bodies) at one pose, our joint order."""
        pin = self._pin
        full = np.zeros(self.model.nq)
        full[self.index] = q
        zero = np.zeros(self.model.nv)
        y = pin.computeJointTorqueRegressor(self.model, self.data, full, zero, zero)
        return np.array(y)[self.index]

    def base_columns(self, poses: int = 40, seed: int = 0) -> np.ndarray:
        """
        Return the indices of the regressor columns that are the gravity's base parameters.

        The columns of the stacked regressor at ``poses`` random poses (angles uniform over
        the circle: the structure, not the workspace) kept by QR with column pivoting up to
        its numerical rank; every other column is a combination of these.
        """
        if self._base is None:
            from scipy.linalg import qr
            rng = np.random.default_rng(seed)
            Y = np.vstack([self._regressor(q) for q in
                           rng.uniform(-np.pi, np.pi, (poses, len(self.joint_names)))])
            _, r, piv = qr(Y, mode='economic', pivoting=True)
            d = np.abs(np.diag(r))
            rank = int(np.sum(d > 1e-9 * max(float(d[0]) if d.size else 0.0, 1e-300)))
            self._base = np.sort(piv[:rank])
        return self._base

    def gravity_basis(self, q: np.ndarray, *, motor_side: bool = True) -> np.ndarray:
        """
        Return the gravity's base regressor at poses q: g(q) = basis @ base parameters.

        Parameters
        ----------
        q : ndarray, shape (N, n)
            Joint positions [rad] in ``joint_names`` order (NaN rows give NaN).
        motor_side : bool
            Divide each joint's row by its gear ratio (the torque its motor sees).

        Returns
        -------
        ndarray, shape (N, n, p)
            Per pose and axis the base columns (p = :meth:`base_columns` count).

        """
        cols = self.base_columns()
        q = np.asarray(q, dtype=float)
        out = np.full((q.shape[0], len(self.joint_names), cols.size), np.nan)
        for k, qk in enumerate(q):
            if np.all(np.isfinite(qk)):
                out[k] = self._regressor(qk)[:, cols]
        return out / self.reduction[None, :, None] if motor_side else out

    def inertial_torque(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """
        Return the link side's inertia and Coriolis torque on the motor side at every sample.

        pinocchio's RNEA at (q, v, a) minus the gravity at q, divided by each joint's gear
        ratio: M(q) a + C(q, v) v at the URDF's inertial parameters, as each motor sees it.

        Parameters
        ----------
        q, v, a : ndarray, shape (N, n)
            Joint positions [rad], velocities [rad/s] and accelerations [rad/s^2] in
            ``joint_names`` order.

        Returns
        -------
        ndarray, shape (N, n)
            The torque [N m] (NaN where a sample is not finite).

        """
        pin = self._pin
        q, v, a = (np.asarray(x, dtype=float) for x in (q, v, a))
        out = np.full(q.shape, np.nan)
        full = [np.zeros(self.model.nq), np.zeros(self.model.nv), np.zeros(self.model.nv)]
        zero = np.zeros(self.model.nv)
        for k in range(q.shape[0]):
            if not (np.all(np.isfinite(q[k])) and np.all(np.isfinite(v[k]))
                    and np.all(np.isfinite(a[k]))):
                continue
            for x, row in zip(full, (q[k], v[k], a[k])):
                x[self.index] = row
            tau = pin.rnea(self.model, self.data, full[0], full[1], full[2])
            tau = tau - pin.rnea(self.model, self.data, full[0], zero, zero)
            out[k] = np.asarray(tau)[self.index]
        return out / self.reduction

    def gravity_torque(self, q: np.ndarray) -> np.ndarray:
        """
        Return the link side's gravity on the motor side at every sample: g(q) over the gears.

        Parameters
        ----------
        q : ndarray, shape (N, n)
            Joint positions [rad] in ``joint_names`` order.

        Returns
        -------
        ndarray, shape (N, n)
            The torque [N m] at the URDF's inertial parameters (NaN where q is not finite).

        """
        pin = self._pin
        q = np.asarray(q, dtype=float)
        out = np.full(q.shape, np.nan)
        full = np.zeros(self.model.nq)
        for k in range(q.shape[0]):
            if np.all(np.isfinite(q[k])):
                full[self.index] = q[k]
                out[k] = np.asarray(pin.computeGeneralizedGravity(self.model, self.data,
                                                                  full))[self.index]
        return out / self.reduction

    def at(self, q: Sequence[float]) -> LinkSide:
        """
        Evaluate M(q), g(q) and dg/dq at a pose.

        Parameters
        ----------
        q : sequence of float
            Joint positions [rad] in the order of ``joint_names``.

        Returns
        -------
        LinkSide
            The link side at ``q`` (arrays in ``joint_names`` order).

        """
        pin = self._pin
        qs = np.asarray(q, dtype=float)
        full = np.zeros(self.model.nq)
        full[self.index] = qs
        m = pin.crba(self.model, self.data, full)
        m = np.triu(m) + np.triu(m, 1).T           # CRBA fills the upper triangle
        g = pin.computeGeneralizedGravity(self.model, self.data, full)
        dg = pin.computeGeneralizedGravityDerivatives(self.model, self.data, full)
        ix = np.ix_(self.index, self.index)
        return LinkSide(q=qs, inertia=np.array(m)[ix], gravity=np.array(g)[self.index],
                        gravity_gradient=np.array(dg)[ix])

    def parameters(self) -> np.ndarray:
        """
        Return the links' inertial parameters, :data:`PARAMETERS_PER_LINK` per joint.

        Returns
        -------
        ndarray, shape (10 n,)
            pinocchio's dynamic parameters of the link each joint moves, in the model's
            joint order (``model.names``).

        """
        return np.concatenate([self.model.inertias[j].toDynamicParameters()
                               for j in range(1, self.model.njoints)])

    def inertia_regressor(self, q: Sequence[float]) -> np.ndarray:
        """
        Return the linear map from the inertial parameters to M(q)'s upper triangle.

        Parameters
        ----------
        q : sequence of float
            Joint positions [rad] in the order of ``joint_names``.

        Returns
        -------
        ndarray, shape (n (n + 1) / 2, 10 n)
            Row r is entry ``np.triu_indices(n)`` r of M(q) (in ``joint_names`` order) as a
            function of :meth:`parameters`: ``regressor @ parameters()`` is that triangle.

        """
        pin = self._pin
        model = self.model.copy()
        model.gravity.linear[:] = 0.0           # tau(q, v=0, a=e_j) is then column j of M
        data = model.createData()
        full = np.zeros(model.nq)
        full[self.index] = np.asarray(q, dtype=float)
        nv = model.nv
        cols = []
        for j in self.index:
            acc = np.zeros(nv)
            acc[j] = 1.0
            cols.append(np.array(pin.computeJointTorqueRegressor(
                model, data, full, np.zeros(nv), acc))[self.index])
        iu = np.triu_indices(len(self.index))
        return np.stack([cols[c][r] for r, c in zip(*iu)])

    def with_parameters(self, parameters: np.ndarray) -> 'Kinematics':
        """
        Return these kinematics with other inertial parameters.

        Parameters
        ----------
        parameters : ndarray, shape (10 n,)
            As :meth:`parameters`; every link's mass must be positive.

        Returns
        -------
        Kinematics
            A copy whose links carry ``parameters``.

        """
        pin = self._pin
        model = self.model.copy()
        p = np.asarray(parameters, dtype=float).reshape(-1, PARAMETERS_PER_LINK)
        for j, pj in enumerate(p, start=1):
            model.inertias[j] = pin.Inertia.FromDynamicParameters(pj)
        return Kinematics(model, self.source, self.joint_names)

    def write_urdf(self, path: str | os.PathLike[str], comment: str = '') -> Path:
        """
        Write the source URDF with this model's inertial parameters in its links.

        Each joint's child link gets the ``<inertial>`` of the model's body (centre of mass
        and inertia about it, in the link frame, which is the joint frame). The source must
        give every moving link its own body (no fixed joints carrying mass, which pinocchio
        merges).

        Parameters
        ----------
        path : str or path-like
            The URDF to write.
        comment : str, optional
            A comment put at the top (what these parameters are).

        Returns
        -------
        Path
            ``path``.

        Raises
        ------
        FrfIdentInputError
            The source URDF has masses on fixed joints, so its links are not the model's
            bodies.

        """
        import xml.etree.ElementTree as ET
        tree = ET.parse(self.source)
        root = tree.getroot()
        fixed = [j.find('child').get('link') for j in root.iter('joint')
                 if j.get('type') == 'fixed']
        if any(lk.get('name') in fixed and lk.find('inertial') is not None
               for lk in root.iter('link')):
            raise FrfIdentInputError(f'{self.source}: links on fixed joints carry mass; '
                                     f'cannot write fitted inertial parameters per link')
        child = {j.get('name'): j.find('child').get('link') for j in root.iter('joint')}
        links = {lk.get('name'): lk for lk in root.iter('link')}
        for jid in range(1, self.model.njoints):
            body = self.model.inertias[jid]
            link = links[child[self.model.names[jid]]]
            old = link.find('inertial')
            if old is not None:
                link.remove(old)
            inertial = ET.SubElement(link, 'inertial')
            c, i = np.asarray(body.lever), np.asarray(body.inertia)
            ET.SubElement(inertial, 'origin', xyz=' '.join(f'{v:.9g}' for v in c), rpy='0 0 0')
            ET.SubElement(inertial, 'mass', value=f'{body.mass:.9g}')
            ET.SubElement(inertial, 'inertia', **{
                f'i{a}{b}': f'{i[r, s]:.9g}' for (a, r), (b, s) in
                (((a, r), (b, s)) for r, a in enumerate('xyz') for s, b in enumerate('xyz')
                 if s >= r)})
        if comment:
            root.insert(0, ET.Comment(f' {comment} '))
        p = Path(path)
        tree.write(p, xml_declaration=True, encoding='unicode')
        return p


def load_kinematics(path: str | os.PathLike[str] | None,
                    joint_names: Sequence[str]) -> Kinematics:
    """
    Read a URDF with pinocchio.

    Parameters
    ----------
    path : str or path-like or None
        The URDF; None: the demo robot's (:data:`DEMO_URDF` in the package's urdf/).
    joint_names : sequence of str
        The model's axes (the URDF's joints, in the model's order).

    Returns
    -------
    Kinematics
        The robot's link side.

    Raises
    ------
    FrfIdentInputError
        pinocchio is missing, the file is missing or not a URDF pinocchio reads, or its
        joints are not the model's axes.

    """
    try:
        import pinocchio as pin
    except ImportError as err:
        raise FrfIdentInputError('reading a URDF needs pinocchio: pip install '
                                 '"frf_ident[kinematics]" (the pin package)') from err
    p = Path(path) if path is not None else share_dir() / 'urdf' / DEMO_URDF
    if not p.is_file():
        raise FrfIdentInputError(f'{p}: no such URDF file')
    try:
        model = pin.buildModelFromUrdf(str(p))
    except (RuntimeError, ValueError) as err:
        raise FrfIdentInputError(f'{p}: not a URDF pinocchio can read '
                                 f'({" ".join(str(err).split())[:200]})') from err
    return Kinematics(model, str(p), joint_names, _reductions(p, joint_names))


def _reductions(path: Path, joint_names: Sequence[str]) -> list[float]:
    """Return per joint the ``mechanicalReduction`` of its URDF transmission (1 if none)."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as err:
        raise FrfIdentInputError(f'{path}: not a URDF pinocchio can read ({err})') from err
    out = {}
    for tr in root.iter('transmission'):
        joint, red = tr.find('joint'), tr.find('actuator/mechanicalReduction')
        if joint is None or red is None:
            continue
        try:
            out[joint.get('name')] = float((red.text or '').strip())
        except ValueError as err:
            raise FrfIdentInputError(f'{path}: transmission {tr.get("name")!r}: '
                                     f'mechanicalReduction {red.text!r}; expected a number'
                                     ) from err
    return [out.get(j, 1.0) for j in joint_names]


def read_poses(path: str | os.PathLike[str], n_axes: int
               ) -> tuple[list[list[float]], Path | None]:
    """
    Read a poses file: ``poses: [[q1, q2, ...], ...]`` [rad], optional ``urdf: FILE``.

    Parameters
    ----------
    path : str or path-like
        The YAML file. ``urdf`` is taken relative to it; absent: the demo robot's URDF.
    n_axes : int
        Number of model axes: every pose has one value per axis.

    Returns
    -------
    poses : list of list of float
        The poses [rad], in file order.
    urdf : Path or None
        The URDF named in the file, or None.

    Raises
    ------
    FrfIdentInputError
        Unreadable YAML, no ``poses`` list, a pose of the wrong length or not finite numbers.

    """
    d = read_yaml_file(path, 'poses file')
    if not isinstance(d, dict) or not isinstance(d.get('poses'), list) or not d['poses']:
        raise FrfIdentInputError(f'{path}: expected a mapping with poses: a non-empty list of '
                                 f'joint positions [rad], one list of {n_axes} per pose')
    poses = []
    for k, q in enumerate(d['poses']):
        ok = isinstance(q, list) and len(q) == n_axes and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)
            for v in q)
        if not ok:
            raise FrfIdentInputError(f'{path}: poses[{k}] = {q!r}; expected {n_axes} finite '
                                     f'joint positions [rad]')
        poses.append([float(v) for v in q])
    urdf = d.get('urdf')
    if urdf is not None and not isinstance(urdf, str):
        raise FrfIdentInputError(f'{path}: urdf = {urdf!r}; expected a file name')
    return poses, (Path(path).parent / urdf if urdf else None)
