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
"""The graph driver's domain and middleware choice (what `frf-ident demo` runs on)."""
import importlib.util

from frf_ident.app import graph
import pytest


def test_domain_from_ros_domain_id(monkeypatch):
    monkeypatch.setenv('ROS_DOMAIN_ID', '42')
    assert graph.default_domain_id() == 42
    monkeypatch.delenv('ROS_DOMAIN_ID')
    lo, hi = graph.RANDOM_DOMAINS
    assert all(lo <= graph.default_domain_id() <= hi for _ in range(20))


def test_middleware_rclpy_when_sourced(monkeypatch, tmp_path):
    monkeypatch.delenv('FRF_IDENT_MIDDLEWARE', raising=False)
    want = 'rclpy' if importlib.util.find_spec('rclpy') else 'dds'
    assert graph.default_middleware() == want
    monkeypatch.setenv('FRF_IDENT_MIDDLEWARE', 'dds')
    assert graph.default_middleware() == 'dds'
    env = graph.graph_env(7, middleware='rclpy')
    assert env['FRF_IDENT_MIDDLEWARE'] == 'rclpy' and env['ROS_DOMAIN_ID'] == '7'
    assert env['ROS_AUTOMATIC_DISCOVERY_RANGE'] == 'LOCALHOST'


def test_graph_mixes_backends_per_node(tmp_path):
    g = graph.Graph(tmp_path, domain_id=9, middleware={'plant_node': 'rclpy'})
    assert g.node_middleware['plant_node'] == 'rclpy'
    assert g.node_middleware['estimator_node'] == g.middleware


def test_free_running_graph_is_wall_time(tmp_path):
    import yaml
    g = graph.Graph(tmp_path, domain_id=9, lockstep=False)
    common = yaml.safe_load(g.params_file.read_text())['/**']['ros__parameters']
    assert common['lockstep'] is False and common['use_sim_time'] is False


@pytest.mark.parametrize('lines, rc, error', [
    (['FRF_RESULT {"kind": "multisine", "success": false, "reply": {"error": "joint_2 198.4 of '
      '200 N m", "refused": true}}'], 3, 'excitation_node refused the multisine: joint_2'),
    ([], 3, 'graph driver failed'),          # no result line: a failure, not a refusal
    (['FRF_RESULT {"kind": "iteration", "success": false, "reply": {"error": "aborted: '
      'stale"}}'], 1, r'graph driver failed \(1\): iteration aborted: stale'),
    ([], 2, 'graph driver failed'),          # argparse's usage error
])
def test_drive_raises_input_error_only_for_a_refusal(tmp_path, monkeypatch, lines, rc, error):
    import subprocess
    import sys

    from frf_ident.errors import FrfIdentInputError
    code = ''.join(f'print({line!r});' for line in lines) + f'raise SystemExit({rc})'
    g = graph.Graph(tmp_path, domain_id=9)
    monkeypatch.setattr(g, 'driver', lambda **kw: subprocess.Popen(
        [sys.executable, '-c', code], stdout=subprocess.PIPE, text=True))
    expected = FrfIdentInputError if 'refused' in error else RuntimeError
    with pytest.raises(expected, match=error) as exc:
        g.drive()
    assert type(exc.value) is expected


def test_a_failed_drive_says_why(tmp_path):
    """The driver's failure names the run's error, else the last line of driver.log."""
    g = graph.Graph(tmp_path, domain_id=7)
    (tmp_path / 'driver.log').write_text('Traceback ...\nTimeoutError: /frf/abort not available\n')
    assert g.failure(None) == 'TimeoutError: /frf/abort not available'
    last = {'kind': 'multisine', 'reply': {'error': '/joint_states stale for 512 ms'}}
    assert g.failure(last) == 'multisine /joint_states stale for 512 ms'
    (tmp_path / 'driver.log').write_text('')
    assert g.failure({'kind': 'iteration', 'reply': {}}) == 'no result and an empty driver.log'
