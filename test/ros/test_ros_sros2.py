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
SROS2 live (issue 56): only the operator's enclave can call /frf/run_multisine.

A keystore is made with openssl (frf_ident/io/sros2_keystore.py) from the shipped policy
config/sros2/frf_ident_policy.xml, for this test's own ROS_DOMAIN_ID. excitation_node runs in
the /frf_ident/excitation enclave with ROS_SECURITY_STRATEGY=Enforce on rmw_cyclonedds_cpp
(Cyclone DDS's security plugins), loopback only, in real-robot mode (``arming: token``, no
plant: every answer is a refusal for arming reasons, which is an answer). Participants
(test/ros/sros2_client.py, one process each) try to call the service:

- ``operator``: the operator enclave; also ``ros2 service call`` under it
  (ROS_SECURITY_ENCLAVE_OVERRIDE) and the operator console, which arms the node.
- ``intruder``: a valid identity of the same CA, permissions without the run services
  (signed by the permissions CA): it may read /frf/arming.
- ``forger``: the intruder's valid identity with permissions that grant the call, signed by
  a permissions CA of its own (a tampered local keystore).
- ``stranger``: a keystore of its own (identity and permissions CA), granting the call.
- ``plain``: no security at all.
- ``control``: the forger's very permissions signed by the real permissions CA: answered,
  so the forger's failure is the signature's, not a mistake in its permissions.

Then the same node without security on another domain: the plain and the intruder's calls
are answered there, so their failure above is security's, not the test's.
"""
from concurrent.futures import ThreadPoolExecutor
import json
import os
from pathlib import Path
import re
import shutil
import signal
import subprocess
import sys
import time

from frf_ident.io import sros2_keystore as ks
import pytest

ROOT = Path(__file__).resolve().parents[2]
POLICY = ROOT / 'config' / 'sros2' / 'frf_ident_policy.xml'
CLIENT = Path(__file__).with_name('sros2_client.py')
PLUGINS = ('libdds_security_auth.so', 'libdds_security_ac.so', 'libdds_security_crypto.so')
#: how long a participant waits for the service, then for the answer [s]; the authorised
#: ones found it within a second here at load 10 on 2 cores
WAIT_S = 20.0
SECURITY_VARS = ('ROS_SECURITY_KEYSTORE', 'ROS_SECURITY_ENABLE', 'ROS_SECURITY_STRATEGY',
                 'ROS_SECURITY_ENCLAVE_OVERRIDE')


def _missing_plugins():
    dirs = [d for d in os.environ.get('LD_LIBRARY_PATH', '').split(os.pathsep) if d]
    return [lib for lib in PLUGINS if not any((Path(d) / lib).is_file() for d in dirs)]


pytestmark = [
    pytest.mark.xdist_group('ros_sros2'),
    pytest.mark.skipif(not ks.have_openssl(), reason='no openssl command line (keystore)'),
    pytest.mark.skipif(bool(_missing_plugins()),
                       reason=f'no Cyclone DDS security plugins on LD_LIBRARY_PATH '
                              f'({", ".join(_missing_plugins())})'),
]

#: a profile's grants every rclpy node needs (the shipped policy's comment block)
NODE_BASICS = """
          <topics publish="ALLOW"><topic>rosout</topic><topic>parameter_events</topic></topics>
          <services reply="ALLOW">
            <service>~/describe_parameters</service><service>~/get_parameter_types</service>
            <service>~/get_parameters</service><service>~/list_parameters</service>
            <service>~/set_parameters</service><service>~/set_parameters_atomically</service>
            <service>~/get_type_description</service>
          </services>"""


def _policy(path, node, grant_call):
    """Write a one-enclave policy for /frf_ident/intruder: read /frf/arming (and call?)."""
    call = ('<services request="ALLOW"><service>frf/run_multisine</service></services>'
            if grant_call else '')
    path.write_text(f"""<?xml version="1.0" encoding="UTF-8"?>
<policy version="0.2.0"><enclaves><enclave path="/frf_ident/intruder"><profiles>
        <profile ns="/" node="{node}">{NODE_BASICS}
          <topics subscribe="ALLOW"><topic>frf/arming</topic></topics>{call}
        </profile>
