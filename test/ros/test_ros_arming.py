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
Arming, the operator heartbeat and caller logs (issue 56) in real-robot mode on the plant.

The graph runs free on wall time (``lockstep: false``, as ``sim:=false``) with the simulated
plant and ``arming: token`` (what a robot gets by default). ``ros2 bag record`` records the
heartbeat, the announcements and the velocity reference with its own receive times: the
truth the timing is judged on. Then the recorded bag is played (``ros2 bag play``) into the
same session and into a new start of the node (on the DDS backend): neither starts a run.
"""
import json
import os
from pathlib import Path
import re
import signal
import subprocess
import sys
import threading
import time

from frf_ident.app.excitation_settings import abort_ramp_steps
from frf_ident.io.model_file import load_model
import numpy as np
import pytest

pytestmark = pytest.mark.xdist_group('ros_arming')

ROOT = Path(__file__).resolve().parents[2]
RECORDED = ['/frf/heartbeat', '/frf/arming', '/velocity_controller/commands', '/frf/progress',
            '/frf/experiment']
#: heartbeat_timeout_ms of the test: the longest accepted, for a loaded 2-core PC (the
#: console's own send gaps reached 0.61 s at load 14, test printed below; the default 250 ms
#: is for a robot PC; the same reason as stale_samples 500 here)
TIMEOUT_MS = 1000.0
RAMP_S = 0.01              # its default abort_ramp_s
#: slack of the watchdog tick and the ramp's sleeps on a loaded 2-core PC [ms] (146 ms
#: measured at load 15 on receive times)
SLACK_MS = 250.0
#: the same below the limit: the node may take the last heartbeat later than the console
#: sent it (978 ms from it to the zero reference measured at load 12 on receive times)
EARLY_SLACK_MS = 60.0


class Proc:
    """A subprocess whose output lines are collected by a thread."""

    def __init__(self, cmd, env, stdin=None):
        self.p = subprocess.Popen(cmd, env=env, stdin=stdin, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True, start_new_session=True,
                                  cwd=str(ROOT))
        self.lines = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.p.stdout:
            self.lines.append(line.rstrip())

    def text(self):
        return '\n'.join(self.lines)

    def wait_for(self, pattern, timeout=60.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if re.search(pattern, self.text()):
                return
            if self.p.poll() is not None:
                break
            time.sleep(0.05)
        pytest.fail(f'no {pattern!r} within {timeout} s:\n{self.text()[-3000:]}')

    def send(self, sig):
        try:
            os.killpg(self.p.pid, sig)
        except ProcessLookupError:
            pass                     # ended already

    def stop(self, sig=signal.SIGINT):
        if self.p.poll() is None:
            self.send(sig)
            try:
                self.p.wait(60)
            except subprocess.TimeoutExpired:
                os.killpg(self.p.pid, signal.SIGKILL)
                self.p.wait()


def _until(cond, timeout, what):
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            pytest.fail(f'timed out waiting for {what}')
        time.sleep(0.05)


def _log(g):
    return (g.out / 'excitation_node.log').read_text(errors='replace')


def _token(g):
    _until(lambda: 'ARMING TOKEN' in _log(g), 30, 'the token on the console')
    return re.search(r'ARMING TOKEN of this start: (\S+)', _log(g)).group(1)


def _call(env, service='/frf/run_multisine'):
    out = subprocess.run(['ros2', 'service', 'call', service, 'std_srvs/srv/Trigger'],
                         env=env, text=True, capture_output=True, timeout=120).stdout
    m = re.search(r"message='(.*)'\)", out)
    assert m, out
    return json.loads(m.group(1).replace("\\'", "'"))


def _operator(g, token):
    """
    Start the operator console, above the test's load where the OS lets it (``nice -n -10``).

    In a full suite (2 cores, the other worker's tests beside the free-running graph) the
    console sent no heartbeat for 1.14 s right after the armed run call, on the recorder's own
    receive times: the node's abort after 1013 ms was right, the console was not run. On a
    robot PC the enabling device keeps its share of the CPU; here the test gives it that (or,
    where the OS refuses to raise it, runs it as before; nice then says so on its output).
    """
    return Proc(['nice', '-n', '-10', sys.executable, '-m', 'frf_ident.nodes.operator_node',
                 '--token', token,
                 '--name', 'test-operator@robot-pc', '--ros-args', '--params-file',
                 str(g.params_file)], g.env, stdin=subprocess.PIPE)


def _graph(out, middleware, domain=None, n_periods=8):
    from frf_ident.app.graph import Graph
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    ms = MultisineConfig(n_realisations=1, n_periods=n_periods, resolution_hz=2.0,
                         compensate=False, return_s=2.0, settle_s=0.3)
    return Graph(out, multisine=ms, lockstep=False, middleware=middleware, domain_id=domain,
                 # a loaded 2-core PC: the free-running simulation lags (as in
                 # test/nodes/test_free_running.py); the live bound of a robot is not tested here
                 params={'excitation_node': {'arming': 'token', 'stale_samples': 500,
                                             'heartbeat_timeout_ms': TIMEOUT_MS,
                                             'live_position_bound_deg': 30.0},
                         'controller_node': {'reference_timeout_s': 0.5}})


class _Segments:
    """The test's own rclpy subscriber of /frf/experiment: when does an excitation run."""

    def __init__(self, domain):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String
        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx, domain_id=domain)
        self.node = rclpy.create_node('frf_arming_observer', context=self.ctx)
        latched = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.events = []
        self.node.create_subscription(String, '/frf/experiment',
                                      lambda m: self.events.append(json.loads(m.data)), latched)
        self.ex = SingleThreadedExecutor(context=self.ctx)
        self.ex.add_node(self.node)
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self):
        while not self.stop.is_set():
            self.ex.spin_once(timeout_sec=0.05)

    def long_segment_started(self):
        return any(e.get('event') == 'start' and e['t_end'] - e['t_start'] > 2.0
                   for e in self.events)

    def close(self):
        import rclpy
        self.stop.set()
        self.thread.join(2.0)
        self.ex.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.ctx)


