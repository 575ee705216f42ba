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
Our drive terms as URDF.

``<dynamics damping friction>``, ``<limit effort>``, and a ``<transmission>`` for what URDF has
no field for (docs/mujoco.md, "URDF").

URDF's joint holds viscous friction (``damping`` [N m s/rad]) and dry friction (``friction``
[N m]) only; the rotor inertia, the series spring and its damping have no URDF field, so each
joint's ``<transmission>`` (ros2_control's ``transmission_interface/SimpleTransmission``,
reduction 1: our torques are the joint's) carries them in a comment and as ``<frf_ident>``
attributes that URDF parsers ignore. :func:`write_drive_urdf` writes a standalone URDF, a star
of one link per axis about z (``link_inertia`` as its inertia), as the standalone MJCF of
:func:`frf_ident.io.mjcf.export.write_mjcf` does;
"""
from __future__ import annotations

from pathlib import Path
import xml.etree.ElementTree as ET

from frf_ident.core.model.params import AxisParams, RobotParams

__all__ = ['write_drive_urdf']


def _transmission(root: ET.Element, a: AxisParams) -> None:
    tr = ET.SubElement(root, 'transmission', name=f'{a.name}_transmission')
    ET.SubElement(tr, 'type').text = 'transmission_interface/SimpleTransmission'
    j = ET.SubElement(tr, 'joint', name=a.name)
    ET.SubElement(j, 'hardwareInterface').text = 'hardware_interface/EffortJointInterface'
    act = ET.SubElement(tr, 'actuator', name=f'{a.name}_motor')
    ET.SubElement(act, 'mechanicalReduction').text = '1'
    tr.append(ET.Comment(
        f' no URDF field: motor_inertia {a.motor_inertia:.6g} kg m^2, series stiffness '
        f'{a.stiffness:.6g} N m/rad and damping {a.damping:.6g} N m s/rad (frf_ident fit; the '
        f'MJCF export holds them as armature and the link-side hinge) '))
    ET.SubElement(tr, 'frf_ident', motor_inertia=repr(a.motor_inertia),
                  stiffness=repr(a.stiffness), damping=repr(a.damping),
                  time_delay=repr(a.time_delay))


def write_drive_urdf(robot: RobotParams, path: str | Path) -> Path:
    """
    Write a standalone URDF with each axis' drive terms (one revolute joint per axis).

    Parameters
    ----------
    robot : RobotParams
        The parameters.
    path : str or Path
        The file to write.

    Returns
    -------
    Path
        ``path``.

    """
    root = ET.Element('robot', name='frf_ident_fit')
    ET.SubElement(root, 'link', name='base')
    for i, a in enumerate(robot.axes):
        link = ET.SubElement(root, 'link', name=f'{a.name}_link')
        inertial = ET.SubElement(link, 'inertial')
        ET.SubElement(inertial, 'mass', value='1')
        jo = repr(float(a.link_inertia))
        ET.SubElement(inertial, 'inertia', ixx=jo, iyy=jo, izz=jo, ixy='0', ixz='0', iyz='0')
        joint = ET.SubElement(root, 'joint', name=a.name, type='continuous')
        ET.SubElement(joint, 'parent', link='base')
        ET.SubElement(joint, 'child', link=f'{a.name}_link')
        ET.SubElement(joint, 'origin', xyz=f'{float(i)!r} 0 0', rpy='0 0 0')
        ET.SubElement(joint, 'axis', xyz='0 0 1')
        ET.SubElement(joint, 'dynamics', damping=repr(float(a.viscous_friction)),
                      friction=repr(float(a.coulomb_friction)))
        ET.SubElement(joint, 'limit', effort=repr(float(a.torque_limit)), velocity='0')
        _transmission(root, a)
    ET.indent(root)
    p = Path(path)
    p.write_text('<?xml version="1.0"?>\n' + ET.tostring(root, encoding='unicode') + '\n')
    return p
