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
The excitation session behind ``excitation_node``: procedures streamed over the node graph.

:class:`ExcitationSession` owns the run state (operating point, the streamed
:class:`~frf_ident.core.excitation.engine.PhaseStream`, the chirp iteration, the watchdog
decision); it does no I/O itself. The node hands it every joint state (:meth:`on_state`) and
a periodic :meth:`watch`; the session answers through the
:class:`~frf_ident.app.excitation_run.Outputs` it was given (publish a reference, a
descriptor, a progress or end event, a log line).

This module holds the session's state; its parts, one concern each:

- :mod:`frf_ident.app.excitation_plan` -- planning: a procedure planned, checked (position
  bound, predicted peak torque) and started, or cut short at its uncertainty target;
- :mod:`frf_ident.app.excitation_stream` -- running: joint states in, references and
  descriptors out (lockstep or free-running timing);
- :mod:`frf_ident.app.excitation_watch` -- watching: stale joint states, the joint-state rate,
  the abort that ramps the reference to zero;
- :mod:`frf_ident.app.excitation_settings` (the node's parameters, the safety limits),
  :mod:`frf_ident.app.excitation_run` (what the session sends, one run's record) and
  :mod:`frf_ident.app.excitation_torque` (which joint state carries a sample's torque, gaps
  filled).
"""
from __future__ import annotations

from collections import deque
import math
import threading
import time
from typing import Callable, Optional

from frf_ident.app.excitation_plan import SessionPlanning
from frf_ident.app.excitation_run import Outputs, Run
from frf_ident.app.excitation_settings import RATE_WINDOW, SessionSettings
from frf_ident.app.excitation_stream import SessionStreaming
from frf_ident.app.excitation_torque import torque_sample_offset
from frf_ident.app.excitation_watch import SessionWatchdog
from frf_ident.core.excitation.chirp_iteration import ChirpIteration
from frf_ident.core.excitation.engine import PhaseEngine
from frf_ident.core.model.params import RobotParams
from frf_ident.core.simulation.controller import PIVelocity
import numpy as np

__all__ = ['ExcitationSession']


class ExcitationSession(SessionPlanning, SessionStreaming, SessionWatchdog):
    """
    Procedures streamed as references, one joint state at a time.

    Parameters
    ----------
    settings
        Node parameters.
    joints
        Joint names (model order).
    dt
        Sample time [s].
    torque_limit
        Per joint [N m] (chirp iteration scaling and refusal).
    out
        Where references, descriptors, events and log lines go.
    model
        The nominal model and its controller: each plan's peak torque is predicted on it
        before the plan runs (refused at 0.95 of a limit). None: no prediction (only the
        runtime saturation abort guards the torque).
    sim_now_ns
        Lockstep: the simulation clock [ns] (the node clock on /clock); staleness is judged
        on it. None: on the stamps of the joint states alone.

    """

    def __init__(self, settings: SessionSettings, joints: list[str], dt: float,
                 torque_limit: np.ndarray, out: Outputs,
                 model: Optional[tuple[RobotParams, PIVelocity]] = None,
                 sim_now_ns: Optional[Callable[[], int]] = None) -> None:
        self.sim_now_ns = sim_now_ns
        self.s = settings
        self.joints = list(joints)
        self.n = len(self.joints)
        self.dt = float(dt)
        self.fs = 1.0 / self.dt
        self.dt_ns = int(round(self.dt * 1e9))
        self.torque_limit = np.asarray(torque_limit, float)
        self.out = out
        self.model = model
        self.lookahead = int(settings.lookahead) if settings.lockstep else 1
        self.lag = 0 if settings.lockstep else 1       # held samples: next_k - k_js allowed
        self.offset = torque_sample_offset(settings.lockstep)
        self.bound = math.radians(settings.plan_bound_deg)
        self.live_bound = math.radians(settings.live_position_bound_deg)
        self.lock = threading.RLock()
        self.k_js = -1
        #: free-running: samples between consecutive joint states the node saw
        self.steps: deque[int] = deque(maxlen=RATE_WINDOW)
        self.q_js: Optional[np.ndarray] = None
        self.q0: Optional[np.ndarray] = None
        self.engine: Optional[PhaseEngine] = None
        self.t_js = time.monotonic()
        self.next_k = -1
        self.last_ref = np.zeros(self.n)
        self.run: Optional[Run] = None
        self.runs = 0
        self.chirp: Optional[ChirpIteration] = None
