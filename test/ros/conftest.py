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

Each test runs on a ROS_DOMAIN_ID of its own (test/conftest.py), which ``ros_env`` passes on.
"""
import importlib.util
import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HAVE_ROS = importlib.util.find_spec('rclpy') is not None and bool(os.environ.get('ROS_DISTRO'))


def pytest_collection_modifyitems(config, items):
    skip = pytest.mark.skip(reason='ROS 2 Jazzy not sourced (source /opt/ros/jazzy/setup.bash)')
    for item in items:
        if Path(str(item.fspath)).parent == Path(__file__).parent:
            item.add_marker(pytest.mark.ros)
            if not HAVE_ROS:
                item.add_marker(skip)


@pytest.fixture
def ros_env():
    """Environment of the ROS processes a test starts: loopback, the test's domain, rclpy."""
    env = dict(os.environ)
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', RMW_IMPLEMENTATION='rmw_cyclonedds_cpp',
               CYCLONEDDS_URI=(ROOT / 'config' / 'cyclonedds-localhost.xml').as_uri(),
               ROS_DOMAIN_ID=os.environ['ROS_DOMAIN_ID'], FRF_IDENT_MIDDLEWARE='rclpy',
               PYTHONUNBUFFERED='1',
               PYTHONPATH=os.pathsep.join([str(ROOT)] + [
                   p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]))
    return env
