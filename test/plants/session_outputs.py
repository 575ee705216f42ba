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
"""The outputs an ExcitationSession writes to, kept for the tests that drive a session by hand."""
from __future__ import annotations

import numpy as np


class RecordingOutputs:
    """Keep every reference by its sample and every log line; drop events and progress."""

    def __init__(self) -> None:
        self.refs: dict[int, np.ndarray] = {}
        self.logs: list[str] = []

    def reference(self, k, r, x) -> None:
        self.refs[k] = np.array(r, float)

    def experiment(self, text) -> None:
        pass

    def progress(self, event) -> None:
        pass

    def log(self, level, text) -> None:
        self.logs.append(text)