def _play(recorded, env):
    """Run ``ros2 bag play`` of the recorded heartbeats and announcements, from the first."""
    rec = _read_recorded(recorded)
    t0 = min(t for msgs in rec.values() for t, _ in msgs)
    offset = max(0.0, (rec['/frf/heartbeat'][0][0] - t0) * 1e-9 - 0.2)
    return Proc(['ros2', 'bag', 'play', str(recorded), '--start-offset', f'{offset:.3f}',
                 '--topics', '/frf/heartbeat', '/frf/arming'], env)


def _until_refused(g, seen, why):
    """
    Wait until the node's log, after its first ``seen`` characters, refuses a played heartbeat.

    The request must come while the played heartbeats reach the node: a fixed 2 s after
    ``ros2 bag play`` started came, on a loaded PC, before the player published any (the
    refusal then named the stopped or missing heartbeat instead of the replay).
    """
    _until(lambda: 'heartbeat refused' in _log(g)[seen:] and why in _log(g)[seen:], 60,
           f'a played heartbeat refused ({why})')


def _published(path, topics):
    """
    Read ``topics`` of the recorder's bag: {topic: [(publish ns, message)]}.

    rosbag2 writes each message's source timestamp (the sender's clock at publish) as the
    MCAP publish_time beside its own receive time; read with the mcap reader.
    """
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    out = {}
    for f in sorted(Path(path).glob('*.mcap')):
        with open(f, 'rb') as fh:
            reader = make_reader(fh, decoder_factories=[DecoderFactory()])
            for _, ch, m, msg in reader.iter_decoded_messages(topics=topics):
                out.setdefault(ch.topic, []).append((m.publish_time, msg))
    return out


def _read_recorded(path):
    """Read the recorder's bag: {topic: [(receive ns, message)]}, with rosbags' reader."""
    from rosbags.highlevel import AnyReader
    out = {}
    with AnyReader([Path(path)]) as reader:
        for conn, t_ns, raw in reader.messages():
            out.setdefault(conn.topic, []).append((t_ns, reader.deserialize(raw, conn.msgtype)))
    return out


def _armed_run(g, env, segments, tries: int = 3):
    """
    Call the armed run until its excitation segment starts; return (reply, retries).

    Twice in full runs (make test on 2 cores) no segment came within 120 s of the accepted
    call and the cause was not captured. A run the node aborts before its segment (the console
    or the plant starved by the other worker's tests: a heartbeat or joint-state gap beyond its
    limit, which the node is right to stop on) is called again, at most ``tries`` times, each
    retry printed with the node's reason; the node must then accept it again (still armed).
    Anything else fails with the reply and the node's log.
    """
    for attempt in range(tries):
        seen = len(_log(g))
        reply = _call(env)
        assert reply['accepted'] is True, reply
        deadline = time.monotonic() + 120.0
        while time.monotonic() < deadline:
            if segments.long_segment_started():
                return reply, attempt
            aborted = re.search(r"experiment 'multisine' aborted: (.*)", _log(g)[seen:])
            if aborted:
                print(f'armed run {attempt + 1} aborted before its segment (a loaded PC): '
                      f'{aborted.group(1)}; called again')
                _until(lambda: 'operator heartbeat of run' in _log(g)[seen:], 10,
                       'the end of the aborted run')
                break
            time.sleep(0.05)
        else:
            pytest.fail(f'no excitation segment within 120 s of the armed run call '
                        f'({reply!r}); excitation node log:\n{_log(g)[-3000:]}')
    pytest.fail(f'{tries} armed runs aborted before their segment; excitation node log:\n'
                f'{_log(g)[-3000:]}')


