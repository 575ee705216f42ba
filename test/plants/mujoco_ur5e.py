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
A Universal Robots UR5e as a dynamics-only MJCF: a second public robot for the MuJoCo tests.

Source: MuJoCo Menagerie (github.com/google-deepmind/mujoco_menagerie),
``universal_robots_ur5e/ur5e.xml``: the bodies' frames (``pos``, ``quat``), masses, centres of
mass, inertias, joint axes and ranges below are that file's. Changed as the shared iiwa 14
(its SOURCE.md): meshes, geoms, materials, light and keyframe removed; the menagerie's
``armature`` 0.1 and ``damping`` 200/15 (its own guesses of the drive) removed, so that the
file is a rigid-body model without drive terms; the position servos replaced by joint torque
motors with the published maximum joint torques (150 N m for the size-3 joints, 28 N m for the
wrist) as ``ctrlrange``; each joint's axis written out instead of taken from a default class;
MuJoCo's ``implicitfast`` integrator at a 1 ms time step.

The menagerie's UR5e files carry this licence (BSD 3-Clause), reproduced as it asks:

    Copyright 2018 ROS Industrial Consortium

    Redistribution and use in source and binary forms, with or without modification,
    are permitted provided that the following conditions are met:

    1. Redistributions of source code must retain the above copyright notice, this
    list of conditions and the following disclaimer.

    2. Redistributions in binary form must reproduce the above copyright notice,
    this list of conditions and the following disclaimer in the documentation and/or
    other materials provided with the distribution.

    3. Neither the name of the copyright holder nor the names of its contributors
    may be used to endorse or promote products derived from this software without
    specific prior written permission.

    THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS AND CONTRIBUTORS "AS IS" AND
    ANY EXPRESS OR IMPLIED WARRANTIES, INCLUDING, BUT NOT LIMITED TO, THE IMPLIED
    WARRANTIES OF MERCHANTABILITY AND FITNESS FOR A PARTICULAR PURPOSE ARE
    DISCLAIMED. IN NO EVENT SHALL THE COPYRIGHT HOLDER OR CONTRIBUTORS BE LIABLE FOR
    ANY DIRECT, INDIRECT, INCIDENTAL, SPECIAL, EXEMPLARY, OR CONSEQUENTIAL DAMAGES
    (INCLUDING, BUT NOT LIMITED TO, PROCUREMENT OF SUBSTITUTE GOODS OR SERVICES;
    LOSS OF USE, DATA, OR PROFITS; OR BUSINESS INTERRUPTION) HOWEVER CAUSED AND ON
    ANY THEORY OF LIABILITY, WHETHER IN CONTRACT, STRICT LIABILITY, OR TORT
    (INCLUDING NEGLIGENCE OR OTHERWISE) ARISING IN ANY WAY OUT OF THE USE OF THIS
    SOFTWARE, EVEN IF ADVISED OF THE POSSIBILITY OF SUCH DAMAGE.
"""
from __future__ import annotations

from pathlib import Path

__all__ = ['UR5E_XML', 'write_ur5e']

UR5E_XML = """<mujoco model="ur5e_dynamics">
  <compiler angle="radian" autolimits="true"/>
  <option integrator="implicitfast" timestep="0.001"/>
  <worldbody>
    <body name="base" quat="1 0 0 1">
      <inertial mass="4.0" pos="0 0 0" diaginertia="0.00443333156 0.00443333156 0.0072"/>
      <body name="shoulder_link" pos="0 0 0.163">
        <inertial mass="3.7" pos="0 0 0" diaginertia="0.0102675 0.0102675 0.00666"/>
        <joint name="shoulder_pan_joint" axis="0 0 1" range="-6.28319 6.28319"/>
        <body name="upper_arm_link" pos="0 0.138 0" quat="1 0 1 0">
          <inertial mass="8.393" pos="0 0 0.2125" diaginertia="0.133886 0.133886 0.0151074"/>
          <joint name="shoulder_lift_joint" axis="0 1 0" range="-6.28319 6.28319"/>
          <body name="forearm_link" pos="0 -0.131 0.425">
            <inertial mass="2.275" pos="0 0 0.196" diaginertia="0.0311796 0.0311796 0.004095"/>
            <joint name="elbow_joint" axis="0 1 0" range="-3.1415 3.1415"/>
            <body name="wrist_1_link" pos="0 0 0.392" quat="1 0 1 0">
              <inertial mass="1.219" pos="0 0.127 0" diaginertia="0.0025599 0.0025599 0.0021942"/>
              <joint name="wrist_1_joint" axis="0 1 0" range="-6.28319 6.28319"/>
              <body name="wrist_2_link" pos="0 0.127 0">
                <inertial mass="1.219" pos="0 0 0.1" diaginertia="0.0025599 0.0025599 0.0021942"/>
                <joint name="wrist_2_joint" axis="0 0 1" range="-6.28319 6.28319"/>
                <body name="wrist_3_link" pos="0 0 0.1">
                  <inertial mass="0.1889" pos="0 0.0771683 0" quat="1 0 0 1"
                      diaginertia="0.000132134 9.90863e-05 9.90863e-05"/>
                  <joint name="wrist_3_joint" axis="0 1 0" range="-6.28319 6.28319"/>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="shoulder_pan" joint="shoulder_pan_joint" ctrlrange="-150 150"/>
    <motor name="shoulder_lift" joint="shoulder_lift_joint" ctrlrange="-150 150"/>
    <motor name="elbow" joint="elbow_joint" ctrlrange="-150 150"/>
    <motor name="wrist_1" joint="wrist_1_joint" ctrlrange="-28 28"/>
    <motor name="wrist_2" joint="wrist_2_joint" ctrlrange="-28 28"/>
    <motor name="wrist_3" joint="wrist_3_joint" ctrlrange="-28 28"/>
  </actuator>
</mujoco>
"""


def write_ur5e(out: Path) -> Path:
    """Write the UR5e MJCF to ``out`` and return it."""
    out.write_text(UR5E_XML)
    return out
