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
The node graph as separate processes over DDS on loopback (each test on its own domain).

- chirp iteration via the service + multisine experiment: FRF = offline run_identification
  + estimate_recording within 0.1 dB;
- the bag opens with rosbags AnyReader and mcap_ros2 and yields the FRF offline;
- SIGKILL of the plant mid-run: reference at zero within 50 ms wall, bag readable;
- SIGINT/SIGTERM of the estimator: bag finalised, no message lost.
"""
from __future__ import annotations

import json
from pathlib import Path
import select
import signal
import subprocess
import sys
import time

from frf_ident.app.graph import Graph
from frf_ident.core.excitation.chirp_iteration import ChirpConfig
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
import numpy as np
import pytest

# its module fixture runs the graph once for all tests here: they share a worker
pytestmark = pytest.mark.xdist_group('test_graph')
ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / 'config' / 'model_3axis.yaml'


def _ms() -> MultisineConfig:
    return MultisineConfig(n_realisations=2, n_periods=2, resolution_hz=1.0, return_s=2.0,
                           settle_s=0.3)


def _chirp() -> ChirpConfig:
    return ChirpConfig(duration=6.0, max_iterations=2)


@pytest.fixture(scope='module')
def graph_run(tmp_path_factory, new_domain):
    out = tmp_path_factory.mktemp('graph')
    # module scope starts before any test's own domain: this run takes one of its own
    g = Graph(out, model=MODEL, multisine=_ms(), chirp=_chirp(), domain_id=new_domain(),
              params={'excitation_node': {'stale_s': 0.5}})
    g.start()
    try:
        results = g.drive()
    finally:
        bag = g.stop()
    return g, bag, results


@pytest.fixture(scope='module')
def offline():
    from frf_ident.core.estimation.described import estimate_recording
    from frf_ident.core.simulation.runner import IdentificationConfig, run_identification
    from frf_ident.io.model_file import load_model, load_plant
    model, _robot, ctrl = load_model(MODEL)
    rec = run_identification(load_plant(None, model), ctrl,
                             IdentificationConfig(_ms(), _chirp()))
    return rec, estimate_recording(rec)


def test_graph_matches_offline(graph_run, offline):
    from frf_ident.bag import read_recording
    from frf_ident.core.estimation.described import estimate_recording
    g, bag, results = graph_run
    assert results['multisine']['success'], results
    its = results['iterations']
    assert len(its) >= 1 and all(i['success'] for i in its), its
    rec_off, est_off = offline
    off_its = rec_off.meta['summary']['chirp']['iterations']
    for node_it, off_it in zip(its, off_its):
        assert node_it['reply']['iteration'] == off_it['iteration']
        assert abs(node_it['reply']['error_db'] - off_it['max_abs_error_db']) < 0.1
    rec, _timing = read_recording(bag)
    est = estimate_recording(rec)
    for key in ('multisine', 'chirp'):
        a, b = est[key], est_off[key]
        np.testing.assert_allclose(a.freq_hz, b.freq_hz)
        # complex: a one-sample shift between effort and velocity keeps every magnitude
        # (21.6 deg at 60 Hz); 0.0116 relative is 0.1 dB, or 0.66 deg
        err = np.max(np.abs(a.response / b.response - 1))
        assert err < 0.0116, f'{key}: max relative difference {err:.4f}'
    live = json.loads((g.frf_dir / 'frf.json').read_text())
    assert live['estimate'] == 'multisine'


def test_bag_readers(graph_run):
    from mcap_ros2.reader import read_ros2_messages
    from rosbags.highlevel import AnyReader
    _g, bag, _ = graph_run
    with AnyReader([bag]) as reader:
        topics = {c.topic for c in reader.connections}
        assert {'/joint_states', '/velocity_controller/commands', '/effort_controller/commands',
                '/frf/excitation', '/frf/experiment'} <= topics
        conns = [c for c in reader.connections if c.topic == '/joint_states']
        n_js = sum(1 for _ in reader.messages(connections=conns))
    # split at each procedure's end (estimator_node): every file holds its part
    n = sum(1 for mcap in bag.glob('*.mcap')
            for m in read_ros2_messages(str(mcap), topics=['/joint_states']))
    assert n == n_js > 1000


KILL_AFTER = 1000      # references seen before the plant is killed


def _observer(env, tag_file: Path) -> subprocess.Popen:
    code = f"""
