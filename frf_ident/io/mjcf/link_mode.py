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
An axis' second, link-side mode as MJCF: a child body of the link body on its own hinge.

Our model (frf_ident/core/model/params.py, ``AxisParams.second_mode``) puts a share J_e of the
link inertia on a spring J_e (2 pi f)^2 behind the link, damped 2 zeta J_e 2 pi f. In MJCF
(:func:`add_modes`): the body holding the axis' link-side hinge (the joint's own body on a
rigid joint) gets a child body ``<joint>_mode_body`` at the hinge's anchor with the hinge
``<joint>`` + :data:`~frf_ident.io.mjcf.drive_map.MODE_SUFFIX` on the same axis, ``stiffness``
and ``damping`` as above, and a disc's inertia: J_e about the axis, J_e / 2 across it (the
least a body can have with moment J_e, so the most often a link body can give it up), its
centre on the axis (gravity does not load the mode spring) and
:data:`~frf_ident.io.mjcf.drive_map.MODE_BODY_MASS`.

The same disc and mass are taken from the link body (its inertial rewritten about the new
centre of mass, parallel-axis terms included): with the mode at rest the arm's rigid body is
the MJCF's exactly, so the low-frequency inertia is the model's. Where the remainder is not a
valid inertia (the link body itself has less than the disc about some axis) the link body is
kept and that is reported as a Limitation: the low-frequency inertia is then J_e larger.
"""
from __future__ import annotations

import math

from frf_ident.errors import MjcfError
from frf_ident.io.mjcf.drive_map import JointDrive, Limitation, MODE_BODY_MASS, MODE_SUFFIX
from frf_ident.io.mjcf.held import SPRING_MAX_STEP_ANGLE
from frf_ident.io.mjcf.spec_edit import link_joint
import mujoco
import numpy as np

__all__ = ['INERTIA_MARGIN', 'add_modes', 'mode_joint', 'read_mode']

#: the link body's inertia less the mode's must keep its principal moments above this share of
#: its largest one, and satisfy the triangle inequality by as much: else MuJoCo refuses it (or
#: integrates a body near the limit badly), and the link body is kept (reported)
INERTIA_MARGIN = 1e-6


def _host(spec: mujoco.MjSpec, joint: str):
    """Return the hinge the mode sits behind: the link-side hinge, else the joint itself."""
    lj = link_joint(spec, joint)
    return lj if lj is not None else spec.joint(joint)


def mode_joint(spec: mujoco.MjSpec, joint: str):
    """
    Return the hinge of ``joint``'s second mode, or None.

    Raises
    ------
    MjcfError
        The hinge ``<joint>_mode`` is not in a child body of the link body, or not on its axis.

    """
    j, mj = spec.joint(joint), spec.joint(joint + MODE_SUFFIX)
    if j is None or mj is None:
        return None
    host = _host(spec, joint)
    if mj.parent.parent.name != host.parent.name:
        raise MjcfError(f'joint {mj.name!r} is not in a child body of the link body '
                        f'{host.parent.name!r} of {joint!r} (a second mode, docs/mujoco.md)')
    return mj


def _rot(quat: np.ndarray) -> np.ndarray:
    r = np.zeros(9)
    mujoco.mju_quat2Mat(r, np.asarray(quat, float) / np.linalg.norm(quat))
    return r.reshape(3, 3)


def _shift(r: np.ndarray) -> np.ndarray:
    """Parallel-axis term of a unit mass at ``r``: |r|^2 I - r r^T."""
    return float(r @ r) * np.eye(3) - np.outer(r, r)


def _valid(moments: np.ndarray) -> bool:
    """Tell whether principal moments are a body's, with :data:`INERTIA_MARGIN` to spare."""
    tol = INERTIA_MARGIN * max(float(moments.max()), 1e-300)
    a, b, c = np.sort(moments)
    return a > tol and a + b >= c + tol


def _reduce_link(model: mujoco.MjModel, body, bid: int, axis: np.ndarray, anchor: np.ndarray,
                 inertia: float) -> float | None:
    """
    Take the mode's disc and mass out of the link body; return None, else what it has.

    None: done (exact). A float: the link body kept; its moment [kg m^2] about the mode's
    axis through its centre of mass (what a disc could be taken from).
    """
    m, c = float(model.body_mass[bid]), model.body_ipos[bid].copy()
    r = _rot(model.body_iquat[bid])
    full = r @ np.diag(model.body_inertia[bid]) @ r.T
    disc = 0.5 * inertia * (np.eye(3) + np.outer(axis, axis))
    own = float(axis @ full @ axis)
    me = MODE_BODY_MASS
    if m <= me:
        return own
    c_new = (m * c - me * anchor) / (m - me)
    rest = full - disc - me * _shift(anchor - c) - (m - me) * _shift(c_new - c)
    rest = 0.5 * (rest + rest.T)
    moments, vec = np.linalg.eigh(rest)
    if not _valid(moments):
        return own
    if np.linalg.det(vec) < 0:
        vec[:, 0] = -vec[:, 0]
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, vec.flatten())
    body.fullinertia = [math.nan, 0.0, 0.0, 0.0, 0.0, 0.0]
    body.mass, body.ipos, body.inertia, body.iquat = m - me, c_new, moments, q
    body.explicitinertial = True
    return None


