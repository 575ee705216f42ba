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
Arming and the operator's enabling heartbeat of the excitation node (docs/ros2.md, "Arming").

On a real robot only the person at the robot starts motion. At start-up the excitation node
opens a session: a random nonce (public, announced on /frf/arming) and a one-time token
(secret: printed on the node's own console only, never logged to /rosout). The operator
console (``ros2 run frf_ident operator``) is given the token and sends a heartbeat every
``heartbeat_timeout_ms / HEARTBEATS_PER_TIMEOUT`` on /frf/heartbeat: the session, a console
id, a sequence number and an HMAC-SHA256 of them keyed with the token. The node is armed
while a heartbeat that verifies came within ``heartbeat_timeout_ms``: a run request is refused
otherwise, and a running procedure is aborted (ramped to zero as /frf/abort does) when the
heartbeats stop.

A replayed bag can neither arm a node nor keep a run alive: a recorded heartbeat carries the
session it was recorded in (a later start has another nonce and token: its MAC does not
verify), and within that session its sequence number was seen already (each console's must
increase). The token never goes on the wire, so whoever sees only the DDS traffic cannot make
a heartbeat. The announcement carries a MAC too, so a console knows a replayed or foreign
announcement from its own node's.

No I/O here: the node wires its topics and watchdog thread to :class:`ArmingGate`; the
heartbeat's format and the console's side are frf_ident/app/heartbeat.py.
"""
from __future__ import annotations

from dataclasses import dataclass
import hmac
import json
import math
import secrets
import threading
import time
from typing import Callable, Optional

from frf_ident.app.heartbeat import announcement_mac, heartbeat_mac, make_token
from frf_ident.errors import DesignError, NotArmed

__all__ = ['ArmingGate', 'ArmingSettings', 'MODES']

#: ``token``: runs need the operator's heartbeat (a real robot, ``sim:=false``);
#: ``off``: no arming (the simulation, as before issue 56)
MODES = ('token', 'off')
#: How long [ms] a run goes on after the newest heartbeat. The node takes heartbeats in its
#: executor between joint states; on this 2-core PC without a real-time kernel its longest
#: joint-state gap in a free-running run was 69 ms (docs/real_robot.md, "stale_samples"), so
#: a heartbeat may be taken up to ~70 ms late. With one every 50 ms (HEARTBEATS_PER_TIMEOUT)
#: three may be late or lost before a run stops; a released console stops the robot within
#: 250 ms + abort_ramp_s. The longest gap each run saw is logged at its end
#: (test/ros/test_ros_arming.py prints it).
HEARTBEAT_TIMEOUT_MS = 250.0
#: heartbeats the console sends per timeout
HEARTBEATS_PER_TIMEOUT = 5
#: the accepted range of ``heartbeat_timeout_ms``: below 50 ms the node's own stalls abort good
#: runs; above 1 s a released console leaves the robot moving too long to call it enabling
TIMEOUT_RANGE_MS = (50.0, 1000.0)


@dataclass(frozen=True)
class ArmingSettings:
    """
    Arming parameters of the excitation node.

    Parameters
    ----------
    mode : str, optional
        One of :data:`MODES`; default 'token'.
    heartbeat_timeout_ms : float, optional
        Wall time [ms] a run goes on after the newest valid heartbeat.

    """

    mode: str = 'token'
    heartbeat_timeout_ms: float = HEARTBEAT_TIMEOUT_MS

    def __post_init__(self) -> None:
        """Refuse an unknown mode or a timeout outside TIMEOUT_RANGE_MS (DesignError)."""
        if self.mode not in MODES:
            raise DesignError(f'arming={self.mode!r}: expected one of {list(MODES)}')
        lo, hi = TIMEOUT_RANGE_MS
        t = self.heartbeat_timeout_ms
        if not (math.isfinite(t) and lo <= t <= hi):
            raise DesignError(f'heartbeat_timeout_ms={t}: expected {lo:g} to {hi:g} ms')

    @property
    def period_ms(self) -> float:
        """Return the operator console's heartbeat period [ms]."""
        return self.heartbeat_timeout_ms / HEARTBEATS_PER_TIMEOUT


class ArmingGate:
    """
    The excitation node's arming state: heartbeats in, refusals and abort reasons out.

    Thread-safe: heartbeats come from the node's executor, :meth:`watch` from its watchdog
    thread, :meth:`refusal` from a service callback.

    Parameters
    ----------
    settings : ArmingSettings
        Mode and timeout.
    node : str, optional
        The node's name (in the announcement).
    clock : callable, optional
        Monotonic time [s]; default ``time.monotonic``.

    """

    def __init__(self, settings: ArmingSettings, node: str = 'excitation_node',
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.s = settings
        self.node = node
        self.clock = clock
        #: the session nonce (public) and the one-time token (secret; None with mode 'off')
        self.session = secrets.token_hex(16)
        self.token = make_token() if settings.mode == 'token' else None
        self._lock = threading.Lock()
        self._valid_t: Optional[float] = None      # when the newest valid heartbeat came
        self._operator = ''
        self._seq: dict[str, int] = {}             # console id -> newest sequence number
        self._rejected = ''                        # why the newest refused heartbeat was
        self._rejected_kind = ''                   # logged once per kind (a replay: 20/s)
        self._armed = settings.mode == 'off'       # as last announced
        self._watched: Optional[int] = None        # id of the run the heartbeat keeps alive
        self._since = 0.0
        self._max_gap = 0.0

    @property
    def required(self) -> bool:
        """Return whether runs need the operator's heartbeat (mode 'token')."""
        return self.token is not None

    # -- heartbeats --------------------------------------------------------------------------
    def on_heartbeat(self, text: str) -> Optional[str]:
        """
        Take one heartbeat message.

        Parameters
        ----------
        text : str
            The JSON of /frf/heartbeat.

        Returns
        -------
        str or None
            Why it was refused, when its kind (format, session, MAC, sequence) differs from
            the previous refusal's (to log once); None when it was taken (or refused again
            for the same kind of reason).

        """
        if not self.required:
            return None
        now = self.clock()
        refused = self._verify(text)
        with self._lock:
            if refused is None:
                if self._valid_t is not None and self._watched is not None:
                    self._max_gap = max(self._max_gap, now - max(self._valid_t, self._since))
                self._valid_t = now
                return None
            kind, reason = refused
            new = kind != self._rejected_kind
            self._rejected, self._rejected_kind = reason, kind
        return reason if new else None

    def _verify(self, text: str) -> Optional[tuple[str, str]]:
        """Return None for a valid heartbeat, else (kind, reason)."""
        try:
            hb = json.loads(text)
            session, console = str(hb['session']), str(hb['console'])
            seq, operator, mac = int(hb['seq']), str(hb['operator']), str(hb['mac'])
        except (ValueError, KeyError, TypeError) as exc:
            return 'format', f'heartbeat refused: not a heartbeat ({type(exc).__name__}: {exc})'
        if session != self.session:
            return 'session', ('heartbeat refused: it belongs to another session (a replayed '
                               'bag, or a console of an earlier start of the node)')
        if not hmac.compare_digest(mac, heartbeat_mac(self.token, session, console, seq,
                                                      operator)):
            return 'mac', (f'heartbeat refused: its MAC does not verify (console of '
                           f'{operator!r} was given a wrong token)')
        with self._lock:
            last = self._seq.get(console, 0)
            if seq <= last:
                return 'seq', (f'heartbeat refused: #{seq} of console {console} came after '
                               f'#{last} (replayed or duplicated)')
            self._seq[console] = seq
            self._operator = operator
        return None

    # -- decisions ---------------------------------------------------------------------------
    def _age(self, now: float) -> Optional[float]:
        return None if self._valid_t is None else now - self._valid_t

    def refusal(self) -> Optional[str]:
        """
        Return why a run may not start now, or None when armed.

        Returns
        -------
        str or None
            The reason (what is missing and what to do).

        """
        if not self.required:
            return None
        with self._lock:
            age = self._age(self.clock())
            rejected = f'; last {self._rejected}' if self._rejected else ''
        limit = self.s.heartbeat_timeout_ms
        if age is None:
            return ('not armed: no operator heartbeat yet (on the robot PC run `ros2 run '
                    f'frf_ident operator` and type the token {self.node} printed at start)'
                    + rejected)
        if 1e3 * age > limit:
            return (f'not armed: the operator heartbeat stopped {1e3 * age:.0f} ms ago '
                    f'(limit heartbeat_timeout_ms={limit:g})' + rejected)
        return None

    def check(self) -> None:
        """
        Raise :class:`NotArmed` when a run may not start now.

        Raises
        ------
        NotArmed
            With :meth:`refusal`'s reason.

        """
        reason = self.refusal()
        if reason is not None:
            raise NotArmed(reason)

    def run_started(self, run_id: int) -> None:
        """
        Watch run ``run_id`` from now on: its heartbeat clock starts now.

        The node took no heartbeats while it planned the run (seconds): the run may go on
        for one timeout after its start without a new one, as after any heartbeat.

        Parameters
        ----------
        run_id : int
            The started run's id.

        """
        with self._lock:
            self._watched, self._since, self._max_gap = run_id, self.clock(), 0.0

    def watch(self, run_id: Optional[int], running: bool) -> tuple[Optional[str], Optional[str]]:
        """
        Watchdog tick for the node's current run.

        Parameters
        ----------
        run_id : int or None
            The node's current run (None: none yet).
        running : bool
            Whether it still runs.

        Returns
        -------
        abort : str or None
            Why the run must stop now (the heartbeat stopped), else None.
        summary : str or None
            Once a watched run ended: its longest heartbeat gap, for the log.

        """
        if not self.required or run_id is None or run_id != self._watched:
            return None, None
        now = self.clock()
        with self._lock:
            if not running:
                self._watched = None
                return None, (f'operator heartbeat of run {run_id}: longest gap '
                              f'{1e3 * self._max_gap:.0f} ms (limit '
                              f'heartbeat_timeout_ms={self.s.heartbeat_timeout_ms:g})')
            since = max(self._valid_t or self._since, self._since)
            age = now - since
            operator = self._operator
        if 1e3 * age <= self.s.heartbeat_timeout_ms:
            return None, None
        return (f'operator heartbeat lost: none for {1e3 * age:.0f} ms (limit '
                f'heartbeat_timeout_ms={self.s.heartbeat_timeout_ms:g}; last from '
                f'{operator or "nobody"})'), None

    def changed_announcement(self) -> Optional[str]:
        """
        Return a new announcement when the armed state changed since the last one, else None.

        Returns
        -------
        str or None
            JSON for /frf/arming.

        """
        armed = self.refusal() is None
        with self._lock:
            if armed == self._armed:
                return None
            self._armed = armed
        return self.announcement()

    def announcement(self) -> str:
        """
        Return the JSON of /frf/arming: session, mode, timing, state, and the MAC.

        Returns
        -------
        str
            ``{"session", "node", "arming", "heartbeat_timeout_ms", "heartbeat_period_ms",
            "armed", "reason", "mac"}`` (``mac`` empty with mode 'off').

        """
        reason = self.refusal()
        mac = announcement_mac(self.token, self.session, self.node) if self.required else ''
        return json.dumps({'session': self.session, 'node': self.node, 'arming': self.s.mode,
                           'heartbeat_timeout_ms': self.s.heartbeat_timeout_ms,
                           'heartbeat_period_ms': self.s.period_ms,
                           'armed': reason is None, 'reason': reason, 'mac': mac},
                          sort_keys=True)