import sys, time, threading, json
from frf_ident import middleware as mw
node = mw.create_node('kill_observer')
log = []
def seen(m):
    # the writer's source timestamp (DDS, wall clock) beside this process' receive time
    log.append((time.time(), m.sample_info.source_timestamp * 1e-9, list(m.data)))
    if len(log) == {KILL_AFTER}:
        print('running', flush=True)
node.create_subscription(mw.msg('std_msgs/msg/Float64MultiArray'),
    '/velocity_controller/commands', seen, mw.qos_default(20000))
stop = threading.Event()
threading.Thread(target=lambda: (sys.stdin.read(), stop.set()), daemon=True).start()
print('ready', flush=True)
mw.spin(node, stop)
open({str(tag_file)!r}, 'w').write(json.dumps(log))
mw.shutdown()
"""
    return subprocess.Popen([sys.executable, '-c', code], env=env, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True, cwd=str(ROOT))


def test_kill_plant(tmp_path):
    # A stale-measurement abort before the kill (a 30 ms stall of a loaded 2-core machine) is
    # the watchdog doing its job, not the property under test: try again, at most 3 times.
    for attempt in range(3):
        if _kill_plant(tmp_path / f'attempt{attempt}'):
            return
    pytest.fail('the watchdog aborted before the kill in 3 attempts (machine too loaded)')


def _kill_plant(tmp_path):
    from frf_ident.bag import read_recording
    # On the DDS backend: the zero reference comes plant_silent_s + abort_ramp_s after the last
    # joint state the excitation node processed. Under rclpy on a loaded 2-core machine the
    # node still works through up to `lookahead` queued joint states after the kill (measured
    # 114-154 ms from kill to zero), so the 50 ms figure is the DDS backend's.
    tmp_path.mkdir()
    g = Graph(tmp_path, model=MODEL, multisine=MultisineConfig(
        n_realisations=1, n_periods=2, resolution_hz=1.0, compensate=False),
        params={'excitation_node': {'plant_silent_s': 0.03}},   # + 10 ms ramp: < 50 ms
        middleware='dds')
    g.start()
    obs_file = tmp_path / 'observed.json'
    # the observer on the DDS backend whatever the graph runs on: it must keep up with the
    # stream (its receive time is the measurement), and the fastest Python subscriber does
    obs = _observer(dict(g.env, FRF_IDENT_MIDDLEWARE='dds'), obs_file)
    assert obs.stdout.readline().strip() == 'ready'
    drv = g.driver(multisine=True, iterations=0)
    try:
        # kill once the run is well under way (by samples, not wall time: load varies);
        # never wait forever: a watchdog abort before that leaves the observer silent
        ready, _, _ = select.select([obs.stdout], [], [], 60.0)
        if not ready:
            early = 'stale' in (tmp_path / 'excitation_node.log').read_text()
            if early:
                return False
            pytest.fail('no 1000 references within 60 s; excitation log: '
                        + (tmp_path / 'excitation_node.log').read_text()[-400:])
        assert obs.stdout.readline().strip() == 'running'
        t_kill = time.time()
        g.kill('plant_node')
        drv.wait(30)
        time.sleep(0.5)
    finally:
        obs.stdin.close()
        obs.wait(10)
        bag = g.stop()
    log = json.loads(obs_file.read_text())
    # judged on the excitation node's publish times (the DDS source timestamps, one wall clock
    # on this PC): the observer's receive times add its own scheduling under load (a full make
    # test once saw 50.2 ms by receive time)
    after = [(t, d) for _, t, d in log if t >= t_kill]
    assert after, 'no reference published after the kill'
    assert np.allclose(after[-1][1], 0.0), after[-1]
    nonzero = [t for t, d in after if np.any(np.abs(d) > 0)]
    t_zero = after[-1][0] if not nonzero else min(t for t, d in after if t > max(nonzero))
    received = min(r for r, t, _ in log if t == t_zero)
    assert t_zero - t_kill < 0.05, (
        f'reference zero published {1e3 * (t_zero - t_kill):.1f} ms after kill '
        f'(received {1e3 * (received - t_kill):.1f} ms after)')
    exc_log = (tmp_path / 'excitation_node.log').read_text()
    assert 'aborted' in exc_log and 'stale' in exc_log
    rec, timing = read_recording(bag)
    assert rec.t.size > 300
    assert 'aborted' in (tmp_path / 'excitation_node.log').read_text()
    return True


def test_estimator_signal_finalises_bag(tmp_path):
    from frf_ident.bag import read_recording
    for sig in (signal.SIGINT, signal.SIGTERM):
        out = tmp_path / sig.name
        g = Graph(out, model=MODEL, nodes=('estimator_node',))
        g.start()
        n = 3000
        code = f"""
