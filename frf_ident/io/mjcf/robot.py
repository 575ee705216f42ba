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
An MJCF robot prepared for identification: the axes, the pose, the held joints, the state of rest.

:func:`load_robot` reads the MJCF, checks each axis (a hinge with one torque motor), takes the
start pose (a keyframe, else the file's ``qpos0``, with the model file's joint positions over
it) and locks every other hinge or slide joint at that pose: its joint is removed and its body
welded where the pose puts it (:func:`~frf_ident.io.mjcf.spec_edit.lock_joint`), which is exact
for the rigid body and costs no constraint; MuJoCo then fuses the welded bodies into their
parents (``compiler fusestatic``). MuJoCo's own options stay (integrator, time step,
gravity). :class:`MjcfRobot` holds the compiled model and finds the state of rest at the pose
(:meth:`MjcfRobot.rest`: the series springs deflected under gravity, the holding torques).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from frf_ident.core.model.params import MjcfSource
from frf_ident.errors import MjcfError
from frf_ident.io.mjcf.link_mode import mode_joint
from frf_ident.io.mjcf.spec_edit import find_actuator, link_joint, lock_joint
import mujoco
import numpy as np

#: joint types a pose can place (numpy ints compare with these, not with the enum)
_MOVABLE = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))

__all__ = ['MjcfRobot', 'Rest', 'load_robot', 'load_spec']

#: iterations and tolerance [rad] of the static deflection of the series springs at rest
REST_ITERATIONS = 50
REST_TOLERANCE = 1e-12


def load_spec(path: str | Path) -> mujoco.MjSpec:
    """Read an MJCF into a spec; a missing or invalid file raises MjcfError naming it."""
    p = Path(path)
    if not p.is_file():
        raise MjcfError(f'{p}: MJCF file not found')
    try:
        return mujoco.MjSpec.from_file(str(p))
    except (ValueError, RuntimeError) as err:
        raise MjcfError(f'{p}: not a valid MJCF ({str(err).strip().splitlines()[0]})') from err


@dataclass
class Rest:
    """The state of rest at the pose: qpos of the simulation model and the holding torques."""

    qpos: np.ndarray
    hold: np.ndarray


