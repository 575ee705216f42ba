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
Our robot parameters written as MJCF (ours -> MJCF, :data:`~frf_ident.io.mjcf.drive_map.MAPPING`).

With a base MJCF (the model file's ``mjcf``), :func:`write_mjcf` keeps its rigid body and writes
each axis' drive terms on the joint of the same name, inserting the series-elastic hinge pair
(:func:`~frf_ident.io.mjcf.spec_edit.split_elastic`); the link inertia stays the MJCF's and
:func:`write_mjcf` reports per axis how far ours differs from it at the pose. Without one it
writes a standalone MJCF: one two-mass chain per axis (a motor body with the rotor as
``armature``, a link body whose inertia about the hinge is ``link_inertia``), no gravity, no
link coupling (a star of independent axes cannot hold it: reported). An axis' ``second_mode``
becomes a child body of its link body on a hinge of its own
(:func:`~frf_ident.io.mjcf.link_mode.add_modes`), its inertia taken from the link body. Terms
MJCF cannot hold are reported with what was written instead, never dropped silently.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from frf_ident.core.model.params import RobotParams
from frf_ident.io.mjcf.drive_map import (drive_from_axis, JointDrive, Limitation, limitations,
                                         LINK_SUFFIX, MOTOR_BODY_INERTIA, MOTOR_BODY_MASS)
from frf_ident.io.mjcf.link_mode import add_modes
from frf_ident.io.mjcf.robot import load_spec
from frf_ident.io.mjcf.spec_edit import set_drive, split_elastic
import mujoco
import numpy as np

__all__ = ['MjcfExport', 'drive_spec', 'write_drives', 'write_mjcf']

#: spacing [m] of the axes of a standalone MJCF along x (they do not touch: no geoms anyway)
AXIS_SPACING = 1.0
#: nsample of an actuator's ctrl history: enough for delay / timestep + 1 samples
_HISTORY_MARGIN = 2


@dataclass
class MjcfExport:
    """What :func:`write_mjcf` wrote: the file, the terms it could not hold, notes per axis."""

    path: Path
    limitations: list[Limitation] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def lines(self) -> list[str]:
        """Return one line per limitation and note, for the console."""
        return [str(x) for x in self.limitations] + list(self.notes)


def _set_delay(act, delay: float, timestep: float) -> None:
    if delay > 0:
        act.nsample = int(np.ceil(delay / timestep)) + _HISTORY_MARGIN
        act.interp = 1          # linear between the history's samples
        act.delay = delay


def _standalone(robot: RobotParams) -> tuple[mujoco.MjSpec, list[str]]:
    """One two-mass chain per axis (text, then a spec: ``to_xml`` drops set inertials)."""
    import xml.etree.ElementTree as ET
    root = ET.Element('mujoco', model='frf_ident_fit')
    ET.SubElement(root, 'option', timestep=repr(robot.dt), gravity='0 0 0',
                  integrator='implicitfast')
    world = ET.SubElement(root, 'worldbody')
    acts = ET.SubElement(root, 'actuator')
    notes = [f'{a.name}: standalone MJCF: gravity ({a.gravity_torque:g} N m and '
             f'{len(a.gravity)} term(s)) not written: the rigid body of an MJCF base holds it'
             for a in robot.axes if a.gravity_torque or a.gravity]
    if robot.link_coupling is not None and np.any(robot.link_coupling):
        notes.append('link_coupling: not representable in a standalone MJCF (independent '
                     'axes); give the model an mjcf base to keep the coupling of its rigid '
                     'body')
    tiny = ' '.join([repr(MOTOR_BODY_INERTIA)] * 3)
    for i, a in enumerate(robot.axes):
        motor = ET.SubElement(world, 'body', name=f'{a.name}_motor',
                              pos=f'{AXIS_SPACING * i!r} 0 0')
        ET.SubElement(motor, 'inertial', pos='0 0 0', mass=repr(MOTOR_BODY_MASS),
                      diaginertia=tiny)
        ET.SubElement(motor, 'joint', name=a.name, type='hinge', axis='0 0 1')
        link = ET.SubElement(motor, 'body', name=a.name + LINK_SUFFIX + '_body')
        jo = repr(float(a.link_inertia))
        ET.SubElement(link, 'inertial', pos='0 0 0', mass='1', diaginertia=f'{jo} {jo} {jo}')
        ET.SubElement(link, 'joint', name=a.name + LINK_SUFFIX, type='hinge', axis='0 0 1',
                      limited='false')
        ET.SubElement(acts, 'motor', name=f'{a.name}_motor', joint=a.name)
    return mujoco.MjSpec.from_string(ET.tostring(root, encoding='unicode')), notes


def _inertia_notes(robot: RobotParams, path: Path) -> list[str]:
    """Per axis: our link inertia against the written MJCF's M(q) at the pose."""
    from frf_ident.core.model.params import MjcfSource
    from frf_ident.io.mjcf.linear import axis_values
    from frf_ident.io.mjcf.robot import load_robot
    src = robot.mjcf
    written = load_robot(MjcfSource(str(path), src.keyframe, src.pose), robot.joint_names)
    values, _ = axis_values(written, robot.sample_rate)
    out = []
    for a, v in zip(robot.axes, values):
        rel = a.link_inertia / v['link_inertia'] - 1.0
        out.append(f'{a.name}: link inertia {a.link_inertia:.4g} kg m^2 here, the MJCF has '
                   f'{v["link_inertia"]:.4g} at the pose ({100 * rel:+.1f} %): its rigid body '
                   f'is kept')
    return out


def write_mjcf(robot: RobotParams, path: str | Path, *, base: str | Path | None = None,
               elastic: list[bool] | None = None) -> MjcfExport:
    """
    Write ``robot``'s drive terms as an MJCF that ``mujoco.MjModel.from_xml_path`` loads.

    Parameters
    ----------
    robot : RobotParams
        The parameters (a fit's, or a model's).
    path : str or Path
        The file to write.
    base : str or Path, optional
        The MJCF whose rigid body to keep; default ``robot.mjcf`` (None: standalone).
    elastic : list of bool, optional
        Per axis whether to write the series-elastic pair (default: every axis).

    Returns
    -------
    MjcfExport
        The file, the terms not representable, and notes.

    """
    path = Path(path)
    base = base or (robot.mjcf.file if robot.mjcf is not None else None)
    flex = [True] * robot.n_axes if elastic is None else list(elastic)
    drives: list[JointDrive] = [drive_from_axis(a, elastic=e) for a, e in zip(robot.axes, flex)]
    lims = [x for a in robot.axes for x in limitations(a)]
    if base is None:
        spec, notes = _standalone(robot)
    else:
        spec, notes = load_spec(base), []
    spec, more = write_drives(spec, drives,
                              link_inertia={a.name: a.link_inertia for a in robot.axes})
    lims += more
    spec.compile()
    path.write_text(spec.to_xml())
    if base is not None and robot.mjcf is not None:
        notes += _inertia_notes(robot, path)
    return MjcfExport(path, lims, notes)


def drive_spec(spec: mujoco.MjSpec, drives: list[JointDrive], *,
               timestep: float | None = None) -> mujoco.MjSpec:
    """Return :func:`write_drives`' spec (what it could not write exactly left out)."""
    return write_drives(spec, drives, timestep=timestep)[0]


def write_drives(spec: mujoco.MjSpec, drives: list[JointDrive], *, timestep: float | None = None,
                 link_inertia: dict[str, float] | None = None
                 ) -> tuple[mujoco.MjSpec, list[Limitation]]:
    """
    Return ``spec`` with the drive terms written: the elastic joints split, each joint's terms.

    The second modes are added (:func:`~frf_ident.io.mjcf.link_mode.add_modes`) after the
    elastic pairs, so each sits behind its link-side hinge.

    Parameters
    ----------
    spec : mujoco.MjSpec
        The MJCF (a fresh read: :func:`~frf_ident.io.mjcf.spec_edit.split_elastic` may return
        a new spec, :func:`~frf_ident.io.mjcf.spec_edit.set_drive` edits in place).
    drives : list of JointDrive
        One per joint to write; ``stiffness`` not None inserts the series-elastic pair.
    timestep : float, optional
        MuJoCo's ``option timestep`` [s] to write (default: the MJCF's).
    link_inertia : dict of str to float, optional
        Joint -> link inertia at the pose [kg m^2], named in a second mode's Limitation.

    Returns
    -------
    spec : mujoco.MjSpec
        The edited spec (not compiled).
    limitations : list of Limitation
        The second modes written inexactly (:func:`~frf_ident.io.mjcf.link_mode.add_modes`).

    """
    spec = split_elastic(spec, [d.joint for d in drives if d.elastic])
    if timestep is not None:
        spec.option.timestep = float(timestep)
    lims = add_modes(spec, drives, link_inertia=link_inertia)
    for d in drives:
        set_drive(spec, d)
        _set_delay(spec.actuator(_actuator_name(spec, d.joint)), d.delay,
                   float(spec.option.timestep))
    return spec, lims


def _actuator_name(spec: mujoco.MjSpec, joint: str) -> str:
    from frf_ident.io.mjcf.spec_edit import find_actuator
    return find_actuator(spec, joint).name