</profiles></enclave></enclaves></policy>
""")
    return path


def _keystores(out, domain):
    """Make the real keystore, the control's copy, the forger's, the stranger's: {name: path}."""
    real = out / 'keystore'
    ks.make_keystore(real, POLICY, ['/frf_ident/excitation', '/frf_ident/operator'], domain)
    ks.create_enclave(real, '/frf_ident/intruder')
    ks.create_permission(real, '/frf_ident/intruder', _policy(out / 'intruder.xml', 'intruder',
                                                              False))
    granted = _policy(out / 'forger.xml', 'forger', True)
    control = out / 'keystore_control'          # same CA and identities (links are relative)
    shutil.copytree(real, control, symlinks=True)
    ks.create_permission(control, '/frf_ident/intruder', granted)
    forged = out / 'keystore_forged'            # a permissions CA and governance of its own
    ks.create_keystore(forged, domain)
    mine, theirs = (ks.enclave_dir(forged, '/frf_ident/intruder'),
                    ks.enclave_dir(real, '/frf_ident/intruder'))
    mine.mkdir(parents=True)
    for name in ('cert.pem', 'key.pem'):        # the intruder's valid identity
        shutil.copy2(theirs / name, mine / name)
    (mine / 'identity_ca.cert.pem').symlink_to(real / 'public' / 'identity_ca.cert.pem')
    (mine / 'permissions_ca.cert.pem').symlink_to(forged / 'public' / 'permissions_ca.cert.pem')
    (mine / 'governance.p7s').symlink_to(forged / 'enclaves' / 'governance.p7s')
    ks.create_permission(forged, '/frf_ident/intruder', granted)
    stranger = out / 'keystore_stranger'        # everything of its own
    ks.create_keystore(stranger, domain)
    ks.create_enclave(stranger, '/frf_ident/intruder')
    ks.create_permission(stranger, '/frf_ident/intruder',
                         _policy(out / 'stranger.xml', 'stranger', True))
    return {'real': real, 'control': control, 'forged': forged, 'stranger': stranger}


def _env(domain, keystore=None, override=None):
    """Loopback, the domain, rclpy; Enforce with ``keystore``, no security without."""
    from frf_ident.app.graph import graph_env
    env = graph_env(domain, middleware='rclpy')
    for var in SECURITY_VARS:
        env.pop(var, None)
    if keystore is not None:
        env.update(ROS_SECURITY_KEYSTORE=str(keystore), ROS_SECURITY_ENABLE='true',
                   ROS_SECURITY_STRATEGY='Enforce')
    if override:
        env['ROS_SECURITY_ENCLAVE_OVERRIDE'] = override
    return env


class _Proc:
    """A process group whose output goes to a file."""

    def __init__(self, cmd, env, log, stdin=None):
        self.log = log
        self.p = subprocess.Popen(cmd, env=env, stdin=stdin, stdout=open(log, 'w'),
                                  stderr=subprocess.STDOUT, text=True, cwd=str(ROOT),
                                  start_new_session=True)

    def text(self):
        return self.log.read_text(errors='replace')

    def wait_for(self, pattern, timeout=120.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            m = re.search(pattern, self.text())
            if m:
                return m
            if self.p.poll() is not None:
                break
            time.sleep(0.1)
        if 'does not have security support' in self.text():
            pytest.skip('rmw_cyclonedds_cpp built without DDS security')
        pytest.fail(f'no {pattern!r} within {timeout} s in {self.log}:\n{self.text()[-3000:]}')

    def stop(self, timeout=60.0):
        if self.p.poll() is None:
            try:
                os.killpg(self.p.pid, signal.SIGINT)
                self.p.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.p.pid, signal.SIGKILL)
                self.p.wait()
            except ProcessLookupError:
                pass
        return self.p.returncode


def _excitation(out, env, enclave):
    params = out / 'params.yaml'
    params.write_text('/**:\n  ros__parameters: {use_sim_time: false, lockstep: false}\n'
                      'excitation_node:\n  ros__parameters: {arming: token}\n')
    args = ['--enclave', enclave] if enclave else []
    p = _Proc([sys.executable, '-m', 'frf_ident.nodes.excitation_node', '--ros-args', *args,
               '--params-file', str(params)], env, out / 'excitation_node.log')
    p.wait_for(r'FRF_NODE_READY excitation_node')
    return p, params


