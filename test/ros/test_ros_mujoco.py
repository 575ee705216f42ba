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
The plant node runs a MuJoCo robot in the launched graph (lockstep, rclpy).

The elastic iiwa 14 of test/plants/mujoco_iiwa.py as the plant node's ``plant: mujoco`` (the
model file names the MJCF; joints 1, 2, 4 identified, the rest welded at home), one short
multisine through plant node (hosting the PI), excitation node and estimator node; the FRF of
the recorded bag against MuJoCo's own linearisation (computed in the test's helper).
"""
from frf_ident.app.graph import Graph
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
import numpy as np
from plants.mujoco_iiwa import AXES, elastic_xml, HELD, home, KI, KP, truth_frf
import pytest
import yaml

pytest.importorskip('mujoco')


def test_plant_node_runs_mujoco_in_the_lockstep_graph(tmp_path, new_domain):
    (tmp_path / 'iiwa.xml').write_text(elastic_xml())
    pose = home()
    model = tmp_path / 'iiwa.yaml'
    model.write_text(yaml.safe_dump({
        'frf_ident_model': 1, 'sample_rate': 1000.0, 'mjcf': 'iiwa.xml',
        'pose': {a: pose[a] for a in AXES}, 'axes': [{'name': a} for a in AXES],
        'controller': {'kind': 'pi_velocity', 'kp': KP, 'ki': KI}}))
    ms = MultisineConfig(n_realisations=1, n_periods=3, resolution_hz=1.0, f_low=2.0,
                         compensate=False, position_bound_deg=1.0, return_s=2.0, settle_s=0.3)
    g = Graph(tmp_path / 'graph', robot=model, multisine=ms, domain_id=new_domain(),
              middleware='rclpy', params={'plant_node': {'plant': 'mujoco'},
                                          'excitation_node': {'stale_s': 2.0}})
    g.start()
    try:
        res = g.drive(multisine=True, iterations=0)
    finally:
        bag = g.stop()
    assert res['multisine']['success'], res
    log = (g.out / 'plant_node.log').read_text()
    assert "plant MujocoPlant ['joint1', 'joint2', 'joint4']" in log, log[-2000:]
    from frf_ident.bag import read_recording
    from frf_ident.core.estimation.described import estimate_recording
    rec, _ = read_recording(bag)
    assert list(rec.joint_names) == AXES
    frf = estimate_recording(rec)['multisine']
    truth = truth_frf(elastic_xml(HELD), frf.freq_hz, pose)
    for i, a in enumerate(AXES):
        db = np.abs(20 * np.log10(np.abs(frf.response[i, i] / truth[i, i])))
        print(f'{a}: graph FRF vs MuJoCo linearisation: median {np.median(db):.3f} dB over '
              f'{frf.freq_hz.size} lines')
        assert np.median(db) < 0.2
