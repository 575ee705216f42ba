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
The shared KUKA LBR iiwa 14 MJCF with drive effects added, and MuJoCo's own truth about it.

Written for the tests without :mod:`frf_ident.io.mjcf`: the series-elastic hinge pair is put in
by plain text edits of the shared file, the held joints are removed from the text (they are at
0 in the ``home`` keyframe, so a removed joint is the joint held there), the state of rest is
found by scipy, and the truth is MuJoCo's ``mjd_transitionFD`` at that state.

Values a real iiwa 14 could have (harmonic drives, ratio ~160; joint torque sensors in series):
joint 2 (link-side inertia 3.08 kg m^2 at home) rotor 1.0 kg m^2, spring 1.5e4 N m/rad: its
resonance and antiresonance near 22 and 11 Hz; joint 4 (0.86 kg m^2) rotor 0.4 kg m^2, spring
8e3 N m/rad: near 27 and 15 Hz. Damping about 5 % of critical.
"""
from __future__ import annotations

from pathlib import Path
import re

import numpy as np

SHARED_IIWA = Path(__file__).resolve().parents[2].parent / 'shared' / 'data' / 'MuJoCo_iiwa14' \
    / 'iiwa14_dynamics.xml'

#: joint -> (armature [kg m^2], motor damping [N m s/rad], stiffness [N m/rad], link damping)
ELASTIC = {'joint2': (1.0, 5.0, 1.5e4, 10.0), 'joint4': (0.4, 3.0, 8.0e3, 5.0)}
AXES = ['joint1', 'joint2', 'joint4']
HELD = ['joint3', 'joint5', 'joint6', 'joint7']
#: velocity PI of the three axes (bandwidth a few Hz on the rotor + link inertia)
KP = [150.0, 150.0, 50.0]
KI = [1500.0, 1500.0, 500.0]


def elastic_xml(held: list[str] = (), elastic: dict = ELASTIC, *, rigid: dict | None = None,
                frictionloss: dict | None = None) -> str:
    """
    Return the shared MJCF text with drive terms added and without ``held`` joints.

    ``elastic``: joint -> (armature, motor damping, stiffness, link damping), the series hinge
    pair; ``rigid``: joint -> (armature, damping) on a joint left rigid; ``frictionloss``:
    joint -> dry friction [N m] on the (motor-side) joint.
    """
    text = SHARED_IIWA.read_text()
    rigid, frictionloss = dict(rigid or {}), dict(frictionloss or {})
    for joint, (arm, damp) in rigid.items():
        pat = rf'<joint name="{joint}" class="(\w+)"/>'
        assert re.search(pat, text), joint
        text = re.sub(pat, rf'<joint name="{joint}" class="\1" armature="{arm}" '
                           rf'damping="{damp}"/>', text)
    for joint, fc in frictionloss.items():
        pat = rf'(<joint name="{joint}" class="\w+")'
        assert re.search(pat, text), joint
        text = re.sub(pat, rf'\1 frictionloss="{fc}"', text)
    for joint, (arm, damp, k, dl) in elastic.items():
        n = joint[-1]
        pat = re.compile(rf'(<body name="link{n}"([^>]*)>)(\s*)(<inertial [^>]*/>)'
                         rf'(\s*)<joint name="{joint}" class="(\w+)"([^/]*)/>')
        m = pat.search(text)
        assert m, joint
        frame, ws = m.group(2), m.group(3)
        new = (f'<body name="link{n}_motor"{frame}>{ws}'
               f'<inertial pos="0 0 0" mass="1e-6" diaginertia="1e-9 1e-9 1e-9"/>{ws}'
               f'<joint name="{joint}" class="{m.group(6)}"{m.group(7)} armature="{arm}" '
               f'damping="{damp}"/>'
               f'{ws}<body name="link{n}">{ws}{m.group(4)}{ws}'
               f'<joint name="{joint}_link" axis="0 0 1" limited="false" stiffness="{k}" '
               f'damping="{dl}"/>')
        text = text[:m.start()] + new + text[m.end():]
        # close the extra body right where link{n} closed: before the </body> that ends it
        text = _close_after(text, f'<body name="link{n}">')
    for joint in held:
        text = re.sub(rf'\s*<joint name="{joint}" [^>]*/>', '', text)
        text = re.sub(rf'\s*<motor name="actuator{joint[-1]}" [^>]*/>', '', text)
    if held or elastic or rigid or frictionloss:
        text = re.sub(r'\s*<keyframe>.*</keyframe>', '', text, flags=re.S)
    return text


def _close_after(text: str, opening: str) -> str:
    """Add one </body> after the element that ``opening`` starts (bodies nest)."""
    i = text.index(opening) + len(opening)
    depth = 1
    for m in re.finditer(r'<body\b[^>]*?(/?)>|</body>', text[i:]):
        if m.group(0).startswith('</'):
            depth -= 1
        elif not m.group(1):
            depth += 1
        if depth == 0:
            j = i + m.end()
            return text[:j] + '</body>' + text[j:]
    raise AssertionError(opening)


def home() -> dict[str, float]:
    """Return the home keyframe of the shared file, joint -> rad."""
    m = re.search(r'<key name="home" qpos="([^"]+)"', SHARED_IIWA.read_text())
    return {f'joint{i + 1}': float(v) for i, v in enumerate(m.group(1).split())}


def truth_frf(xml: str, freq_hz: np.ndarray, pose: dict[str, float], axes=AXES,
              dt: float = 1e-3) -> np.ndarray:
    """
    Return MuJoCo's linearisation at rest at ``pose`` as a discrete FRF (torque -> velocity).

    The rest: the link angle at the pose, each series spring deflected so that the link-side
    hinge needs no force (scipy root of mj_inverse's force there); then mjd_transitionFD with
    the holding torques applied (each axis' actuator found by its joint), and C (zI - A)^-1 B
    at z = exp(j 2 pi f dt) (timestep = dt).
    """
    import mujoco
    from scipy.optimize import fsolve
    m = mujoco.MjModel.from_xml_string(xml)
    assert abs(m.opt.timestep - dt) < 1e-15
    d = mujoco.MjData(m)
    jid = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j): j for j in range(m.njnt)}
    link = [a for a in axes if a + '_link' in jid]

    def put(delta):
        d.qpos[:] = 0.0
        for a in axes:
            d.qpos[m.jnt_qposadr[jid[a]]] = pose[a]
        for a, x in zip(link, delta):
            d.qpos[m.jnt_qposadr[jid[a]]] -= x
            d.qpos[m.jnt_qposadr[jid[a + '_link']]] = x
        d.qvel[:] = 0.0
        d.qacc[:] = 0.0
        mujoco.mj_inverse(m, d)
        return np.array([d.qfrc_inverse[m.jnt_dofadr[jid[a + '_link']]] for a in link])

    delta = fsolve(put, np.zeros(len(link)), xtol=1e-14) if link else np.zeros(0)
    put(delta)
    acts = [next(k for k in range(m.nu) if m.actuator_trnid[k, 0] == jid[a]) for a in axes]
    d.ctrl[acts] = [d.qfrc_inverse[m.jnt_dofadr[jid[a]]] for a in axes]
    mujoco.mj_forward(m, d)
    nx = 2 * m.nv
    A, B = np.zeros((nx, nx)), np.zeros((nx, m.nu))
    mujoco.mjd_transitionFD(m, d, 1e-6, True, A, B, None, None)
    B = B[:, acts]
    C = np.zeros((len(axes), nx))
    for i, a in enumerate(axes):
        C[i, m.nv + m.jnt_dofadr[jid[a]]] = 1.0
    z = np.exp(2j * np.pi * np.asarray(freq_hz) * dt)
    return np.stack([C @ np.linalg.solve(zk * np.eye(nx) - A, B) for zk in z], axis=-1)


def linear_frf(xml: str, freq_hz: np.ndarray, pose: dict[str, float], axes: list[str],
               dt: float = 1e-3) -> np.ndarray:
    """
    Return MuJoCo's linearisation of any MJCF text at rest at ``pose`` (torque -> velocity).

    :func:`truth_frf` for an MJCF written by anyone (the diagnosis' extended_model.xml, an
    MJCF of a URDF): every hinge that is not an axis or an axis' link-side hinge
    (``<axis>_link``) is removed through MuJoCo's own editor at its position in ``pose``
    (which must be 0: a removed joint is the joint held at 0), the axes' actuators are found
    by their joint, and dry friction is switched off (``mjDSBL_FRICTIONLOSS``: MuJoCo's
    frictionloss is a constraint that holds a joint at rest, it has no linearisation there;
    its value is checked on its own); then as :func:`truth_frf`.
    """
    import mujoco
    spec = mujoco.MjSpec.from_string(xml)
    keep = set(axes) | {a + '_link' for a in axes}
    for a in list(spec.actuators):
        if a.target not in keep:
            spec.delete(a)
    for j in list(spec.joints):
        if j.name not in keep:
            assert abs(pose.get(j.name, 0.0)) < 1e-12, j.name
            spec.delete(j)
    for k in list(spec.keys):
        spec.delete(k)
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS
    return truth_frf(spec.to_xml(), freq_hz, pose, axes, dt)


def with_drives(xml: str, *, elastic: dict | None = None, rigid: dict | None = None,
                frictionloss: dict | None = None) -> str:
    """
    Return any MJCF text with drive terms added, by the test's own XML edits.

    :func:`elastic_xml` for an MJCF other than the shared iiwa file (e.g. one MuJoCo wrote
    from a URDF): the same arguments; each elastic joint must be alone in its body, whose
    frame attributes move to a new body ``<body>_motor`` holding the motor-side joint, the
    body itself (inertial, children) inside it with the link-side hinge ``<joint>_link``.
    Written without :mod:`frf_ident.io.mjcf` (the code under test).
    """
    import xml.etree.ElementTree as ET
    root = ET.fromstring(xml)
    parents = {c: p for p in root.iter() for c in p}
    joints = {j.get('name'): j for j in root.iter('joint') if j.get('name')}
    for name, (arm, damp) in (rigid or {}).items():
        joints[name].set('armature', repr(arm))
        joints[name].set('damping', repr(damp))
    for name, fc in (frictionloss or {}).items():
        joints[name].set('frictionloss', repr(fc))
    for name, (arm, damp, k, dl) in (elastic or {}).items():
        j = joints[name]
        body = parents[j]
        outer = ET.Element('body', {'name': body.get('name') + '_motor'})
        for key in ('pos', 'quat', 'euler', 'axisangle', 'xyaxes', 'zaxis'):
            if key in body.attrib:
                outer.set(key, body.attrib.pop(key))
        parent = parents[body]
        parent.insert(list(parent).index(body), outer)
        parent.remove(body)
        ET.SubElement(outer, 'inertial', {'pos': j.get('pos', '0 0 0'), 'mass': '1e-6',
                                          'diaginertia': '1e-9 1e-9 1e-9'})
        body.remove(j)
        j.set('armature', repr(arm))
        j.set('damping', repr(damp))
        outer.append(j)
        outer.append(body)
        body.insert(0, ET.Element('joint', {
            'name': name + '_link', 'axis': j.get('axis', '0 0 1'),
            'pos': j.get('pos', '0 0 0'), 'limited': 'false', 'stiffness': repr(k),
            'damping': repr(dl)}))
    return ET.tostring(root, encoding='unicode')
