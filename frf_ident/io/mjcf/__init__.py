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
MuJoCo adapter (the optional extra ``pip install 'frf_ident[mujoco]'``).

MJCF robots as the plant, as the nominal model, and our drive parameters written as MJCF
(docs/mujoco.md).

- :mod:`~frf_ident.io.mjcf.drive_map`: the one mapping our parameters <-> MJCF attributes
  (no mujoco import)
- :mod:`~frf_ident.io.mjcf.spec_edit`: lock a joint, insert the series-elastic hinge pair, set
  drive terms (``mujoco.MjSpec``)
- :mod:`~frf_ident.io.mjcf.robot`: an MJCF prepared for identifying some of its joints
- :mod:`~frf_ident.io.mjcf.loop`, :mod:`~frf_ident.io.mjcf.plant`: the compiled closed loop
  and the §4 plant
- :mod:`~frf_ident.io.mjcf.linear`: MuJoCo's linearisation at the pose, its FRF and our
  parameters of it
- :mod:`~frf_ident.io.mjcf.export`: fitted parameters as MJCF and URDF
"""
