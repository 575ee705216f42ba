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
What the excitation session sends and the record of one run.

:class:`Outputs` is the node's side (publishers and its logger); :class:`Run` one streamed
procedure with its state; :func:`event_json` the text of an experiment event.
"""
from __future__ import annotations

import json
import threading
import time
from typing import Any, Callable, Optional, Protocol

from frf_ident.core.excitation.engine import PhaseStream
import numpy as np

__all__ = ['event_json', 'Outputs', 'Run']


class Outputs(Protocol):
    """What the session sends; the node implements it with publishers and its logger."""

    def reference(self, k: int, r: np.ndarray, x: np.ndarray) -> None:
        """
        Send the reference of one sample.

        Parameters
        ----------
        k : int
            Sample index; the sample's stamp is k dt.
        r : ndarray, shape (n,)
            Velocity reference [rad/s] per joint (model joint order).
        x : ndarray, shape (n,)
            Excitation part of ``r`` [rad/s].

        """

    def experiment(self, text: str) -> None:
        """
        Send an experiment descriptor or event.

        Parameters
        ----------
        text : str
            JSON text: a ``Segment.descriptor`` or a ``procedure_end`` / ``aborted`` event.

        """

    def progress(self, event: dict[str, Any]) -> None:
        """
        Send a progress event.

        Parameters
        ----------
        event : dict
            JSON-serialisable event: ``event`` ('started', 'progress' or 'finished'), ``run``,
            ``procedure``, ``samples``, ``of``, ``fraction``, ``wall_s`` and, when finished,
            ``success`` with ``result`` or ``error`` (and ``aborted`` after an abort).

        """

    def log(self, level: str, text: str) -> None:
        """
        Write a log line.

        Parameters
        ----------
        level : str
            Severity: 'info', 'warn' or 'error'.
        text : str
            The line.

        """


class Run:
    """One streamed procedure."""

    def __init__(self, run_id: int, name: str, stream: PhaseStream, collect: bool,
                 on_end: Callable[['Run'], dict]) -> None:
        self.id, self.name, self.stream, self.collect = run_id, name, stream, collect
        self.on_end = on_end
        self.start_k = stream.k
        #: False until the stream starts: free-running, at the first joint state after the
        #: start (the newest one known when the service was called may be seconds old)
        self.anchored = False
        self.u: dict[int, np.ndarray] = {}     # segment index -> torque (collect)
        self.end_k: Optional[int] = None
        self.done = threading.Event()
        self.result: Optional[dict] = None
        self.error: Optional[str] = None
        self.max_gap = 0.0
        self.t0 = time.monotonic()
        self.t_progress = self.t0


def event_json(**d: Any) -> str:
    """Return the JSON text of an experiment event (keys sorted)."""
    return json.dumps(d, sort_keys=True)