class MjcfRobot:
    """
    The compiled simulation model of an MJCF with its axes; see :func:`load_robot`.

    Attributes
    ----------
    model : mujoco.MjModel
        The simulation model (held joints locked, keyframes removed).
    axes : list of str
        The identified (motor-side) joints, in axis order.
    pose : dict of str to float
        The start pose of every hinge and slide joint [rad or m].
    gear : ndarray, shape (n,)
        Our command u [N m] is ``gear * ctrl`` of each axis' actuator.
    gain : ndarray, shape (n,)
        ``gainprm[0]`` of each axis' actuator: the torque applied is ``gain * u``.
    torque_limit : ndarray, shape (n,)
        ``gear * ctrlrange`` [N m] (infinite without a ctrlrange).

    """

    def __init__(self, spec: mujoco.MjSpec, source: str, axes: list[str],
                 pose: dict[str, float]) -> None:
        self.source, self.axes, self.pose = source, list(axes), dict(pose)
        try:
            self.model = spec.compile()
        except (ValueError, RuntimeError) as err:
            raise MjcfError(f'{source}: does not compile after holding the other joints '
                            f'({str(err).strip().splitlines()[0]})') from err
        m = self.model
        ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, a) for a in axes]
        self.qadr = np.array([m.jnt_qposadr[j] for j in ids], dtype=np.int64)
        self.vadr = np.array([m.jnt_dofadr[j] for j in ids], dtype=np.int64)
        link = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, a + '_link') for a in axes]
        self.link_qadr = np.array([m.jnt_qposadr[j] if j >= 0 else -1 for j in link], np.int64)
        self.link_vadr = np.array([m.jnt_dofadr[j] if j >= 0 else -1 for j in link], np.int64)
        self.actuator = np.array([_actuator_of(m, j, a) for j, a in zip(ids, axes)], np.int64)
        self.gear = m.actuator_gear[self.actuator, 0].copy()
        self.gain = m.actuator_gainprm[self.actuator, 0].copy()
        lim = np.full(len(axes), np.inf)
        for i, a in enumerate(self.actuator):
            if m.actuator_ctrllimited[a]:
                lim[i] = self.gear[i] * max(abs(m.actuator_ctrlrange[a]).min(), 0.0)
            if m.actuator_forcelimited[a]:
                lim[i] = min(lim[i], self.gear[i] * abs(m.actuator_forcerange[a]).min())
        self.torque_limit = lim

    @property
    def n_axes(self) -> int:
        """Return the number of axes."""
        return len(self.axes)

    @property
    def elastic(self) -> np.ndarray:
        """Tell per axis whether it has the series-elastic hinge pair."""
        return self.link_qadr >= 0

    def substeps(self, dt: float) -> int:
        """
        Return the MuJoCo steps per sample of period ``dt`` [s].

        Raises
        ------
        MjcfError
            The MJCF's ``timestep`` does not divide ``dt``.

        """
        h = float(self.model.opt.timestep)
        m = round(dt / h)
        if m < 1 or abs(m * h - dt) > 1e-9 * dt:
            raise MjcfError(f'{self.source}: option timestep {h:g} s does not divide the sample '
                            f'period {dt:g} s (sample_rate {1 / dt:g} Hz); choose a '
                            f'sample_rate of {1 / h:g} Hz / k')
        return m

    def rest(self, position: np.ndarray | None = None) -> Rest:
        """
        Return the state of rest with the axes' links at ``position`` (default the pose).

        The series springs carry the gravity load: the link-side hinge deflects by the
        static solution of -k delta + g(q) = 0 (fixed-point iteration of mj_inverse), the
        motor-side hinge sits at the link angle less that deflection; the holding torque of
        each axis is the generalized force mj_inverse needs on its motor-side hinge.

        Parameters
        ----------
        position : array_like, shape (n,), optional
            Link positions of the axes [rad].

        Returns
        -------
        Rest
            The simulation model's qpos and the holding torques u [N m].

        """
        m = self.model
        d = mujoco.MjData(m)
        link = np.array([self.pose[a] for a in self.axes]) if position is None \
            else np.asarray(position, dtype=float)
        el = self.elastic
        k = np.where(el, m.jnt_stiffness[np.maximum(
            [m.dof_jntid[v] if v >= 0 else 0 for v in self.link_vadr], 0)], 1.0)
        delta = np.zeros(self.n_axes)
        flags = m.opt.disableflags
        m.opt.disableflags = flags | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
        try:
            for _ in range(REST_ITERATIONS):
                d.qpos[:] = m.qpos0
                d.qpos[self.qadr] = link - delta
                d.qpos[self.link_qadr[el]] = delta[el]
                d.qvel[:] = 0.0
                d.qacc[:] = 0.0
                mujoco.mj_inverse(m, d)
                step = d.qfrc_inverse[self.link_vadr[el]] / k[el] if el.any() else np.zeros(0)
                delta[el] -= step
                if not el.any() or np.max(np.abs(step)) < REST_TOLERANCE:
                    break
            torque = d.qfrc_inverse[self.vadr] / self.gain
        finally:
            m.opt.disableflags = flags
        return Rest(d.qpos.copy(), torque)


def _actuator_of(m: mujoco.MjModel, joint: int, name: str) -> int:
    """Return the actuator of an axis: one torque motor on the joint."""
    acts = [a for a in range(m.nu) if int(m.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT)
            and m.actuator_trnid[a, 0] == joint]
    if len(acts) != 1:
        raise MjcfError(f'joint {name!r}: expected one actuator on it, found {len(acts)}')
    a = acts[0]
    if (int(m.actuator_gaintype[a]) != int(mujoco.mjtGain.mjGAIN_FIXED)
            or int(m.actuator_biastype[a]) != int(mujoco.mjtBias.mjBIAS_NONE)
            or int(m.actuator_dyntype[a]) != int(mujoco.mjtDyn.mjDYN_NONE)):
        raise MjcfError(f'actuator {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a)!r} '
                        f'of joint {name!r}: expected a torque motor (motor, or general with '
                        f'fixed gain, no bias, no dynamics); a position or velocity servo is '
                        f'a controller of its own')
    return a


