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
An SROS2 keystore without sros2: the layout ``ros2 security`` makes, built with ``openssl``.

Where sros2 is installed, use it (docs/ros2.md, "SROS2"). This module makes the same files
with the ``openssl`` command line and the Python standard library, for a PC without sros2::

    python3 -m frf_ident.io.sros2_keystore KEYSTORE [--policy POLICY.xml]
        [--enclave /frf_ident/operator ...] [--domain ID]

Layout (sros2's ``create_keystore`` / ``create_enclave`` / ``create_permission``; rcl takes
an enclave's files from ``$ROS_SECURITY_KEYSTORE/enclaves/<enclave>``, rmw_dds_common's
``get_security_files`` names them)::

    KEYSTORE/public/ca.cert.pem            one CA, ECDSA P-256, CN=sros2CA
    KEYSTORE/public/{identity,permissions}_ca.cert.pem  -> ca.cert.pem
    KEYSTORE/private/ca.key.pem            (PKCS#8, mode 600)
    KEYSTORE/private/{identity,permissions}_ca.key.pem  -> ca.key.pem
    KEYSTORE/enclaves/governance.xml, governance.p7s  (signed by the permissions CA)
    KEYSTORE/enclaves/<enclave>/cert.pem, key.pem      CN=<enclave>, signed by the identity CA
    KEYSTORE/enclaves/<enclave>/permissions.xml, permissions.p7s
    KEYSTORE/enclaves/<enclave>/{identity_ca.cert.pem, permissions_ca.cert.pem,
                                 governance.p7s}  -> the keystore's (relative links)

The governance is sros2's default: no unauthenticated participants, join access control,
discovery and liveliness encrypted, RTPS messages signed, every topic's data encrypted and
its reads and writes access-controlled. The ``.p7s`` files are S/MIME, detached
(multipart/signed), text, SHA-256, the signer's certificate included: ``openssl smime -sign
-text``, what sros2 makes with ``cryptography``'s PKCS#7 builder.

A permissions file holds one grant for the enclave's certificate subject (``CN=<enclave>``),
valid over the certificate's validity, from the enclave's profiles in an SROS2 policy
(policy version 0.2.0, the ROS 2 design article "ROS 2 DDS-Security integration" and
sros2's ``policy/templates/dds/permissions.xsl``): a topic ``t`` becomes the DDS topic
``rt/t``, a service ``s`` the request topic ``rq/sRequest`` and the reply topic
``rr/sReply`` (``request``: publish the request, subscribe the reply; ``reply``: the other
way round), an action its ``_action`` services and topics; relative names are resolved in
the profile's namespace, ``~`` names under the node's name. Every grant also allows
``ros_discovery_info`` (as sros2 adds for rmw_cyclonedds_cpp) and defaults to DENY.

Differences from sros2: certificates are valid from the moment they are made (sros2 dates
them a day back), so a PC whose clock is behind the one that made the keystore refuses them
until it catches up; the XML is not validated against the OMG schemas (no lxml here).
"""
from __future__ import annotations

import argparse
import datetime
import os
from pathlib import Path
import secrets
import shutil
import subprocess
import sys
import tempfile
from typing import Iterable, Optional, Sequence
import xml.etree.ElementTree as ET

from frf_ident.errors import FrfIdentInputError

__all__ = ['CA_NAME', 'DEFAULT_POLICY', 'KeystoreError', 'create_enclave', 'create_keystore',
           'create_permission', 'enclave_dir', 'governance_xml', 'have_openssl',
           'keystore_domain', 'main', 'make_keystore', 'permissions_xml', 'policy_enclaves',
           'sign_smime']

#: the CA's common name, sros2's
CA_NAME = 'sros2CA'
#: the shipped policy (docs/ros2.md, "SROS2"), relative to the package's share directory
DEFAULT_POLICY = Path('config') / 'sros2' / 'frf_ident_policy.xml'
#: validity of the CA and enclave certificates [days], sros2's
VALID_DAYS = 3650
_SCHEMA = 'http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_{}.xsd'
_XSI = 'http://www.w3.org/2001/XMLSchema-instance'
#: an action's services and topics under ``<action>/_action/``
_ACTION_SERVICES = ('cancel_goal', 'get_result', 'send_goal')
_ACTION_TOPICS = ('feedback', 'status')
#: policy element -> (its child element, the permissions it takes)
_KINDS = {'topics': ('topic', ('publish', 'subscribe')),
          'services': ('service', ('request', 'reply')),
          'actions': ('action', ('call', 'execute'))}


class KeystoreError(FrfIdentInputError):
    """A keystore, policy or enclave that cannot be made as asked (names what and why)."""


def have_openssl(openssl: str = 'openssl') -> bool:
    """Return whether the ``openssl`` command line is on PATH."""
    return shutil.which(openssl) is not None


def _openssl(*args: str, openssl: str = 'openssl') -> str:
    """Run ``openssl ARGS``; return its stdout, raise :class:`KeystoreError` with stderr."""
    exe = shutil.which(openssl)
    if exe is None:
        raise KeystoreError(f'{openssl!r} not found: install it (Debian/Ubuntu: apt install '
                            'openssl) or use sros2 (ros2 security)')
    r = subprocess.run([exe, *args], capture_output=True, text=True)
    if r.returncode != 0:
        raise KeystoreError(f'openssl {args[0]} failed ({r.returncode}): {r.stderr.strip()}')
    return r.stdout


def _dds_topics(kind: str, perm: str, name: str) -> list[tuple[str, str]]:
    """Return the (DDS rule, DDS topic) pairs one policy permission on one ROS name grants."""
    if kind == 'topics':
        return [(perm, 'rt' + name)]
    if kind == 'services':
        req, rep = 'rq' + name + 'Request', 'rr' + name + 'Reply'
        return [('publish', req), ('subscribe', rep)] if perm == 'request' else [
            ('publish', rep), ('subscribe', req)]
    requests = [f'rq{name}/_action/{s}Request' for s in _ACTION_SERVICES]
    replies = [f'rr{name}/_action/{s}Reply' for s in _ACTION_SERVICES]
    topics = [f'rt{name}/_action/{t}' for t in _ACTION_TOPICS]
    if perm == 'call':
        return [('publish', t) for t in requests] + [
            ('subscribe', t) for t in replies + topics]
    return [('publish', t) for t in replies + topics] + [('subscribe', t) for t in requests]


def _resolve(name: str, ns: str, node: str) -> str:
    """Return the fully qualified ROS name of a policy name in a profile (``ns``, ``node``)."""
    if name.startswith('/'):
        return name
    base = ns if ns.endswith('/') else ns + '/'
    if name.startswith('~'):
        return base + node + name[1:]
    return base + name


def _policy_root(policy: Path | str) -> ET.Element:
    try:
        root = ET.parse(str(policy)).getroot()
    except (OSError, ET.ParseError) as e:
        raise KeystoreError(f'{policy}: not a readable policy: {e}') from e
    if root.tag != 'policy' or root.find('enclaves') is None:
        raise KeystoreError(f'{policy}: not an SROS2 policy (<policy><enclaves>...)')
    return root


def policy_enclaves(policy: Path | str) -> list[str]:
    """Return the enclave paths of an SROS2 policy file, in its order."""
    return [e.get('path', '') for e in _policy_root(policy).find('enclaves')]


def _grants(policy: Path | str, enclave: str) -> dict[str, dict[str, set[str]]]:
    """Return {'ALLOW'|'DENY': {'publish'|'subscribe': {DDS topic}}} of a policy's enclave."""
    found = [e for e in _policy_root(policy).find('enclaves') if e.get('path') == enclave]
    if not found:
        raise KeystoreError(f'{policy}: no enclave {enclave!r} (it has '
                            f'{", ".join(policy_enclaves(policy))})')
    out: dict[str, dict[str, set[str]]] = {
        q: {'publish': set(), 'subscribe': set()} for q in ('DENY', 'ALLOW')}
    for profiles in found[0].iter('profiles'):
        for profile in profiles:
            ns, node = profile.get('ns', '/'), profile.get('node', '')
            for rule in profile:
                if rule.tag not in _KINDS:
                    raise KeystoreError(f'{policy}: {enclave} {node}: unknown <{rule.tag}>')
                child, perms = _KINDS[rule.tag]
                for perm, qual in rule.attrib.items():
                    if perm not in perms or qual not in out:
                        raise KeystoreError(f'{policy}: {enclave} {node}: <{rule.tag} '
                                            f'{perm}="{qual}"> is not an SROS2 permission')
                    for obj in rule.iter(child):
                        name = _resolve((obj.text or '').strip(), ns, node)
                        for dds_rule, topic in _dds_topics(rule.tag, perm, name):
                            out[qual][dds_rule].add(topic)
    return out


def _domains(parent: ET.Element, domain_id: int) -> None:
    ET.SubElement(ET.SubElement(parent, 'domains'), 'id').text = str(int(domain_id))


def _document(kind: str) -> ET.Element:
    root = ET.Element('dds', {'xmlns:xsi': _XSI,
                              'xsi:noNamespaceSchemaLocation': _SCHEMA.format(kind)})
    return root


def _text(root: ET.Element) -> str:
    ET.indent(root, space='  ')
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(
        root, encoding='unicode') + '\n'


def permissions_xml(policy: Path | str, enclave: str, domain_id: int,
                    not_before: datetime.datetime, not_after: datetime.datetime,
                    ros_discovery_info: bool = True) -> str:
    """
    Return the DDS permissions document of one enclave of an SROS2 policy.

    Parameters
    ----------
    policy : Path or str
        The policy file (e.g. config/sros2/frf_ident_policy.xml).
    enclave : str
        The enclave's path in the policy (``/frf_ident/operator``); the grant's subject is
        ``CN=<enclave>``, the enclave certificate's subject.
    domain_id : int
        The ROS_DOMAIN_ID the grant holds for.
    not_before, not_after : datetime
        The grant's validity (UTC; the enclave certificate's).
    ros_discovery_info : bool
        Also allow publishing and subscribing ``ros_discovery_info`` (rmw_cyclonedds_cpp,
        rmw_fastrtps and rmw_connextdds need it for the ROS graph).

    Returns
    -------
    str
        The XML text (UTF-8 declaration), rules sorted by topic name.

    """
    grants = _grants(policy, enclave)
    root = _document('permissions')
    grant = ET.SubElement(ET.SubElement(root, 'permissions'), 'grant', {'name': enclave})
    ET.SubElement(grant, 'subject_name').text = f'CN={enclave}'
    validity = ET.SubElement(grant, 'validity')
    for tag, t in (('not_before', not_before), ('not_after', not_after)):
        ET.SubElement(validity, tag).text = t.strftime('%Y-%m-%dT%H:%M:%S')
    rules = [(q.lower() + '_rule', grants[q]) for q in ('DENY', 'ALLOW')]
    if ros_discovery_info:
        rules.append(('allow_rule', {'publish': {'ros_discovery_info'},
                                     'subscribe': {'ros_discovery_info'}}))
    for tag, topics in rules:
        if not any(topics.values()):
            continue
        rule = ET.SubElement(grant, tag)
        _domains(rule, domain_id)
        for direction in ('publish', 'subscribe'):
            if topics[direction]:
                listed = ET.SubElement(ET.SubElement(rule, direction), 'topics')
                for name in sorted(topics[direction]):
                    ET.SubElement(listed, 'topic').text = name
    ET.SubElement(grant, 'default').text = 'DENY'
    return _text(root)


def governance_xml(domain_id: int) -> str:
    """Return sros2's default governance document for one domain (module docstring)."""
    root = _document('governance')
    rule = ET.SubElement(ET.SubElement(root, 'domain_access_rules'), 'domain_rule')
    _domains(rule, domain_id)
    for tag, value in (('allow_unauthenticated_participants', 'false'),
                       ('enable_join_access_control', 'true'),
                       ('discovery_protection_kind', 'ENCRYPT'),
                       ('liveliness_protection_kind', 'ENCRYPT'),
                       ('rtps_protection_kind', 'SIGN')):
        ET.SubElement(rule, tag).text = value
    topic = ET.SubElement(ET.SubElement(rule, 'topic_access_rules'), 'topic_rule')
    for tag, value in (('topic_expression', '*'),
                       ('enable_discovery_protection', 'true'),
                       ('enable_liveliness_protection', 'true'),
                       ('enable_read_access_control', 'true'),
                       ('enable_write_access_control', 'true'),
                       ('metadata_protection_kind', 'ENCRYPT'),
                       ('data_protection_kind', 'ENCRYPT')):
        ET.SubElement(topic, tag).text = value
    return _text(root)


def sign_smime(cert: Path, key: Path, document: Path, signed: Path,
               openssl: str = 'openssl') -> None:
    """Sign ``document`` into ``signed``: S/MIME, detached, text, SHA-256, cert included."""
    _openssl('smime', '-sign', '-text', '-md', 'sha256', '-in', str(document),
             '-out', str(signed), '-signer', str(cert), '-inkey', str(key), openssl=openssl)


def _link(target: Path, link: Path) -> None:
    """Make ``link`` a symbolic link to ``target`` relative to the link's directory."""
    rel = os.path.relpath(target, link.parent)
    if link.is_symlink() or link.exists():
        if link.is_symlink() and os.readlink(link) == rel:
            return
        link.unlink()
    link.symlink_to(rel)


def _new_key(path: Path, openssl: str) -> None:
    """Write a new ECDSA P-256 private key (PKCS#8 PEM) readable by its owner only."""
    tmp = path.with_name(path.name + '.tmp')
    _openssl('genpkey', '-algorithm', 'EC', '-pkeyopt', 'ec_paramgen_curve:P-256',
             '-pkeyopt', 'ec_param_enc:named_curve', '-out', str(tmp), openssl=openssl)
    tmp.chmod(0o600)
    tmp.replace(path)


def _config(common_name: str, ca: bool) -> str:
    """Return an openssl ``req``/``x509`` config: the subject and the basic constraints."""
    basic = 'critical, CA:TRUE, pathlen:1' if ca else 'CA:FALSE'
    return ('[req]\nprompt = no\ndistinguished_name = dn\n'
            f'[dn]\nCN = {common_name}\n'
            f'[ext]\nbasicConstraints = {basic}\n'
            'subjectKeyIdentifier = hash\n')


def _serial() -> str:
    """Return a random positive 127-bit certificate serial number (hex)."""
    return hex(secrets.randbits(126) | 1 << 126)


def _cert(common_name: str, key: Path, out: Path, openssl: str,
          ca: Optional[tuple[Path, Path]] = None) -> None:
    """Write a certificate for ``key``: self-signed (a CA) or signed by ``ca`` (cert, key)."""
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Path(tmp) / 'openssl.cnf'
        cfg.write_text(_config(common_name, ca is None))
        if ca is None:
            _openssl('req', '-new', '-x509', '-config', str(cfg), '-extensions', 'ext',
                     '-key', str(key), '-sha256', '-days', str(VALID_DAYS),
                     '-set_serial', _serial(), '-out', str(out), openssl=openssl)
            return
        csr = Path(tmp) / 'req.pem'
        _openssl('req', '-new', '-config', str(cfg), '-key', str(key), '-out', str(csr),
                 openssl=openssl)
        _openssl('x509', '-req', '-in', str(csr), '-CA', str(ca[0]), '-CAkey', str(ca[1]),
                 '-set_serial', _serial(), '-sha256', '-days', str(VALID_DAYS),
                 '-extfile', str(cfg), '-extensions', 'ext', '-out', str(out),
                 openssl=openssl)


def _validity(cert: Path, openssl: str) -> tuple[datetime.datetime, datetime.datetime]:
    """Return a certificate's (notBefore, notAfter) in UTC."""
    out = dict(line.split('=', 1) for line in _openssl(
        'x509', '-noout', '-startdate', '-enddate', '-in', str(cert),
        openssl=openssl).splitlines() if '=' in line)

    def parse(text: str) -> datetime.datetime:
        return datetime.datetime.strptime(' '.join(text.split()), '%b %d %H:%M:%S %Y GMT')
    return parse(out['notBefore']), parse(out['notAfter'])


def _domain(domain_id: Optional[int]) -> int:
    if domain_id is not None:
        return int(domain_id)
    return int(os.environ.get('ROS_DOMAIN_ID', '').strip() or 0)


def keystore_domain(keystore: Path | str) -> int:
    """Return the domain id a keystore's governance holds for."""
    gov = Path(keystore, 'enclaves', 'governance.xml')
    try:
        return int(ET.parse(str(gov)).getroot().findtext(
            'domain_access_rules/domain_rule/domains/id'))
    except (OSError, ET.ParseError, TypeError, ValueError) as e:
        raise KeystoreError(f'{gov}: no domain id ({e})') from e


def _same_domain(keystore: Path, domain_id: Optional[int]) -> int:
    """Return the keystore's domain; refuse an explicit other one (one domain a keystore)."""
    have = keystore_domain(keystore)
    if domain_id is not None and int(domain_id) != have:
        raise KeystoreError(f'{keystore}: its governance holds for domain {have}, not '
                            f'{domain_id} (make a keystore per domain)')
    return have


def enclave_dir(keystore: Path | str, enclave: str) -> Path:
    """Return where rcl looks for an enclave's files: ``KEYSTORE/enclaves/<enclave>``."""
    parts = [p for p in enclave.split('/') if p]
    if not enclave.startswith('/') or any(p in ('.', '..') for p in parts):
        raise KeystoreError(f'enclave {enclave!r}: an absolute ROS name (/frf_ident/operator)')
    return Path(keystore, 'enclaves', *parts)


def create_keystore(keystore: Path | str, domain_id: Optional[int] = None,
                    openssl: str = 'openssl') -> Path:
    """
    Make (or complete) a keystore: the CA, its links and the signed governance.

    An existing CA and governance are kept (as sros2 does), so enclaves made before stay
    valid; delete the keystore to start again.

    Parameters
    ----------
    keystore : Path or str
        The keystore directory (``ROS_SECURITY_KEYSTORE``).
    domain_id : int, optional
        The domain the governance holds for; default ``ROS_DOMAIN_ID`` or 0. A keystore
        holds for one domain: an existing one for another domain is refused.
    openssl : str
        The openssl command.

    Returns
    -------
    Path
        The keystore.

    """
    ks = Path(keystore)
    public, private, enclaves = (ks / 'public', ks / 'private', ks / 'enclaves')
    for d in (public, private, enclaves):
        d.mkdir(parents=True, exist_ok=True)
    private.chmod(0o700)
    ca_cert, ca_key = public / 'ca.cert.pem', private / 'ca.key.pem'
    if not (ca_cert.is_file() and ca_key.is_file()):
        _new_key(ca_key, openssl)
        _cert(CA_NAME, ca_key, ca_cert, openssl)
    for role in ('identity_ca', 'permissions_ca'):
        _link(ca_cert, public / f'{role}.cert.pem')
        _link(ca_key, private / f'{role}.key.pem')
    gov = enclaves / 'governance.xml'
    if gov.is_file():
        _same_domain(ks, domain_id)
    else:
        gov.write_text(governance_xml(_domain(domain_id)))
    if not (enclaves / 'governance.p7s').is_file():
        sign_smime(public / 'permissions_ca.cert.pem', private / 'permissions_ca.key.pem',
                   gov, enclaves / 'governance.p7s', openssl)
    return ks


def create_enclave(keystore: Path | str, enclave: str, openssl: str = 'openssl') -> Path:
    """
    Make an enclave's identity: its key, its certificate (CN=enclave) and the links.

    An existing key and certificate are kept. The enclave needs permissions
    (:func:`create_permission`) before a node can use it.

    Returns
    -------
    Path
        The enclave's directory.

    """
    ks = Path(keystore)
    if not (ks / 'enclaves' / 'governance.p7s').is_file():
        raise KeystoreError(f'{ks}: not a keystore (make it first: create_keystore)')
    d = enclave_dir(ks, enclave)
    d.mkdir(parents=True, exist_ok=True)
    for name in ('identity_ca.cert.pem', 'permissions_ca.cert.pem'):
        _link(ks / 'public' / name, d / name)
    _link(ks / 'enclaves' / 'governance.p7s', d / 'governance.p7s')
    if not ((d / 'cert.pem').is_file() and (d / 'key.pem').is_file()):
        _new_key(d / 'key.pem', openssl)
        _cert(enclave, d / 'key.pem', d / 'cert.pem', openssl,
              ca=(ks / 'public' / 'identity_ca.cert.pem',
                  ks / 'private' / 'identity_ca.key.pem'))
    return d


def create_permission(keystore: Path | str, enclave: str, policy: Path | str,
                      domain_id: Optional[int] = None, openssl: str = 'openssl') -> Path:
    """
    Write an enclave's permissions.xml from a policy and sign it into permissions.p7s.

    Parameters
    ----------
    keystore : Path or str
        The keystore (made by :func:`create_keystore`).
    enclave : str
        An enclave of the policy, made by :func:`create_enclave`.
    policy : Path or str
        The SROS2 policy file.
    domain_id : int, optional
        The domain the grant holds for: the keystore's (its governance's); another one is
        refused.
    openssl : str
        The openssl command.

    Returns
    -------
    Path
        permissions.p7s.

    """
    ks, d = Path(keystore), enclave_dir(keystore, enclave)
    if not (d / 'cert.pem').is_file():
        raise KeystoreError(f'{d}: no cert.pem (make the enclave first: create_enclave)')
    domain = _same_domain(ks, domain_id)
    before, after = _validity(d / 'cert.pem', openssl)
    (d / 'permissions.xml').write_text(permissions_xml(policy, enclave, domain, before, after))
    sign_smime(ks / 'public' / 'permissions_ca.cert.pem',
               ks / 'private' / 'permissions_ca.key.pem', d / 'permissions.xml',
               d / 'permissions.p7s', openssl)
    return d / 'permissions.p7s'


def make_keystore(keystore: Path | str, policy: Path | str,
                  enclaves: Optional[Iterable[str]] = None, domain_id: Optional[int] = None,
                  openssl: str = 'openssl') -> list[Path]:
    """
    Make a keystore with enclaves and their permissions from a policy.

    ``ros2 security create_keystore`` + ``create_enclave`` + ``create_permission`` per
    enclave; default enclaves: every enclave of the policy. Returns their directories.
    """
    names = list(enclaves) if enclaves else policy_enclaves(policy)
    for name in names:          # a name the policy lacks fails before anything is written
        _grants(policy, name)
    create_keystore(keystore, domain_id, openssl)
    out = []
    for name in names:
        out.append(create_enclave(keystore, name, openssl))
        create_permission(keystore, name, policy, domain_id, openssl)
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Command line (module docstring): make the keystore; 2 with a one-line error."""
    from frf_ident.io.share import share_dir
    p = argparse.ArgumentParser(
        prog='python3 -m frf_ident.io.sros2_keystore',
        description='Make an SROS2 keystore (the layout of ros2 security create_keystore, '
                    'create_enclave, create_permission) with openssl, without sros2.')
    p.add_argument('keystore', type=Path, help='keystore directory (ROS_SECURITY_KEYSTORE)')
    p.add_argument('--policy', type=Path, default=None,
                   help=f"SROS2 policy (default: the package's {DEFAULT_POLICY})")
    p.add_argument('--enclave', action='append', default=None,
                   help='an enclave of the policy (repeatable; default: all of them)')
    p.add_argument('--domain', type=int, default=None,
                   help='ROS_DOMAIN_ID the governance and permissions hold for (default: '
                        'ROS_DOMAIN_ID or 0)')
    args = p.parse_args(argv)
    policy = args.policy or share_dir() / DEFAULT_POLICY
    try:
        dirs = make_keystore(args.keystore, policy, args.enclave, args.domain)
    except KeystoreError as e:
        print(f'sros2_keystore: error: {e}', file=sys.stderr)
        return 2
    domain = keystore_domain(args.keystore)
    print(f'keystore {args.keystore} (domain {domain}, policy {policy}):')
    for d in dirs:
        print(f'  enclave /{d.relative_to(args.keystore / "enclaves").as_posix()}: {d}')
    print(f'use it: export ROS_SECURITY_KEYSTORE={args.keystore.resolve()} '
          f'ROS_SECURITY_ENABLE=true ROS_SECURITY_STRATEGY=Enforce ROS_DOMAIN_ID={domain}; '
          'each node with --ros-args --enclave ENCLAVE')
    return 0


if __name__ == '__main__':
    sys.exit(main())