@pytest.fixture(scope='module')
def session(tmp_path_factory, new_domain):
    """
    Run one armed session on rclpy: refused unarmed, accepted armed, heartbeat stopped.

    Then its recorded bag played back into the same session (the node still running).
    """
    out = tmp_path_factory.mktemp('arming')
    g = _graph(out / 'graph', 'rclpy', new_domain())
    g.start()
    env = dict(g.env)
    res = {'graph': g}
    recorder = op = player = None
    segments = _Segments(g.domain_id)
    try:
        token = _token(g)
        recorder = Proc(['ros2', 'bag', 'record', '-s', 'mcap', '-o', str(out / 'recorded'),
                         *RECORDED], env)
        recorder.wait_for("Subscribed to topic '/frf/arming'")
        res['unarmed'] = _call(env)
        op = _operator(g, token)
        op.wait_for('ARMED')
        recorder.wait_for("Subscribed to topic '/frf/heartbeat'")
        res['armed'], res['retries'] = _armed_run(g, env, segments)
        time.sleep(1.0)                          # the multisine moves the (simulated) robot
        mark = len(_log(g))
        op.send(signal.SIGSTOP)                  # a hung console: no more heartbeats
        t_stop = time.monotonic()
        _until(lambda: 'operator heartbeat lost' in _log(g)[mark:], 30, 'the heartbeat abort')
        res['abort_seen_s'] = time.monotonic() - t_stop
        _until(lambda: 'operator heartbeat of run' in _log(g)[mark:], 10,
               'the heartbeat summary')
        # the recorder takes what it subscribes to in batches, under make test's load up to
        # 0.4 s late (see test_armed_accepts...): 0.5 s once left the run's 'finished'
        # progress event out of the bag
        time.sleep(2.0)
        recorder.stop()
        res['recorded'] = out / 'recorded'
        # the recorded session played back while the same node runs: never a run
        op.send(signal.SIGKILL)
        seen = len(_log(g))
        player = _play(out / 'recorded', env)
        _until_refused(g, seen, 'replayed or duplicated')
        res['replayed_same_session'] = _call(env)
        player.stop()
        res['log'] = _log(g)
        res['operator'] = op.text()
    finally:
        for p in (player, op, recorder):
            if p is not None:
                if p is op:
                    p.send(signal.SIGKILL)
                p.stop()
        segments.close()
        g.stop()
    return res


def test_unarmed_refuses_and_names_caller(session):
    """An unarmed node refuses a run from another process: reply and log name both."""
    r = session['unarmed']
    assert r['accepted'] is False and r['refused'] is True, r
    assert 'not armed: no operator heartbeat yet' in r['error'], r
    assert '_ros2cli_requester' in r['caller'], r
    line = next(ln for ln in session['log'].splitlines()
                if '/frf/run_multisine refused at' in ln)
    print(line)
    assert 'not armed' in line and 'caller: node /_ros2cli_requester' in line, line
    assert 'ARMING TOKEN' not in line


