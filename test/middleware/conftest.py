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
"""DDS test environment: loopback only, a random ROS domain per test module, DDS backend."""

import os
from pathlib import Path

import pytest

CONFIG_URI = (Path(__file__).resolve().parents[2] / 'config' / 'cyclonedds-localhost.xml').as_uri()


def loopback_env(domain_id: int) -> dict[str, str]:
    """Environment for this process and every DDS peer process a test starts."""
    env = dict(os.environ)
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', CYCLONEDDS_URI=CONFIG_URI,
               ROS_DOMAIN_ID=str(domain_id), FRF_IDENT_MIDDLEWARE='dds')
    return env


@pytest.fixture(scope='module')
def domain_env(new_domain):
    """Put this process on a fresh domain of its own and tear the participant down after."""
    from frf_ident.middleware import dds_backend
    dds_backend.shutdown()
    saved = dict(os.environ)
    env = loopback_env(new_domain())
    os.environ.update(env)
    try:
        yield env
    finally:
        dds_backend.shutdown()
        os.environ.clear()
        os.environ.update(saved)
