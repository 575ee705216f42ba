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
ROS 2 tests: run only where ROS 2 Jazzy is sourced (rclpy importable), else skipped.

Each test gets its own ROS_DOMAIN_ID from :func:`next_domain`: a domain in 110..149 that no
other test process holds (an flock on /tmp/frf_ident_ros_domain_<id>.lock, kept until this
session ends), so neither sequential tests nor concurrent test sessions share a domain.
"""
import fcntl
import importlib.util
import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HAVE_ROS = importlib.util.find_spec('rclpy') is not None and bool(os.environ.get('ROS_DISTRO'))
_held: list = []


def next_domain() -> int:
    """Return a ROS domain id in 110..149 held by no other test session, unused here."""
    for d in range(110, 150):
        if any(h[0] == d for h in _held):
            continue
        f = open(f'/tmp/frf_ident_ros_domain_{d}.lock', 'w')
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.close()
            continue
        _held.append((d, f))
        return d
    raise RuntimeError('no free ROS domain in 110..149')


def pytest_collection_modifyitems(config, items):
    skip = pytest.mark.skip(reason='ROS 2 Jazzy not sourced (source /opt/ros/jazzy/setup.bash)')
    for item in items:
        if Path(str(item.fspath)).parent == Path(__file__).parent:
            item.add_marker(pytest.mark.ros)
            if not HAVE_ROS:
                item.add_marker(skip)


@pytest.fixture(scope='session')
def new_domain():
    """:func:`next_domain` as a fixture (test modules here are not importable packages)."""
    return next_domain


@pytest.fixture
def ros_env():
    """Environment of the ROS processes a test starts: loopback, its own domain, rclpy."""
    env = dict(os.environ)
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', RMW_IMPLEMENTATION='rmw_cyclonedds_cpp',
               CYCLONEDDS_URI=(ROOT / 'config' / 'cyclonedds-localhost.xml').as_uri(),
               ROS_DOMAIN_ID=str(next_domain()), FRF_IDENT_MIDDLEWARE='rclpy',
               PYTHONUNBUFFERED='1',
               PYTHONPATH=os.pathsep.join([str(ROOT)] + [
                   p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]))
    return env
