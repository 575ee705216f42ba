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
The live estimate of an offline run (``frf-ident identify``) for a person and a viewer.

:class:`LiveView` takes the runner's estimate after every whole MIMO period
(``run_identification(on_estimate=...)``): its status line goes to one updating terminal line
(:class:`frf_ident.app.console.LiveLine`), its frames, progress event and early warnings to
a Foxglove WebSocket when a port is given (frf_ident/io/foxglove_server.py), as the
excitation node publishes them on a robot.
"""
from __future__ import annotations

import logging
import threading
from typing import Any, Optional

from frf_ident.app.console import LiveLine
from frf_ident.app.live import EstimateOut
from frf_ident.core.estimation.early_warnings import WarningMonitor
from frf_ident.core.estimation.live import LiveEstimate
from frf_ident.core.estimation.target import UncertaintyTarget
import numpy as np

__all__ = ['LiveView']

_log = logging.getLogger(__name__)


class LiveView:
    """
    The status line and, optionally, the Foxglove WebSocket of an offline run.

    Parameters
    ----------
    joints : list of str
        The robot's joints, in model order.
    torque_limit : ndarray, shape (n,)
        Per axis [N m] (the early warnings).
    target : UncertaintyTarget, optional
        The run's target (its sd and periods left in the line).
    foxglove_port : int, optional
        Serve on ws://127.0.0.1:PORT (0: a free port); None: no server.
    line : LiveLine, optional
        Where the status goes (default: stdout's).

    """

    def __init__(self, joints: list[str], torque_limit: np.ndarray,
                 target: Optional[UncertaintyTarget] = None,
                 foxglove_port: Optional[int] = None, line: Optional[LiveLine] = None) -> None:
        self.line = line or LiveLine()
        self.t_ns = 0
        self.warnings = WarningMonitor(joints, torque_limit)
        self.server: Any = None
        if foxglove_port is not None:
            from frf_ident.io.foxglove_server import FoxgloveLive
            self.server = FoxgloveLive(foxglove_port, name='frf-ident identify')
        self.out = EstimateOut(target or UncertaintyTarget(), self)

    def __call__(self, est: LiveEstimate) -> None:
        """Take one estimate of the runner (its ``on_estimate``)."""
        self.t_ns = int(round(est.t * 1e9))
        self.out.publish(est)
        for w in self.warnings.estimate(est):
            self.warning(w.to_dict())

    # -- LiveOutputs ---------------------------------------------------------------------------
    def live_frame(self, topic: str, frame: Any) -> None:
        """Serve a frame on /frf/live/<topic> (nothing without a server)."""
        if self.server is not None:
            self.server.frame(topic, frame, self.t_ns)

    def warning(self, event: dict) -> None:
        """Log an early warning and serve it on /frf/warnings."""
        self.line.end()
        _log.warning(f"early warning ({event['kind']}): {event['message']}")
        if self.server is not None:
            self.server.text('/frf/warnings', event, self.t_ns)

    def progress(self, event: dict) -> None:
        """Show the status line; serve the event on /frf/progress."""
        self.line.update(event['line'])
        if self.server is not None:
            self.server.text('/frf/progress', event, self.t_ns)

    def log(self, level: str, text: str) -> None:
        """Keep the node's log lines at DEBUG (the status line shows them already)."""
        _log.debug(text)

    # -- the end -------------------------------------------------------------------------------
    def end(self) -> None:
        """Close the status line (what is printed next starts on its own line)."""
        self.line.end()

    def serve_until_interrupted(self, stop: Optional[threading.Event] = None) -> None:
        """
        Keep serving the newest messages until Ctrl-C (or ``stop``), then close the server.

        Parameters
        ----------
        stop : threading.Event, optional
            Ends the wait (tests); default: only Ctrl-C.

        """
        if self.server is None:
            return
        stop = stop or threading.Event()
        try:
            while not stop.wait(0.2):
                pass
        except KeyboardInterrupt:
            pass
        finally:
            self.server.close()