import time
from frf_ident import middleware as mw
node = mw.create_node('fake_plant')
JS = mw.msg('sensor_msgs/msg/JointState')
pub = node.create_publisher(JS, '/joint_states', mw.qos_default(20000))
while pub.get_subscription_count() == 0:
    time.sleep(0.01)
time.sleep(0.3)
m = JS(name=['joint_1', 'joint_2', 'joint_3'], position=[0.0] * 3, velocity=[0.0] * 3,
       effort=[0.0] * 3)
for k in range({n}):
    m.header.stamp.sec, m.header.stamp.nanosec = divmod(k * 1000000, 1000000000)
    m.velocity = [float(k)] * 3
    pub.publish(m)
print('sent', flush=True)
time.sleep(0.5)
mw.shutdown()
"""
        pub = subprocess.Popen([sys.executable, '-c', code], env=g.env, stdout=subprocess.PIPE,
                               text=True, cwd=str(ROOT))
        assert pub.stdout.readline().strip() == 'sent'
        g.kill('estimator_node', sig)          # right after the last message went out
        assert g.procs['estimator_node'].wait(30) == 0
        pub.wait(10)
        g.stop()
        assert (g.bag / 'metadata.yaml').is_file()
        rec, _ = read_recording(g.bag)
        assert rec.t.size == n
        np.testing.assert_array_equal(rec.velocity[:, 0], np.arange(n, dtype=float))


def test_demo_of_a_robot_its_plan_would_saturate_exits_2_with_one_line(
        tmp_path, capsys, new_domain, monkeypatch):
    """
    Joint 2's limit at 160 N m: excitation_node refuses the multisine (predicted torque).

    The refusal travels from the service answer through the driver (exit REFUSED) to the CLI:
    one line naming the joint, exit 2, no traceback; every node stopped.
    """
    import yaml

    from frf_ident.cli import main
    robot = yaml.safe_load(MODEL.read_text())
    robot['axes'][1]['torque_limit'] = 160.0
    path = tmp_path / 'tight.yaml'
    path.write_text(yaml.safe_dump(robot))
    monkeypatch.setenv('ROS_DOMAIN_ID', str(new_domain()))
    rc = main(['demo', '--out', str(tmp_path / 'demo'), '--robot', str(path), '--model',
               str(MODEL), '--realisations', '1', '--periods', '1', '--resolution', '1',
               '--max-iterations', '1'])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert 'excitation_node refused the multisine' in err[0] and 'joint_2' in err[0], err
    logs = tmp_path / 'demo' / 'graph'
    assert 'not started' in (logs / 'excitation_node.log').read_text()
