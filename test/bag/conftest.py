"""Shared fixtures of the bag tests."""
from __future__ import annotations

from pathlib import Path

from bag_synth import make_recording
from frf_ident.bag import write_recording
from frf_ident.core.recording import Recording
import pytest


@pytest.fixture(scope='session')
def clean_rec() -> Recording:
    return make_recording()


@pytest.fixture(scope='session')
def clean_bag(tmp_path_factory: pytest.TempPathFactory, clean_rec: Recording) -> Path:
    return write_recording(clean_rec, tmp_path_factory.mktemp('bags') / 'clean')