def test_armed_accepts_and_heartbeat_loss_ramps_to_zero(session):
    """
    Armed, the run starts; the heartbeat stopped mid-run ramps the reference to zero.

    Judged on the senders' publish times (one clock: every node runs on this PC): from the
    last heartbeat the console sent to the zero reference the node sent at most
    heartbeat_timeout_ms + abort_ramp_s (+ slack); no step in the reference. (The recorder's
    receive times were judged before: under make test's load it took the last four
    heartbeats in one batch, the last 396 ms late, and the zero reference seemed to come
    646 ms after it; by publish times 1021 ms, the node's own log said 1006 ms.)
    """
    r = session['armed']
    assert r['accepted'] is True, r
    log = session['log']
    assert re.search(r'/frf/run_multisine accepted at \S+: run \d+ multisine; caller: node '
                     r'/_ros2cli_requester', log), log[-3000:]
    assert 'aborted: operator heartbeat lost' in log, log[-3000:]
    print(re.findall(r'operator heartbeat of run.*', log)[-1])
    print(re.search(r'aborted: operator heartbeat lost: none for \d+ ms', log).group(0))
    rec = _read_recorded(session['recorded'])
    sent = _published(session['recorded'], ['/frf/heartbeat', '/velocity_controller/commands'])
    finished = [json.loads(m.data) for _, m in rec['/frf/progress']]
    end = [e for e in finished if e.get('event') == 'finished'][-1]
    assert end['aborted'] and 'operator heartbeat lost' in end['error'], end
    t_hb = sent['/frf/heartbeat'][-1][0]
    cmds = sent['/velocity_controller/commands']
    t = np.array([tc for tc, _ in cmds])
    r_all = np.array([m.data for _, m in cmds])
    after = np.flatnonzero(t > t_hb)
    zero = after[np.all(r_all[after] == 0.0, axis=1)][0]
    dt_ms = (t[zero] - t_hb) * 1e-6
    print(f'last heartbeat to zero reference: {dt_ms:.0f} ms (limit {TIMEOUT_MS:.0f} + '
          f'{1e3 * RAMP_S:.0f} ms); the abort seen in the log {session["abort_seen_s"]:.2f} s '
          'after SIGSTOP')
    assert TIMEOUT_MS - EARLY_SLACK_MS <= dt_ms <= TIMEOUT_MS + 1e3 * RAMP_S + SLACK_MS
    assert np.all(r_all[zero:] == 0.0), 'the reference left zero after the abort'
    # the graph runs the default model (1 kHz): the ramp takes abort_ramp_s of its samples
    n = abort_ramp_steps(RAMP_S, load_model(None)[1].dt)
    ramp = np.abs(np.diff(r_all[zero - n:zero + 1], axis=0)).max()
    run_steps = np.abs(np.diff(r_all[:zero - n], axis=0)).max()
    r0 = np.abs(r_all[zero - n]).max()
    print(f'largest reference step in the ramp {ramp:.4f} rad/s (reference before it '
          f'{r0:.4f} rad/s), in the run before {run_steps:.4f} rad/s')
    assert ramp <= run_steps + 1e-12, 'the abort ramp steps more than the excitation does'


def test_replayed_bag_never_starts_a_run(session):
    """The recorded heartbeats played into the same session: seen numbers, refused."""
    r = session['replayed_same_session']
    assert r['accepted'] is False, r
    assert 'not armed' in r['error'] and 'replayed or duplicated' in r['error'], r
    runs = re.findall(r'/frf/run_multisine accepted', session['log'])
    # one per armed call the fixture made (it calls again after a run aborted by load)
    assert len(runs) == 1 + session['retries'], runs


def test_replay_into_a_new_start_on_dds(session, tmp_path):
    """
    A new start of the node (new session and token) on the DDS backend.

    The recorded bag played into it cannot arm it; the console with the new token can, and
    the caller line then carries what the DDS backend tells (host, enclave, process).
    """
    # a 20 s multisine: the q must come while it runs (with 4 s the wait for the abort after q
    # timed out once in a full run, output not captured; a q after the run's end aborts
    # nothing)
    g = _graph(tmp_path / 'graph', 'dds', n_periods=40)
    g.start()
    env = dict(g.env)
    player = op = None
    try:
        token = _token(g)
        seen = len(_log(g))
        player = _play(session['recorded'], env)
        _until_refused(g, seen, 'another session')
        replayed = _call(env)
        player.stop()
        op = _operator(g, token)
        op.wait_for('ARMED')
        armed = _call(env)
        _until(lambda: 'multisine started' in op.text(), 60, 'the run on the console')
        op.p.stdin.write('q\n')
        op.p.stdin.flush()
        try:
            _until(lambda: 'operator heartbeat lost' in _log(g), 30, 'the abort after q')
        except pytest.fail.Exception:
            pytest.fail(f'no abort within 30 s of q; console:\n{op.text()[-1500:]}\n'
                        f'excitation node log:\n{_log(g)[-3000:]}')
        log = _log(g)
    finally:
        for p in (player, op):
            if p is not None:
                p.stop()
        g.stop()
    assert replayed['accepted'] is False, replayed
    assert 'another session' in replayed['error'], replayed
    assert armed['accepted'] is True, armed
    line = next(ln for ln in log.splitlines() if '/frf/run_multisine accepted at' in ln)
    print(line)
    assert re.search(r'caller: node /_ros2cli_requester\S* on \S+, enclave /, process ', line)