def _client(out, env, node, enclave=None):
    """Run sros2_client.py as one participant; return what it printed, and the command."""
    args = ['--ros-args', '--enclave', enclave] if enclave else []
    cmd = [sys.executable, str(CLIENT), node, str(WAIT_S), *args]
    log = out / f'client_{node}_{time.monotonic_ns()}.log'
    t0 = time.monotonic()
    p = _Proc(cmd, env, log)
    try:
        p.p.wait(4 * WAIT_S + 120)
    finally:
        p.stop()
    m = re.search(r'^SROS2_CLIENT (.*)$', p.text(), re.M)
    assert m, f'{" ".join(cmd)}:\n{p.text()[-3000:]}'
    res = json.loads(m.group(1))
    res.update(wall_s=round(time.monotonic() - t0, 1), log=p.text(),
               security=env.get('ROS_SECURITY_KEYSTORE', 'off'))
    return res


def _parallel(*calls):
    with ThreadPoolExecutor(len(calls)) as pool:
        return [f.result() for f in [pool.submit(_client, *c) for c in calls]]


def _cli_call(env):
    """``ros2 service call /frf/run_multisine std_srvs/srv/Trigger``: its output."""
    r = subprocess.run(['ros2', 'service', 'call', '/frf/run_multisine',
                        'std_srvs/srv/Trigger'], env=env, text=True, capture_output=True,
                       timeout=4 * WAIT_S + 60, cwd=str(ROOT))
    return r.stdout + r.stderr


@pytest.fixture(scope='module')
def observed(tmp_path_factory, new_domain):
    """Run the secure graph and every participant, then the same node without security."""
    out = tmp_path_factory.mktemp('sros2')
    secure_out, open_out = out / 'secure', out / 'open'
    secure_out.mkdir()
    open_out.mkdir()
    domain = new_domain()
    keys = _keystores(out, domain)
    res = {'keystores': keys}
    exc, params = _excitation(secure_out, _env(domain, keys['real']), '/frf_ident/excitation')
    console = None
    try:
        token = exc.wait_for(r'ARMING TOKEN of this start: (\S+)').group(1)
        res['operator'] = _client(secure_out, _env(domain, keys['real']), 'operator',
                                  '/frf_ident/operator')
        res['ros2cli'] = _cli_call(_env(domain, keys['real'], '/frf_ident/operator'))
        res['intruder'], res['forger'], res['stranger'], res['plain'] = _parallel(
            (secure_out, _env(domain, keys['real']), 'intruder', '/frf_ident/intruder'),
            (secure_out, _env(domain, keys['forged']), 'forger', '/frf_ident/intruder'),
            (secure_out, _env(domain, keys['stranger']), 'stranger', '/frf_ident/intruder'),
            (secure_out, _env(domain), 'plain'))
        res['control'] = _client(secure_out, _env(domain, keys['control']), 'forger',
                                 '/frf_ident/intruder')
        console = _Proc([sys.executable, '-m', 'frf_ident.nodes.operator_node', '--token', token,
                         '--name', 'sros2-test', '--ros-args', '--enclave',
                         '/frf_ident/operator', '--params-file', str(params)],
                        _env(domain, keys['real']), secure_out / 'operator.log',
                        stdin=subprocess.PIPE)
        console.wait_for(r'ARMED: runs may start')
        console.p.stdin.write('q\n')
        console.p.stdin.flush()
        console.wait_for(r'quit: heartbeat stopped')
        res['console'] = console.text()
    finally:
        if console is not None:
            console.stop()
        exc.stop()
    res['secure_log'] = exc.text()
    # the same node and calls without security (a domain of its own)
    domain2 = new_domain()
    exc, _ = _excitation(open_out, _env(domain2), None)
    try:
        res['open_plain'], res['open_intruder'] = _parallel(
            (open_out, _env(domain2), 'plain'),
            (open_out, _env(domain2), 'intruder', '/frf_ident/intruder'))
    finally:
        exc.stop()
    res['open_log'] = exc.text()
    return res


def _show(case, r):
    keys = ('created', 'discovered', 'discover_s', 'answered', 'answer_s', 'arming_seen',
            'wall_s')
    print(f'{case}: ' + ', '.join(f'{k}={r.get(k)}' for k in keys)
          + (f"; error: {r['error']}" if r['error'] else '')
          + (f"; answer: {r['answer'][:90]}..." if r.get('answer') else ''))


def _callers(log):
    """Return the caller node of every run request the excitation node logged."""
    return re.findall(r'/frf/run_multisine (?:refused|accepted) at \S+: .*?; caller: node (\S+)',
                      log)


