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
The SROS2 keystore made without sros2 (frf_ident/io/sros2_keystore.py).

Permissions from a policy: the DDS topic names of topics, services and actions, relative,
absolute and ``~`` names, ALLOW and DENY rules, the grant's subject, validity and domain.
With ``openssl``: the keystore's layout as rcl and rmw_dds_common look for it, the
certificates (ECDSA P-256, CN, issuer, CA constraints) and the S/MIME signatures checked by
``openssl`` itself, a second run that keeps what exists, and the command line. That these
files work in Cyclone DDS's security plugins is test/ros/test_ros_sros2.py.
"""
import datetime
import os
from pathlib import Path
import subprocess
import xml.etree.ElementTree as ET

from frf_ident.io import sros2_keystore as ks
import pytest

ROOT = Path(__file__).resolve().parents[2]
POLICY = ROOT / 'config' / 'sros2' / 'frf_ident_policy.xml'
T0 = datetime.datetime(2026, 1, 2, 3, 4, 5)
T1 = datetime.datetime(2036, 1, 2, 3, 4, 5)
needs_openssl = pytest.mark.skipif(not ks.have_openssl(), reason='no openssl command line')

POLICY_TEXT = """<?xml version="1.0" encoding="UTF-8"?>
<policy version="0.2.0">
  <enclaves>
    <enclave path="/a/b">
      <profiles>
        <profile ns="/ns" node="n">
          <topics publish="ALLOW" subscribe="DENY">
            <topic>rel</topic><topic>/abs</topic><topic>~/own</topic>
          </topics>
          <topics subscribe="ALLOW"><topic>rel</topic></topics>
          <services request="ALLOW"><service>srv</service></services>
          <services reply="ALLOW"><service>~/get</service></services>
          <actions call="ALLOW"><action>/go</action></actions>
        </profile>
        <profile ns="/" node="m">
          <topics publish="ALLOW"><topic>rel</topic></topics>
          <actions execute="ALLOW"><action>act</action></actions>
        </profile>
      </profiles>
    </enclave>
    <enclave path="/other"><profiles/></enclave>
  </enclaves>
</policy>
"""


def _rules(xml_text):
    """{(rule tag, publish|subscribe): [topics]} of the one grant, and the grant."""
    root = ET.fromstring(xml_text)
    grants = root.findall('permissions/grant')
    assert len(grants) == 1
    out = {}
    for rule in grants[0]:
        if rule.tag in ('allow_rule', 'deny_rule'):
            for d in ('publish', 'subscribe'):
                out.setdefault((rule.tag, d), []).extend(
                    t.text for t in rule.findall(f'{d}/topics/topic'))
    return out, grants[0]


@pytest.fixture
def policy(tmp_path):
    p = tmp_path / 'policy.xml'
    p.write_text(POLICY_TEXT)
    return p


def test_names_map_to_dds_topics_as_the_ros2_design_does(policy):
    text = ks.permissions_xml(policy, '/a/b', 7, T0, T1, ros_discovery_info=False)
    rules, grant = _rules(text)
    assert rules[('allow_rule', 'publish')] == sorted({
        'rt/ns/rel', 'rt/abs', 'rt/ns/n/own', 'rt/rel',          # topics (profile m: /)
        'rq/ns/srvRequest', 'rr/ns/n/getReply',                  # request / reply
        'rq/go/_action/cancel_goalRequest', 'rq/go/_action/get_resultRequest',
        'rq/go/_action/send_goalRequest',                        # call
        'rr/act/_action/cancel_goalReply', 'rr/act/_action/get_resultReply',
        'rr/act/_action/send_goalReply', 'rt/act/_action/feedback',
        'rt/act/_action/status'})                                # execute
    assert rules[('allow_rule', 'subscribe')] == sorted({
        'rt/ns/rel', 'rr/ns/srvReply', 'rq/ns/n/getRequest',
        'rr/go/_action/cancel_goalReply', 'rr/go/_action/get_resultReply',
        'rr/go/_action/send_goalReply', 'rt/go/_action/feedback', 'rt/go/_action/status',
        'rq/act/_action/cancel_goalRequest', 'rq/act/_action/get_resultRequest',
        'rq/act/_action/send_goalRequest'})
    assert rules[('deny_rule', 'subscribe')] == ['rt/abs', 'rt/ns/n/own', 'rt/ns/rel']
    assert rules[('deny_rule', 'publish')] == []
    # the grant: subject of the enclave's certificate, validity, DENY before ALLOW, default
    assert grant.get('name') == '/a/b'
    assert grant.findtext('subject_name') == 'CN=/a/b'
    assert grant.findtext('validity/not_before') == '2026-01-02T03:04:05'
    assert grant.findtext('validity/not_after') == '2036-01-02T03:04:05'
    assert [c.tag for c in grant] == ['subject_name', 'validity', 'deny_rule', 'allow_rule',
                                      'default']
    assert grant.findtext('default') == 'DENY'
    assert {e.text for e in grant.iter('id')} == {'7'}


def test_ros_discovery_info_rule_and_an_enclave_without_rules(policy):
    _, grant = _rules(ks.permissions_xml(policy, '/other', 0, T0, T1))
    assert [c.tag for c in grant] == ['subject_name', 'validity', 'allow_rule', 'default']
    assert [t.text for t in grant.iter('topic')] == ['ros_discovery_info'] * 2


def test_the_shipped_policy_gives_the_run_services_to_the_operator_only():
    """Permissions from config/sros2: the run services' DDS topics, who writes which."""
    req = {f'rq/frf/{s}Request' for s in ('run_multisine', 'run_iteration')}
    rep = {f'rr/frf/{s}Reply' for s in ('run_multisine', 'run_iteration')}
    seen = {}
    for enclave in ks.policy_enclaves(POLICY):
        rules, _ = _rules(ks.permissions_xml(POLICY, enclave, 0, T0, T1))
        seen[enclave] = {d: set(rules.get(('allow_rule', d), []))
                         for d in ('publish', 'subscribe')}
    assert set(seen) == {'/frf_ident/excitation', '/frf_ident/operator',
                         '/frf_ident/estimator'}
    writers = {e for e, r in seen.items() if req & r['publish']}
    assert writers == {'/frf_ident/operator'}
    assert req <= seen['/frf_ident/operator']['publish']
    assert rep <= seen['/frf_ident/operator']['subscribe']
    assert req <= seen['/frf_ident/excitation']['subscribe']
    assert rep <= seen['/frf_ident/excitation']['publish']
    assert 'rt/velocity_controller/commands' in seen['/frf_ident/excitation']['publish']
    # '~' names under each node's own name
    assert 'rr/excitation_node/get_parametersReply' in seen['/frf_ident/excitation']['publish']
    assert ('rr/_ros2cli_requester_std_srvs_Trigger/get_parametersReply'
            in seen['/frf_ident/operator']['publish'])