def start_pose(spec: mujoco.MjSpec, model: mujoco.MjModel, source: MjcfSource) -> dict:
    """Return joint name -> position of every hinge/slide joint: keyframe, then the pose."""
    qpos = model.qpos0.copy()
    if source.keyframe is not None:
        k = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, source.keyframe)
        if k < 0:
            names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_KEY, i)
                     for i in range(model.nkey)]
            raise MjcfError(f'{source.file}: no keyframe {source.keyframe!r} (has {names})')
        qpos = model.key_qpos[k].copy()
    elif model.nkey:
        qpos = model.key_qpos[0].copy()
    pose = {}
    for j in range(model.njnt):
        if int(model.jnt_type[j]) in _MOVABLE:
            pose[mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)] = \
                float(qpos[model.jnt_qposadr[j]])
    for name, value in source.pose.items():
        if name not in pose:
            raise MjcfError(f'pose.{name}: not a hinge or slide joint of {source.file}')
        pose[name] = value
    return pose


def load_robot(source: MjcfSource, axes: list[str], *,
               spec: mujoco.MjSpec | None = None) -> MjcfRobot:
    """
    Read an MJCF and prepare it for identifying ``axes`` (the others held at the pose).

    Parameters
    ----------
    source : MjcfSource
        The file, keyframe and joint positions of the start pose.
    axes : list of str
        The actuated joints to identify, in axis order.
    spec : mujoco.MjSpec, optional
        The MJCF already read and edited (a candidate model of the diagnosis): used instead
        of reading ``source.file`` (changed in place); ``source`` still names the pose.

    Returns
    -------
    MjcfRobot
        The simulation model with only the axes (their link-side and second-mode hinges) free.

    Raises
    ------
    MjcfError
        The file is missing or invalid, an axis is not a hinge with one torque motor, a
        keyframe or pose joint is unknown, another joint is a ball or free joint.

    """
    spec = load_spec(source.file) if spec is None else spec
    full = _compile(spec, source.file)
    pose = start_pose(spec, full, source)
    names = set(pose)
    keep = set()
    for a in axes:
        if a not in names or spec.joint(a).type != mujoco.mjtJoint.mjJNT_HINGE:
            raise MjcfError(f'axis {a!r}: not a hinge joint of {source.file} (its hinges: '
                            f'{sorted(n for n in names if not n.endswith(("_link", "_mode")))})')
        find_actuator(spec, a)
        keep.add(a)
        lj = link_joint(spec, a)
        if lj is not None:
            keep.add(lj.name)
        mj = mode_joint(spec, a)
        if mj is not None:
            keep.add(mj.name)
    for j in list(spec.joints):
        if j.name in keep:
            continue
        if j.type in (mujoco.mjtJoint.mjJNT_FREE, mujoco.mjtJoint.mjJNT_BALL):
            raise MjcfError(f'{source.file}: joint {j.name or "(unnamed)"} is a '
                            f'{j.type.name}: only hinge and slide joints can be held')
        lock_joint(spec, j.name, pose[j.name])
    for key in list(spec.keys):
        spec.delete(key)
    for act in list(spec.actuators):
        if not (act.trntype == mujoco.mjtTrn.mjTRN_JOINT and act.target in axes):
            spec.delete(act)
    # the welded bodies fused into their parents: the same rigid body (M and gravity to
    # rounding, test_mjcf_plant.py), fewer bodies per step (the iiwa on 3 axes: 9 -> 4)
    spec.compiler.fusestatic = True
    return MjcfRobot(spec, source.file, axes, pose)


def _compile(spec: mujoco.MjSpec, file: str) -> mujoco.MjModel:
    try:
        return spec.compile()
    except (ValueError, RuntimeError) as err:
        raise MjcfError(f'{file}: does not compile ({str(err).strip().splitlines()[0]})') \
            from err
