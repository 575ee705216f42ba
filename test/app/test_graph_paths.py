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
The node graph hands its nodes absolute paths: they run in the source tree, not the caller's cwd.

``frf-ident demo --robot robot.yaml --plant mujoco`` run in the robot's folder failed with
"plant_node: bad parameter: robot.yaml: model file not found" (issue 50 phase B, found by
running the demo on a MuJoCo robot).
"""
from frf_ident.app.graph import Graph
import yaml


def test_relative_model_and_output_paths_reach_the_nodes_absolute(tmp_path, monkeypatch):
    (tmp_path / 'robot.yaml').write_text('frf_ident_model: 1\n')
    monkeypatch.chdir(tmp_path)
    g = Graph('out', robot='robot.yaml', domain_id=0)
    params = yaml.safe_load(g.params_file.read_text())
    assert params['/**']['ros__parameters']['model'] == str(tmp_path / 'robot.yaml')
    bag = params['estimator_node']['ros__parameters']['bag']
    assert bag == str(tmp_path / 'out' / 'bag')