def test_policy_errors_name_what(policy, tmp_path):
    with pytest.raises(ks.KeystoreError, match=r"no enclave '/x' \(it has /a/b, /other\)"):
        ks.permissions_xml(policy, '/x', 0, T0, T1)
    bad = tmp_path / 'bad.xml'
    bad.write_text(POLICY_TEXT.replace('request="ALLOW"', 'request="MAYBE"'))
    with pytest.raises(ks.KeystoreError, match='request="MAYBE"'):
        ks.permissions_xml(bad, '/a/b', 0, T0, T1)
    bad.write_text(POLICY_TEXT.replace('<actions call="ALLOW"><action>/go</action></actions>',
                                       '<nodes call="ALLOW"><node>/go</node></nodes>'))
    with pytest.raises(ks.KeystoreError, match='unknown <nodes>'):
        ks.permissions_xml(bad, '/a/b', 0, T0, T1)
    bad.write_text('<dds/>')
    with pytest.raises(ks.KeystoreError, match='not an SROS2 policy'):
        ks.policy_enclaves(bad)
    with pytest.raises(ks.KeystoreError, match='an absolute ROS name'):
        ks.enclave_dir(tmp_path, 'a/../b')


def test_governance_is_sros2s_default():
    root = ET.fromstring(ks.governance_xml(12))
    rule = root.find('domain_access_rules/domain_rule')
    assert rule.findtext('domains/id') == '12'
    assert rule.findtext('allow_unauthenticated_participants') == 'false'
    assert rule.findtext('enable_join_access_control') == 'true'
    assert rule.findtext('rtps_protection_kind') == 'SIGN'
    topic = rule.find('topic_access_rules/topic_rule')
    assert topic.findtext('topic_expression') == '*'
    assert topic.findtext('enable_write_access_control') == 'true'
    assert topic.findtext('data_protection_kind') == 'ENCRYPT'


def _openssl(*args):
    return subprocess.run(['openssl', *args], capture_output=True, text=True, check=True).stdout


