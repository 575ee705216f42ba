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
The nodes' velocity loop runs a model file's filters as the simulation kernel does.

The controller node's VelocityLoop (and the plant node's, which hosts the same) commands the
torques of the kernel on the same measurements.

A model file with controller.filters (notch and low-pass sections) is simulated in closed
loop; nodes/controller_node.py's VelocityLoop, loaded from the same file, is fed the recorded
references and velocities one by one, as the node's callbacks do, and must command the
recorded torques.
"""
import copy

from frf_ident.core.loop.notch import design_lowpass, design_notch
from frf_ident.core.model.schema import robot_from_dict
from frf_ident.core.simulation.controller import controller_from_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.io.model_file import load_model
from frf_ident.nodes.controller_node import VelocityLoop
import numpy as np
from plants.campaign import MODEL
import yaml


class _Node:
    def get_logger(self):
        return self

    def error(self, text):
        raise AssertionError(text)


def test_velocity_loop_of_the_nodes_runs_the_filters(tmp_path):
    d = copy.deepcopy(load_model(MODEL)[0])
    for a in d['axes']:
        a['velocity_noise'] = 0.0
    n = design_notch(46.7, 47.0, 0.014, 0.5, 1000.0)
    d['controller']['filters'] = {'joint_2': [n.sos.tolist(),
                                              design_lowpass(20.0, 1000.0).sos.tolist()]}
    path = tmp_path / 'tuned.yaml'
    path.write_text(yaml.safe_dump(d))
    rob = robot_from_dict(d)
    r = np.cumsum(np.random.default_rng(1).standard_normal((2000, 3)), axis=0) * 1e-3
    res = FlexibleJointPlant(rob).simulate(reference=r, controller=controller_from_dict(d, rob))
    loop = VelocityLoop(_Node(), str(path))
    assert loop.ctrl.n_sections == 2
    u = np.array([loop.torque(loop.reference(r[k].tolist()), res.velocity[k])
                  for k in range(r.shape[0])])
    np.testing.assert_allclose(u, res.effort, rtol=1e-12, atol=1e-9)