def test_operator_enclave_gets_an_answer(observed):
    """The operator's enclave calls: answered (refused: not armed), the node names it."""
    r = observed['operator']
    _show('operator', r)
    assert r['created'] and r['discovered'] and r['answered'] and r['arming_seen'], r
    reply = json.loads(r['answer'])
    assert reply['refused'] and reply['error'].startswith('not armed'), reply
    assert reply['caller'].startswith('node /operator'), reply
    cli = observed['ros2cli']
    print('ros2 service call under ROS_SECURITY_ENCLAVE_OVERRIDE=/frf_ident/operator: '
          + next((ln for ln in cli.splitlines() if 'Trigger_Response' in ln), cli)[:160])
    assert "Trigger_Response(success=False, message='{\"accepted\": false" in cli, cli


def test_operator_console_arms_the_node_in_its_enclave(observed):
    """The shipped policy carries the heartbeat and the announcement in Enforce mode."""
    assert 'excitation_node: ARMED: runs may start' in observed['console']


def test_intruder_enclave_cannot_even_create_the_client(observed):
    """
    A valid identity whose permissions lack the service: its own access control refuses.

    It is authenticated and matched (it reads the node's /frf/arming), but creating the
    request writer fails in its own participant, so no request is ever sent.
    """
    r = observed['intruder']
    _show('intruder', r)
    assert not r['created'] and not r['answered'], r
    assert 'failed to create client' in r['error'], r
    assert 'rq/frf/run_multisineRequest' in r['error'], r
    assert r['arming_seen'], 'the intruder did not even see the node: not a fair test'


def test_forged_permissions_are_refused_by_the_excitation_node(observed):
    """
    Permissions granting the call, signed by another CA: the node does not talk to it.

    The forger's client is created (its local checks use its own CA), but the service is
    never discovered and the call never answered; the excitation node logs that the remote
    participant's permissions did not verify. The control (the same permissions signed by the
    keystore's CA) is answered.
    """
    r, c = observed['forger'], observed['control']
    _show('forger', r)
    _show('control', c)
    assert r['created'] and not r['discovered'] and not r['answered'], r
    assert not r['arming_seen'], r
    assert r['wall_s'] >= 2 * WAIT_S, r
    assert re.search(r'remote participant \S+ permissions.*Verify error',
                     observed['secure_log']), observed['secure_log'][-3000:]
    assert c['created'] and c['discovered'] and c['answered'] and c['arming_seen'], c
    assert json.loads(c['answer'])['caller'].startswith('node /forger'), c


def test_a_keystore_of_its_own_is_not_authenticated(observed):
    """
    Identity and permissions from another CA, granting the call: never discovered.

    The handshake fails on the stranger's side: it cannot verify the excitation node's
    certificate (another identity CA), so the node's check of the stranger's certificate is
    not reached (a stranger with a patched plugin would meet it; not tested).
    """
    r = observed['stranger']
    _show('stranger', r)
    assert r['created'] and not r['discovered'] and not r['answered'], r
    assert not r['arming_seen'], r
    assert r['wall_s'] >= 2 * WAIT_S, r
    refusal = re.search(r'fsm: (Begin handshake reply failed: Certificate not valid: .*?);',
                        r['log'])
    assert refusal, r['log'][-2000:]
    print('stranger logged:', refusal.group(1))


def test_participant_without_security_never_discovers_the_service(observed):
    """No security: no discovery of the secure node, no answer; without security, answered."""
    r = observed['plain']
    _show('plain', r)
    assert r['created'] and not r['discovered'] and not r['answered'], r
    assert not r['arming_seen'], r
    assert r['wall_s'] >= 2 * WAIT_S, r
    for case in ('open_plain', 'open_intruder'):
        o = observed[case]
        _show(f'{case} (node without security)', o)
        assert o['created'] and o['discovered'] and o['answered'] and o['arming_seen'], o
        assert json.loads(o['answer'])['refused'], o


def test_only_authorised_callers_reached_the_node(observed):
    """The secure node logged requests from the operator, ros2cli and the control only."""
    callers = _callers(observed['secure_log'])
    print('callers the secure node logged:', callers)
    assert sorted(callers) == ['/_ros2cli_requester_std_srvs_Trigger', '/forger', '/operator']
    # without security both reach it; called at once, each may see both clients listed
    # (rclpy tells no request GID: "one of the clients of ...: /intruder, /plain")
    requests = re.findall(r'/frf/run_multisine (?:refused|accepted) at \S+: .*?; caller: '
                          r'(?:node (\S+)|one of the clients of \S+: ([^(]+) \()',
                          observed['open_log'])
    named = {n.strip() for one, some in requests for n in (one or some).split(',')}
    assert len(requests) == 2 and named == {'/intruder', '/plain'}, observed['open_log']