def _add_mode_body(host, axis: np.ndarray, anchor: np.ndarray, d: JointDrive) -> None:
    """Add the child body at the anchor, its z on the axis, a disc, and the mode's hinge."""
    q = np.zeros(4)
    mujoco.mju_quatZ2Vec(q, np.asarray(axis, float))
    child = host.parent.add_body(name=d.joint + MODE_SUFFIX + '_body', pos=anchor, quat=q)
    je = d.mode_inertia
    child.mass, child.ipos, child.iquat = MODE_BODY_MASS, [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
    child.inertia, child.explicitinertial = [0.5 * je, 0.5 * je, je], True
    j = child.add_joint(name=d.mode_joint, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1],
                        pos=[0.0, 0.0, 0.0])
    j.limited = mujoco.mjtLimited.mjLIMITED_FALSE
    j.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE
    j.armature, j.frictionloss, j.springref, j.ref = 0.0, 0.0, 0.0, 0.0
    _set_terms(j, d)


def _set_terms(j, d: JointDrive) -> None:
    # MuJoCo 4: stiffness and damping are polynomials [linear, quadratic, cubic]
    j.stiffness = [d.mode_stiffness, 0.0, 0.0]
    j.damping = [d.mode_damping, 0.0, 0.0]


def add_modes(spec: mujoco.MjSpec, drives: list[JointDrive], *,
              link_inertia: dict[str, float] | None = None) -> list[Limitation]:
    """
    Write each drive's second mode into ``spec`` (in place; after the elastic pairs are in).

    A joint that already has its mode hinge gets the drive's ``stiffness`` and ``damping``
    (its body's inertia kept: reported where it is not the drive's). ``link_inertia``: joint
    -> its link inertia at the pose [kg m^2], to say what share of it an approximation adds.

    Returns
    -------
    list of Limitation
        The modes written inexactly: the link body kept (low-frequency inertia +J_e), a mode
        body's inertia kept, a mode MuJoCo's time step cannot integrate.

    """
    todo = [d for d in drives if d.has_mode]
    if not todo:
        return []
    model = spec.compile()
    lims = []
    h = float(spec.option.timestep)
    for d in todo:
        value = (f'{d.mode_inertia:.4g} kg m^2 at '
                 f'{math.sqrt(d.mode_stiffness / d.mode_inertia) / (2 * math.pi):.4g} Hz')
        existing = mode_joint(spec, d.joint)
        if existing is not None:
            _set_terms(existing, d)
            je = read_mode(model, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT,
                                                    existing.name))[0]
            if abs(je / d.mode_inertia - 1.0) > 1e-6:
                lims.append(Limitation(d.joint, 'second_mode', value,
                                       f"written: the MJCF's mode body kept, {je:.4g} kg m^2"))
        else:
            lims += _new_mode(spec, model, d, value, (link_inertia or {}).get(d.joint))
        if math.sqrt(d.mode_stiffness / d.mode_inertia) * h > SPRING_MAX_STEP_ANGLE:
            lims.append(Limitation(d.joint, 'second_mode', value, "written, but MuJoCo's time "
                                   f'step {h:g} s cannot integrate it (w h > '
                                   f'{SPRING_MAX_STEP_ANGLE:g}): lower the MJCF timestep'))
    return lims


def _new_mode(spec: mujoco.MjSpec, model: mujoco.MjModel, d: JointDrive, value: str,
              inertia: float | None) -> list[Limitation]:
    host = _host(spec, d.joint)
    jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, host.name)
    bid = int(model.jnt_bodyid[jid])
    axis = model.jnt_axis[jid] / np.linalg.norm(model.jnt_axis[jid])
    anchor = model.jnt_pos[jid].copy()
    fromgeom = spec.compiler.inertiafromgeom == mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE
    own = math.nan if fromgeom else _reduce_link(model, host.parent, bid, axis, anchor,
                                                 d.mode_inertia)
    _add_mode_body(host, axis, anchor, d)
    if own is None:
        return []
    why = ('the compiler takes inertias from the geoms' if fromgeom else
           f'about the axis through its centre of mass it has {own:.4g} kg m^2, too little '
           f"to give up the mode's disc")
    return [Limitation(d.joint, 'second_mode', value, f'written: the mode body added to the '
                       f'link body {host.parent.name!r} kept as it is ({why}): the '
                       f'low-frequency inertia is {d.mode_inertia:.4g} kg m^2 larger'
                       + ('' if inertia is None else
                          f', {100 * d.mode_inertia / inertia:.1f} % of the link inertia '
                          f'{inertia:.4g} kg m^2 at the pose'))]


def read_mode(model: mujoco.MjModel, jid: int) -> tuple[float, float, float]:
    """Return (inertia about the hinge [kg m^2], stiffness, damping) of a mode hinge ``jid``."""
    bid = int(model.jnt_bodyid[jid])
    axis = model.jnt_axis[jid] / np.linalg.norm(model.jnt_axis[jid])
    r = _rot(model.body_iquat[bid])
    full = r @ np.diag(model.body_inertia[bid]) @ r.T
    off = model.body_ipos[bid] - model.jnt_pos[jid]
    je = float(axis @ full @ axis + model.body_mass[bid] * (_shift(off) @ axis @ axis))
    return je, float(model.jnt_stiffness[jid]), float(model.dof_damping[model.jnt_dofadr[jid]])