@needs_openssl
def test_keystore_layout_certificates_and_signatures(tmp_path):
    k = tmp_path / 'keystore'
    dirs = ks.make_keystore(k, POLICY, ['/frf_ident/operator', '/frf_ident/excitation'],
                            domain_id=42)
    assert dirs == [k / 'enclaves' / 'frf_ident' / 'operator',
                    k / 'enclaves' / 'frf_ident' / 'excitation']
    ca = k / 'public' / 'ca.cert.pem'
    for role in ('identity_ca', 'permissions_ca'):
        assert os.readlink(k / 'public' / f'{role}.cert.pem') == 'ca.cert.pem'
        assert os.readlink(k / 'private' / f'{role}.key.pem') == 'ca.key.pem'
    assert (k / 'private').stat().st_mode & 0o077 == 0
    assert (k / 'private' / 'ca.key.pem').stat().st_mode & 0o077 == 0
    assert 'BEGIN PRIVATE KEY' in (k / 'private' / 'ca.key.pem').read_text()   # PKCS#8
    text = _openssl('x509', '-in', str(ca), '-noout', '-text')
    assert 'Subject: CN = sros2CA' in text and 'CA:TRUE, pathlen:1' in text
    assert 'prime256v1' in text and 'ecdsa-with-SHA256' in text
    d = dirs[0]
    # what rmw_dds_common's get_security_files takes, every one a file (links resolve)
    for name in ('identity_ca.cert.pem', 'cert.pem', 'key.pem', 'permissions_ca.cert.pem',
                 'governance.p7s', 'permissions.p7s'):
        assert (d / name).is_file(), name
    assert os.readlink(d / 'governance.p7s') == '../../governance.p7s'
    assert os.readlink(d / 'identity_ca.cert.pem') == '../../../public/identity_ca.cert.pem'
    assert (d / 'key.pem').stat().st_mode & 0o077 == 0
    text = _openssl('x509', '-in', str(d / 'cert.pem'), '-noout', '-text')
    assert 'Subject: CN = /frf_ident/operator' in text and 'Issuer: CN = sros2CA' in text
    assert 'CA:FALSE' in text and 'prime256v1' in text
    assert _openssl('verify', '-CAfile', str(ca), str(d / 'cert.pem')).strip().endswith('OK')
    # the signed documents: detached text S/MIME that verifies with the CA, same content
    gov = k / 'enclaves'
    for signed, plain in ((gov / 'governance.p7s', gov / 'governance.xml'),
                          (d / 'permissions.p7s', d / 'permissions.xml')):
        head = signed.read_text()[:400]
        assert 'multipart/signed' in head and 'micalg="sha-256"' in head
        out = subprocess.run(['openssl', 'smime', '-verify', '-text', '-in', str(signed),
                              '-CAfile', str(ca)], capture_output=True, check=True).stdout
        assert out.replace(b'\r\n', b'\n') == plain.read_bytes()
    # the grant holds over the certificate's validity, for the keystore's domain
    grant = ET.parse(d / 'permissions.xml').getroot().find('permissions/grant')
    dates = dict(line.split('=', 1) for line in _openssl(
        'x509', '-in', str(d / 'cert.pem'), '-noout', '-dates').splitlines())
    start = datetime.datetime.strptime(' '.join(dates['notBefore'].split()),
                                       '%b %d %H:%M:%S %Y GMT')
    assert grant.findtext('validity/not_before') == start.strftime('%Y-%m-%dT%H:%M:%S')
    assert {e.text for e in grant.iter('id')} == {'42'}
    assert ks.keystore_domain(k) == 42


@needs_openssl
def test_a_signature_verifies_only_with_its_own_keystores_ca(tmp_path):
    ks.create_keystore(tmp_path / 'a', 0)
    ks.create_keystore(tmp_path / 'b', 0)
    r = subprocess.run(['openssl', 'smime', '-verify', '-in',
                        str(tmp_path / 'a' / 'enclaves' / 'governance.p7s'), '-CAfile',
                        str(tmp_path / 'b' / 'public' / 'ca.cert.pem')], capture_output=True)
    assert r.returncode != 0


@needs_openssl
def test_a_second_run_keeps_the_ca_and_identities_and_refuses_another_domain(tmp_path):
    k = tmp_path / 'k'
    ks.make_keystore(k, POLICY, ['/frf_ident/operator'], domain_id=3)
    d = ks.enclave_dir(k, '/frf_ident/operator')
    before = {p: p.read_bytes() for p in (k / 'public' / 'ca.cert.pem', d / 'cert.pem',
                                          d / 'key.pem', k / 'enclaves' / 'governance.p7s')}
    ks.make_keystore(k, POLICY, ['/frf_ident/operator', '/frf_ident/excitation'])
    assert {p: p.read_bytes() for p in before} == before
    assert (ks.enclave_dir(k, '/frf_ident/excitation') / 'permissions.p7s').is_file()
    with pytest.raises(ks.KeystoreError, match='holds for domain 3, not 4'):
        ks.create_permission(k, '/frf_ident/operator', POLICY, domain_id=4)
    with pytest.raises(ks.KeystoreError, match='no cert.pem'):
        ks.create_permission(k, '/frf_ident/estimator', POLICY)
    with pytest.raises(ks.KeystoreError, match='not a keystore'):
        ks.create_enclave(tmp_path / 'nothing', '/x')


@needs_openssl
def test_command_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv('ROS_DOMAIN_ID', '9')
    assert ks.main([str(tmp_path / 'k')]) == 0
    out = capsys.readouterr().out
    assert f'keystore {tmp_path / "k"} (domain 9, policy {POLICY})' in out
    for e in ('excitation', 'operator', 'estimator'):
        assert f'enclave /frf_ident/{e}: ' in out
        assert (tmp_path / 'k' / 'enclaves' / 'frf_ident' / e / 'permissions.p7s').is_file()
    assert ks.main([str(tmp_path / 'k2'), '--enclave', '/frf_ident/nobody']) == 2
    assert "no enclave '/frf_ident/nobody'" in capsys.readouterr().err
    assert not (tmp_path / 'k2').exists()
