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
ROS 2 node suite of frf_ident (plant, controller, excitation + iteration service, estimator).

Thin nodes: they wire topics and parameters to the core objects (plant, PI, procedure phases,
ChirpIteration, BagRecorder, estimate_recording). See README_nodes.md.
"""
