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
