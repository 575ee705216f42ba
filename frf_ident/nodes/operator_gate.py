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
The excitation node's arming wiring: /frf/arming, /frf/heartbeat, the token, request logs.

Parameters (read once): ``arming`` ('token' or 'off'; '' = 'off' in lockstep, the simulation,
and 'token' free-running, a robot), ``heartbeat_timeout_ms``, ``arming_topic``,
``heartbeat_topic``. The logic is :class:`frf_ident.app.arming.ArmingGate`; this module only
wires it.
"""
from __future__ import annotations

import sys
import threading
from typing import Any, Callable, Optional

from frf_ident import middleware as mw
from frf_ident.app.arming import ArmingGate, ArmingSettings, HEARTBEAT_TIMEOUT_MS
from frf_ident.app.run_requests import RunRequest
from frf_ident.middleware.caller import wall_time_text
from frf_ident.nodes import common as c

__all__ = ['OperatorGate']


class OperatorGate:
    """
    Arming of one excitation node: announce, take heartbeats, check starts, stop runs.

    Parameters
    ----------
    node : Any
        The excitation node.
    lockstep : bool
        The node's ``lockstep`` (the default mode follows it).
    log : callable
        ``log(level, text)`` of the node.

    """

    def __init__(self, node: Any, lockstep: bool, log: Callable[[str, str], None]) -> None:
        mode = c.param(node, 'arming', '') or ('off' if lockstep else 'token')
        timeout = c.param(node, 'heartbeat_timeout_ms', HEARTBEAT_TIMEOUT_MS)
        self.gate = ArmingGate(ArmingSettings(mode, float(timeout)), node.get_name())
        self.log = log
        t = c.topics(node, ('arming_topic', 'heartbeat_topic'))
        self.String = mw.msg('std_msgs/msg/String')
        self.pub = node.create_publisher(self.String, t['arming_topic'],
                                         mw.qos_transient_local(1))
        self._stop = threading.Event()
        self._spinner: Optional[threading.Thread] = None
        self.hb_node: Any = None
        name = node.get_name()
        if self.gate.required:
            self._listen(node, t['heartbeat_topic'])
            # the console only: a logger line would go out on /rosout to the whole domain
            print(f'{name}: ARMING TOKEN of this start: {self.gate.token}\n{name}: runs are '
                  'refused until the operator runs `ros2 run frf_ident operator` on this PC '
                  'and types it', file=sys.stderr, flush=True)
        elif not lockstep:
            log('warn', 'arming: off on a free-running graph: any participant of the domain '
                        'can start motion (only for a simulated plant)')
        self.pub.publish(self.String(data=self.gate.announcement()))

    def _listen(self, node: Any, topic: str) -> None:
        """
        Take heartbeats on a node and thread of their own.

        The excitation node's executor works through a backlog of joint states after it
        planned a run (seconds without taking any): heartbeats taken there came 280 ms late
        on a loaded 2-core PC and aborted good runs. Their own executor judges the operator,
        not the node's load (the joint-state watchdog judges that).
        """
        self.hb_node = mw.create_node(f'{node.get_name()}_arming', use_sim_time=False,
                                      namespace=node.get_namespace(), global_arguments=False)
        self.hb_node.create_subscription(self.String, topic, self._on_heartbeat,
                                         mw.qos_default(1))
        self._spinner = threading.Thread(target=mw.spin, args=(self.hb_node, self._stop),
                                         daemon=True, name='operator heartbeat')
        self._spinner.start()

    def _on_heartbeat(self, msg: Any) -> None:
        reason = self.gate.on_heartbeat(msg.data)
        if reason is not None:
            self.log('warn', reason)

    def close(self) -> None:
        """
        Stop taking heartbeats and wait for their thread (it spins in 0.1 s steps).

        Joined before the middleware shuts down: a thread still inside rclpy's wait set at
        shutdown raised, and the interpreter's exit then aborted the process (SIGABRT,
        "terminate called without an active exception") instead of exiting 0.
        """
        self._stop.set()
        if self._spinner is not None:
            self._spinner.join(timeout=2.0)

    def check(self) -> None:
        """Raise NotArmed when a run may not start now (ArmingGate.check)."""
        self.gate.check()

    def run_started(self, run: Any) -> None:
        """Keep ``run`` alive on the heartbeat from now on."""
        self.gate.run_started(run.id)

    def watch(self, session: Any) -> Optional[str]:
        """
        Watchdog tick: announce a changed state; abort the session's run without heartbeat.

        Parameters
        ----------
        session : ExcitationSession
            The node's session (its current ``run``).

        Returns
        -------
        str or None
            The abort reason when this tick aborted the run.

        """
        text = self.gate.changed_announcement()
        if text is not None:
            self.pub.publish(self.String(data=text))
        run = session.run
        running = run is not None and not run.done.is_set()
        abort, summary = self.gate.watch(None if run is None else run.id, running)
        if summary is not None:
            self.log('info', summary)
        if abort is not None:
            session.abort(abort)
        return abort

    def log_request(self, caller: Any, accepted: bool, detail: str) -> str:
        """
        Log one run request with its caller and time; return the caller's description.

        Parameters
        ----------
        caller : Caller
            From the middleware.
        accepted : bool
            Whether it started (or stopped) a run.
        detail : str
            The run, or why it was refused.

        Returns
        -------
        str
            ``caller.describe()``, for the reply.

        """
        who = caller.describe()
        line = RunRequest(caller.service, wall_time_text(caller.received_ns), who, accepted,
                          detail).line()
        self.log('info' if accepted else 'warn', line)
        return who
