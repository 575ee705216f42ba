"""DDS test environment: loopback only, a random ROS domain per test module, DDS backend."""

import os
from pathlib import Path
import random

import pytest

CONFIG_URI = (Path(__file__).resolve().parents[2] / 'config' / 'cyclonedds-localhost.xml').as_uri()


def loopback_env(domain_id: int) -> dict[str, str]:
    """Environment for this process and every DDS peer process a test starts."""
    env = dict(os.environ)
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', CYCLONEDDS_URI=CONFIG_URI,
               ROS_DOMAIN_ID=str(domain_id), FRF_IDENT_MIDDLEWARE='dds')
    return env


@pytest.fixture(scope='module')
def domain_env():
    """Put this process on a fresh random domain (100..200) and tear the participant down after."""
    from frf_ident.middleware import dds_backend
    dds_backend.shutdown()
    saved = dict(os.environ)
    env = loopback_env(random.randint(100, 200))
    os.environ.update(env)
    try:
        yield env
    finally:
        dds_backend.shutdown()
        os.environ.clear()
        os.environ.update(saved)
