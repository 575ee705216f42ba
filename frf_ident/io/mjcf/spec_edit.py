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
Edits of an MJCF through MuJoCo's model editor (``mujoco.MjSpec``).

Lock a joint at a pose, insert the series-elastic hinge pair, set a joint's drive terms. Each
function changes the spec in place (:func:`split_elastic` returns a new one); the caller
compiles it (``spec.compile()``) or writes it (``spec.to_xml()``). The attribute names are
those of :data:`~frf_ident.io.mjcf.drive_map.MAPPING`.
"""
from __future__ import annotations

from frf_ident.errors import MjcfError
from frf_ident.io.mjcf.drive_map import (JointDrive, LINK_SUFFIX, MOTOR_BODY_INERTIA,
                                         MOTOR_BODY_MASS)
import mujoco
import numpy as np

#: joint types a pose can place (numpy ints compare with these, not with the enum)
_MOVABLE = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))

__all__ = ['find_actuator', 'link_joint', 'lock_joint', 'set_drive', 'split_elastic']


def _rotation(axis: np.ndarray, angle: float) -> tuple[np.ndarray, np.ndarray]:
    """Quaternion and matrix of a rotation by ``angle`` about the unit ``axis``."""
    q = np.zeros(4)
    mujoco.mju_axisAngle2Quat(q, np.asarray(axis, float) / np.linalg.norm(axis), float(angle))
    r = np.zeros(9)
    mujoco.mju_quat2Mat(r, q)
    return q, r.reshape(3, 3)


def lock_joint(spec: mujoco.MjSpec, name: str, position: float) -> None:
    """
    Weld a hinge or slide joint at ``position``: its body moved there, the joint removed.

    Exact for the rigid body (the body's frame rotated about the joint's axis through its
    anchor, or shifted along it); its actuators are removed with it.

    Raises
    ------
    MjcfError
        The joint is a ball or free joint, or its body's frame is not a plain pos/quat.

    """
    j = spec.joint(name)
    body = j.parent
    if j.type == mujoco.mjtJoint.mjJNT_SLIDE:
        quat = np.array(body.quat, float)
        rb = np.zeros(9)
        mujoco.mju_quat2Mat(rb, quat / np.linalg.norm(quat))
        body.pos = np.array(body.pos) + rb.reshape(3, 3) @ (np.array(j.axis) * position)
    elif j.type == mujoco.mjtJoint.mjJNT_HINGE:
        qr, r = _rotation(np.array(j.axis, float), position)
        quat = np.array(body.quat, float)
        quat /= np.linalg.norm(quat)
        rb = np.zeros(9)
        mujoco.mju_quat2Mat(rb, quat)
        anchor = np.array(j.pos, float)
        body.pos = np.array(body.pos) + rb.reshape(3, 3) @ (anchor - r @ anchor)
        out = np.zeros(4)
        mujoco.mju_mulQuat(out, quat, qr)
        body.quat = out
    else:
        raise MjcfError(f'joint {name!r} ({j.type.name}): only hinge and slide joints can be '
                        f'held at the pose; identify it or make it a hinge')
    for act in list(spec.actuators):
        if act.trntype == mujoco.mjtTrn.mjTRN_JOINT and act.target == name:
            spec.delete(act)
    spec.delete(j)


def find_actuator(spec: mujoco.MjSpec, joint: str):
    """Return the one actuator on ``joint`` (joint transmission), or raise MjcfError."""
    acts = [a for a in spec.actuators
            if a.trntype == mujoco.mjtTrn.mjTRN_JOINT and a.target == joint]
    if len(acts) != 1:
        raise MjcfError(f'joint {joint!r}: expected one actuator with joint="{joint}" (a torque '
                        f'motor), found {len(acts)}')
    return acts[0]


def link_joint(spec: mujoco.MjSpec, joint: str):
    """Return the link-side hinge of ``joint``'s series-elastic pair, or None (rigid)."""
    j = spec.joint(joint)
    other = spec.joint(joint + LINK_SUFFIX)
    if other is None or j is None:
        return None
    if other.parent.parent.name != j.parent.name:
        raise MjcfError(f'joint {other.name!r} is not in a child body of the body '
                        f'{j.parent.name!r} of {joint!r} (the series-elastic pair, '
                        f'docs/mujoco.md)')
    if not np.allclose(np.cross(np.array(other.axis), np.array(j.axis)), 0.0, atol=1e-9):
        raise MjcfError(f'joint {other.name!r}: axis {list(other.axis)} is not the axis '
                        f'{list(j.axis)} of {joint!r} (the series-elastic pair)')
    return other


#: attributes that place a body in its parent's frame (moved to the motor-side body)
_FRAME_ATTRS = ('pos', 'quat', 'axisangle', 'euler', 'xyaxes', 'zaxis')


