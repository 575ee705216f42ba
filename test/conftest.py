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
Shared test setup: every DDS participant stays on loopback (docs/CONTRACT.md §2).

Every DDS participant a test starts is on a ROS_DOMAIN_ID that no other test process holds:
a domain in 100..199 with an flock on /tmp/frf_ident_ros_domain_<id>.lock
(:func:`next_domain`), so neither sequential tests, nor the parallel workers of one
``make test`` (pytest-xdist), nor concurrent test sessions share a domain. Each test runs with
ROS_DOMAIN_ID set to one of its own (released after it) unless a fixture of a wider scope
set one already; a test that needs more takes them from the fixture ``new_domain`` (held
until the process ends).
"""
import fcntl
import os
from pathlib import Path
import signal
import warnings

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = ROOT.parent / 'shared' / 'data'

os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('CYCLONEDDS_URI', (ROOT / 'config' / 'cyclonedds-localhost.xml').as_uri())
os.environ.setdefault('MPLBACKEND', 'Agg')

_held: list = []
_turn = [os.getpid() % 100]


def next_domain() -> int:
    """Return a ROS domain id in 100..199 held by no other test process, unused here."""
    # round robin from a per-process start: a domain just released is not taken again at
    # once, while a process the test before started may still be leaving it
    for k in range(100):
        d = 100 + (_turn[0] + k) % 100
        if any(h[0] == d for h in _held):
            continue
        f = open(f'/tmp/frf_ident_ros_domain_{d}.lock', 'w')
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.close()
            continue
        _held.append((d, f))
        _turn[0] = (d - 100 + 1) % 100
        return d
    raise RuntimeError('no free ROS domain in 100..199')


def release_domain(domain: int) -> None:
    """Give a domain of :func:`next_domain` back (its lock file stays for the next taker)."""
    for h in [h for h in _held if h[0] == domain]:
        _held.remove(h)
        h[1].close()


@pytest.fixture(autouse=True)
def _own_domain(monkeypatch):
    """Run the test on a domain of its own (graphs it starts pick ROS_DOMAIN_ID up)."""
    if os.environ.get('ROS_DOMAIN_ID', '').strip() and any(
            str(h[0]) == os.environ['ROS_DOMAIN_ID'].strip() for h in _held):
        yield           # a module fixture put the process on a domain of its own already
        return
    d = next_domain()
    monkeypatch.setenv('ROS_DOMAIN_ID', str(d))
    try:
        yield
    finally:
        release_domain(d)


def sigint_ignored() -> bool:
    """Return whether this process ignores SIGINT (as the kernel has it; children inherit it)."""
    for line in Path('/proc/self/status').read_text().splitlines():
        if line.startswith('SigIgn:'):
            return bool(int(line.split()[1], 16) >> (signal.SIGINT - 1) & 1)
    return False


@pytest.fixture(autouse=True)
def _sigint_as_found(request):
    """
    Leave SIGINT as the test found it, and say which test did not.

    An ignored SIGINT is inherited by every process the worker starts later: an ``identify``
    child of test/cli/test_identify_live.py then ignored its Ctrl-C (SigIgn 0x81001006) in two
    full runs. The test that leaves it so is named by the warning, and the worker's handler is
    put back for the tests after it.
    """
    before = signal.getsignal(signal.SIGINT), sigint_ignored()
    yield
    if sigint_ignored() and not before[1]:
        handler = before[0] if callable(before[0]) else signal.default_int_handler
        signal.signal(signal.SIGINT, handler)
        warnings.warn(f'{request.node.nodeid} left SIGINT ignored in the test process '
                      '(restored)', RuntimeWarning)


@pytest.fixture(scope='session')
def new_domain():
    """:func:`next_domain` as a fixture (test modules here are not importable packages)."""
    return next_domain
