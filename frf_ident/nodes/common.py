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
"""Shared plumbing of the node processes: parameters, stamps, signals, readiness, CDR bytes."""
from __future__ import annotations

import os
import signal
import sys
import threading
import time
from typing import Any, Optional, Sequence

from frf_ident import middleware as mw
from frf_ident.app.excitation_settings import SessionSettings
from frf_ident.errors import FrfIdentInputError

#: Topic defaults (docs/CONTRACT.md §3); every one is a node parameter.
TOPICS = {
    'joint_states_topic': '/joint_states',
    'effort_topic': '/effort_controller/commands',
    'velocity_topic': '/velocity_controller/commands',
    'excitation_topic': '/frf/excitation',
    'experiment_topic': '/frf/experiment',
    'clock_topic': '/clock',
    'progress_topic': '/frf/progress',
    'arming_topic': '/frf/arming',
    'heartbeat_topic': '/frf/heartbeat',
    'live_topic': '/frf/live',            # + /frf, /distortion, /summary (docs/live.md)
    'warnings_topic': '/frf/warnings',
}
#: the live frames under ``live_topic`` (frf_ident/io/live_frame.py)
LIVE_FRAMES = ('frf', 'distortion', 'summary')
READY = mw.READY
#: default of the ``lockstep`` parameter of every node: free-running, the mode that is safe on a
#: real robot; the simulation (config/frf_ident.yaml, launch sim:=true, app.graph) sets true
LOCKSTEP = SessionSettings.lockstep
#: deep queues: lockstep references are published ahead, recorders must never drop a sample
DEEP = 20000
#: a second SIGINT/SIGTERM within this many wall s of the first is the same Ctrl-C (a terminal
#: signals the whole process group, and ``ros2 launch`` forwards its own copy): ignored; a
#: later one stops the node at once
SAME_SIGNAL_S = 2.0


class Refused(Exception):
    """A parameter combination a node refuses to start with (one line, exit 2)."""


def refuse_lockstep_without_sim(node: Any, lockstep: bool) -> None:
    """Lockstep exists only with the simulated plant, which is the /clock source."""
    sim_time = node.get_parameter('use_sim_time').value
    if lockstep and not sim_time:
        raise Refused('lockstep: true needs the simulated plant (use_sim_time: true); on a real '
                      'robot set lockstep: false (ros2 launch ... sim:=false does)')


def run_node(name: str, wiring: Any, argv: Optional[Sequence[str]] = None, *,
             use_sim_time: Optional[bool] = None) -> int:
    """
    Create node ``name``, wire it with ``wiring(node)``, announce readiness and spin.

    Parameters
    ----------
    name
        Node name.
    wiring
        Class (or callable) taking the node; its ``close()`` runs at shutdown, its
        ``spin(stop_event)`` replaces the default spin when it has one.
    argv
        Command line (``--ros-args`` ...); default sys.argv.
    use_sim_time
        Forced value (the plant is the clock source), None: from parameters.

    Returns
    -------
    int
        0, or 2 when the node refused its parameters (one line on stderr).

    """
    try:
        # our reader first: rcl's parser fails on a bad --params-file with a traceback
        mw.check_params_files(list(sys.argv if argv is None else argv), name)
    except FrfIdentInputError as exc:
        print(f'{name}: bad parameter: {exc}', file=sys.stderr, flush=True)
        return 2
    stop = StopOnSignal()        # before rclpy: its own handlers stay off (middleware.init)
    init(argv)
    try:
        try:
            node = mw.create_node(name, use_sim_time=use_sim_time)
            stop.nodes.append(node)
            wired = wiring(node)
        except Refused as exc:
            print(f'{name}: refused: {exc}', file=sys.stderr, flush=True)
            return 2
        except (FrfIdentInputError, ValueError) + mw.parameter_errors() as exc:
            print(f'{name}: bad parameter: {exc}', file=sys.stderr, flush=True)
            return 2
        stop.starting = False
        announce_ready(name)
        try:
            spin = getattr(wired, 'spin', None)
            if spin is not None:
                spin(stop.event)
            else:
                mw.spin(node, stop.event)
        finally:
            close = getattr(wired, 'close', None)
            if close is not None:
                close()
    except SystemExit:
        pass                         # a signal during start-up, or a second one: a normal end
    finally:
        mw.shutdown()
    return leave(0)


def leave(code: int) -> int:
    """
    End a node process at once with ``code`` once its work is done (bag closed, DDS left).

    The interpreter's own finalisation (numba, llvmlite, rclpy modules) took 4-5 s on a loaded
    2-core PC, so ``ros2 launch`` escalated Ctrl-C to SIGTERM after its 5 s and logged the
    node as died (issue 44). Outside a node process (a test calling ``main``) it returns.
    """
    from frf_ident.nodes import is_node_process
    if is_node_process():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


def control_qos(lockstep: bool) -> Any:
    """
    Return the QoS of what a node acts on (joint states, commands).

    Lockstep: deep (every sample is consumed in order). Free-running: the newest only, as in a
    real-time loop: a node that fell behind acts on the present, never works through a backlog
    (which would add a growing delay to the control loop).
    """
    return mw.qos_default(DEEP if lockstep else 1)


def param(node: Any, name: str, default: Any) -> Any:
    """Declare ``name`` with ``default`` and return its value."""
    return node.declare_parameter(name, default).value


def topics(node: Any, which: Sequence[str]) -> dict[str, str]:
    return {k: param(node, k, TOPICS[k]) for k in which}


def stamp_ns(msg: Any) -> int:
    s = msg.header.stamp
    return s.sec * 1_000_000_000 + s.nanosec


def set_stamp(msg: Any, ns: int) -> None:
    st = msg.header.stamp
    st.sec, st.nanosec = divmod(int(ns), 1_000_000_000)


def to_cdr(msg: Any) -> bytes:
    """CDR bytes (with encapsulation header) of a received message, as rosbag2 stores them."""
    if mw.backend_name() == 'dds':
        return msg.serialize()
    from rclpy.serialization import serialize_message  # rclpy backend only
    return serialize_message(msg)


class StopOnSignal:
    """
    SIGINT/SIGTERM set ``event`` and wake the given nodes.

    During start-up, and at a second signal, the process exits 0 at once (SystemExit: the
    finally blocks still run).
    """

    def __init__(self) -> None:
        self.event = threading.Event()
        self.nodes: list[Any] = []
        self.callbacks: list[Any] = []
        #: True while the node is being created and wired (seconds under load: model, numba
        #: kernels, discovery): a signal then stops it at once, the finally blocks close what
        #: is open (the estimator's bag), so launch never has to escalate to SIGTERM
        self.starting = True
        self.t_signal = 0.0
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, self._handler)
            signal.signal(signal.SIGTERM, self._handler)

    def _handler(self, signum: int, frame: Any) -> None:
        now = time.monotonic()
        if self.event.is_set() and not self.starting and now - self.t_signal < SAME_SIGNAL_S:
            return                   # the same Ctrl-C again (terminal's group + launch's copy)
        if self.starting or self.event.is_set():
            self.event.set()
            raise SystemExit(0)      # Ctrl-C is a normal end: exit 0, no traceback
        self.t_signal = now
        self.event.set()
        for cb in self.callbacks:
            cb()
        for n in self.nodes:
            wake = getattr(n, 'wake', None)
            if wake is not None:
                wake()


def announce_ready(name: str) -> None:
    print(f'{READY} {name}', flush=True)


def init(argv: Optional[Sequence[str]]) -> list[str]:
    args = list(sys.argv if argv is None else argv)
    mw.init(args)
    return args