def split_elastic(spec: mujoco.MjSpec, joints: list[str]) -> mujoco.MjSpec:
    """
    Insert the series-elastic hinge pair at each of ``joints`` (ours -> MJCF, docs/mujoco.md).

    Body B holding hinge J becomes: a new body ``B`` + ``_motor`` where B was (B's frame and
    childclass), holding J (the motor side, with the tiny inertial of
    :data:`~frf_ident.io.mjcf.drive_map.MOTOR_BODY_MASS`), and inside it B at the identity frame,
    keeping its name, inertial, geoms, sites, children, with the link-side hinge J +
    :data:`~frf_ident.io.mjcf.drive_map.LINK_SUFFIX` on J's axis and anchor (no range, no
    armature, no friction: stiffness and damping are set by :func:`set_drive`). Every other
    name stays. Joints that already have the pair are left as they are.

    Returns
    -------
    MjSpec
        A new spec (MJCF text edited through ``to_xml``; the structure cannot be moved in place).

    """
    import xml.etree.ElementTree as ET
    todo = [j for j in joints if link_joint(spec, j) is None]
    if not todo:
        return spec
    model = spec.compile()
    root = ET.fromstring(spec.to_xml())
    parents = {c: p for p in root.iter() for c in p}
    for name in todo:
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
        if int(model.jnt_type[jid]) != int(mujoco.mjtJoint.mjJNT_HINGE):
            raise MjcfError(f'joint {name!r}: a series elasticity needs a hinge')
        el = next((e for e in root.iter('joint') if e.get('name') == name), None)
        body = parents[el]
        if len(body.findall('joint')) + len(body.findall('freejoint')) != 1:
            raise MjcfError(f'body {body.get("name")!r}: the series-elastic pair needs the '
                            f'joint {name!r} alone in its body')
        outer = ET.Element('body', {'name': f'{body.get("name") or name}_motor'})
        for key in _FRAME_ATTRS + ('childclass',):
            if key in body.attrib:
                outer.set(key, body.attrib.pop(key))
        if 'childclass' in outer.attrib:
            body.set('childclass', outer.get('childclass'))
        parent = parents[body]
        parent.insert(list(parent).index(body), outer)
        parent.remove(body)
        axis, pos = model.jnt_axis[jid], model.jnt_pos[jid]
        ET.SubElement(outer, 'inertial', {'pos': _vec(pos), 'mass': repr(MOTOR_BODY_MASS),
                                          'diaginertia': _vec([MOTOR_BODY_INERTIA] * 3)})
        body.remove(el)
        outer.append(el)
        outer.append(body)
        link = ET.Element('joint', {'name': name + LINK_SUFFIX, 'type': 'hinge',
                                    'axis': _vec(axis), 'pos': _vec(pos), 'limited': 'false',
                                    'armature': '0', 'frictionloss': '0', 'damping': '0',
                                    'stiffness': '0', 'springref': '0', 'ref': '0'})
        body.insert(0, link)
        parents = {c: p for p in root.iter() for c in p}
    out = mujoco.MjSpec.from_string(ET.tostring(root, encoding='unicode'))
    _carry_keyframes(model, out)
    return out


def _carry_keyframes(old: mujoco.MjModel, spec: mujoco.MjSpec) -> None:
    """Rewrite the keyframes' qpos by joint name (a new link-side hinge at 0), qvel zero."""
    new = spec.compile()
    for k, key in enumerate(spec.keys):
        qpos = new.qpos0.copy()
        for j in range(new.njnt):
            name = mujoco.mj_id2name(new, mujoco.mjtObj.mjOBJ_JOINT, j)
            jo = mujoco.mj_name2id(old, mujoco.mjtObj.mjOBJ_JOINT, name)
            if jo >= 0 and int(old.jnt_type[jo]) in _MOVABLE:
                qpos[new.jnt_qposadr[j]] = old.key_qpos[k, old.jnt_qposadr[jo]]
        key.qpos = qpos
        key.qvel = np.zeros(new.nv)


def _vec(v) -> str:
    return ' '.join(repr(float(x)) for x in v)


def set_drive(spec: mujoco.MjSpec, drive: JointDrive) -> None:
    """
    Write a joint's drive terms on the motor-side and (when elastic) the link-side hinge.

    ``armature``, ``damping``, ``frictionloss`` on the motor-side hinge; ``stiffness`` and
    ``damping`` on the link-side hinge (which :func:`split_elastic` inserts); the
    actuator's ``ctrlrange`` from the torque limit and its gear, ``delay`` when not 0.
    """
    j = spec.joint(drive.joint)
    if j is None:
        raise MjcfError(f'joint {drive.joint!r}: not in the MJCF')
    # MuJoCo 4: stiffness and damping are polynomials [linear, quadratic, cubic]
    j.armature, j.frictionloss = drive.armature, drive.frictionloss
    j.damping = [drive.damping, 0.0, 0.0]
    if drive.elastic:
        lj = link_joint(spec, drive.joint)
        if lj is None:
            raise MjcfError(f'joint {drive.joint!r}: no link-side hinge '
                            f'{drive.link_joint!r}; split_elastic first')
        lj.stiffness = [drive.stiffness, 0.0, 0.0]
        lj.damping = [drive.link_damping, 0.0, 0.0]
        lj.springref = 0.0
    act = find_actuator(spec, drive.joint)
    gear = float(act.gear[0])
    act.ctrllimited = True
    act.ctrlrange = [-drive.torque_limit / gear, drive.torque_limit / gear]
    if drive.delay > 0:
        act.delay = drive.delay
