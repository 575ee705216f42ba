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
frf_ident: closed-loop FRF identification of flexible-joint robots.

Implements Saupe & Knoblach (2015), "Experimental determination of frequency response
function estimates for flexible joint industrial manipulators with serial kinematics".

Layers, bottom to top (each imports only the ones below it; contracts in .importlinter):

- ``frf_ident.errors``: the exception hierarchy.
- ``frf_ident.core``: pure numpy/scipy (model, simulation, excitation, estimation,
  diagnosis). Never imports ROS, DDS, bag, YAML or plotting libraries.
- ``frf_ident.io``: model files, CSV/MAT import, FRF export, the package's data files.
- adapters: ``frf_ident.bag`` (rosbag2 MCAP I/O), ``frf_ident.middleware`` (rclpy / Cyclone
  DDS), ``frf_ident.report`` (figures and HTML).
- ``frf_ident.app``: one application function per job, shared by CLI and nodes.
- ``frf_ident.cli`` and ``frf_ident.nodes`` on top.
"""

__all__ = ['__version__']

__version__ = '0.1.0'
