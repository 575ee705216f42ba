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
The node graph on real rclpy: end to end, against the DDS backend, and mixed graphs.

One short lockstep multisine (16 s of samples) per graph. Lockstep is deterministic, so the
rclpy graph, the DDS-backend graph and the two mixed graphs (rclpy plant with DDS excitation +
estimator, and the reverse) must record the same bag: the FRFs agree to 1e-6 dB.
"""
import json

from frf_ident.app.graph import Graph
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
import numpy as np
import pytest

# module fixtures shared by the tests here, and conftest's lockstep_run (the rclpy graph,
# shared with test_ros_bag_record and test_ros_bag_play): one worker (make test, xdist)
pytestmark = pytest.mark.xdist_group('ros_lockstep_run')

SIM = ('plant_node', 'controller_node')
REST = ('excitation_node', 'estimator_node')


def _ms() -> MultisineConfig:
    return MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=2.0, compensate=False,
                           return_s=2.0, settle_s=0.3)


def _run(out, middleware, domain):
    g = Graph(out, multisine=_ms(), domain_id=domain, middleware=middleware,
              params={'excitation_node': {'stale_s': 2.0}})
    g.start()
    try:
        res = g.drive(multisine=True, iterations=0)
    finally:
        bag = g.stop()
    assert res['multisine']['success'], res
    return g, bag, res


def _frf(bag):
    from frf_ident.bag import read_recording
    from frf_ident.core.estimation.described import estimate_recording
    rec, _ = read_recording(bag)
    return rec, estimate_recording(rec)['multisine']


@pytest.fixture(scope='module')
def dds_run(tmp_path_factory, new_domain):
    return _run(tmp_path_factory.mktemp('dds'), 'dds', new_domain())


@pytest.fixture
def rclpy_run(lockstep_run):
    """Return the all-rclpy graph: conftest's shared lockstep run (same multisine, params)."""
    assert lockstep_run.result['multisine']['success'], lockstep_run.result
    return lockstep_run.graph, lockstep_run.bag, lockstep_run.result


def _same(bag_a, bag_b):
    rec_a, a = _frf(bag_a)
    rec_b, b = _frf(bag_b)
    np.testing.assert_array_equal(rec_a.t, rec_b.t)
    np.testing.assert_allclose(rec_a.velocity, rec_b.velocity, atol=1e-12)
    db = np.max(np.abs(20 * np.log10(np.abs(a.response) / np.abs(b.response))))
    assert db < 1e-6, f'FRFs differ by {db:.2e} dB'


def test_rclpy_graph_bag_and_frf(rclpy_run, dds_run):
    g, bag, res = rclpy_run
    meta = (bag / 'metadata.yaml').read_text()
    assert 'ros_distro: jazzy' in meta
    live = json.loads((g.frf_dir / 'frf.json').read_text())
    assert live['estimate'] == 'multisine'
    for name in g.nodes:    # every node ran on rclpy
        assert g.procs[name].returncode == 0, name
    _same(bag, dds_run[1])


@pytest.mark.parametrize('split', ['rclpy_sim', 'dds_sim'])
def test_mixed_graph(split, dds_run, tmp_path, new_domain):
    a, b = ('rclpy', 'dds') if split == 'rclpy_sim' else ('dds', 'rclpy')
    mw = {n: a for n in SIM}
    mw.update({n: b for n in REST})
    _g, bag, _ = _run(tmp_path, mw, new_domain())
    _same(bag, dds_run[1])
