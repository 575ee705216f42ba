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
excitation_node: streams the identification procedures as velocity references.

One node, one process. Publishes /velocity_controller/commands (Float64MultiArray), the
excitation part with its sample stamp on /frf/excitation (JointState), ``Segment.descriptor``
JSON and the ``procedure_end`` / ``aborted`` events on /frf/experiment (String, reliable,
transient-local) and progress on /frf/progress (String JSON, transient-local: ``started``,
``progress`` every ``progress_period_s``, ``finished`` with the result). Subscribes
/joint_states.

Services (std_srvs/Trigger), answering once the plan is made and checked (seconds; a start
during a run is refused at once) with ``{"accepted": true, "run": id, ...}``:
``/frf/run_multisine`` starts the multisine procedure, ``/frf/run_iteration`` one step of the
chirp iteration (its ``finished`` event carries ``iteration``, ``error_db``, ``converged``).
``foxglove_port`` (default 0: none) serves the live stream, progress, warnings and joint
states on a Foxglove WebSocket at ws://127.0.0.1:PORT (frf_ident/io/foxglove_server.py; the
``[foxglove]`` extra), for the DDS backend where no foxglove_bridge runs.
``/frf/abort`` stops the running procedure (reference ramped to zero within ``abort_ramp_s``,
an ``aborted`` event on /frf/experiment, a ``finished`` event with ``"aborted": true`` on
/frf/progress); it answers ``{"aborted": false, ...}`` (success false) when nothing runs.

Refused at start-up (one line, exit 2): ``lockstep: true`` with ``use_sim_time: false``
(lockstep exists only with the simulated plant; a real robot runs free), and a second
publisher on the velocity topic (two excitation engines). The run logic is
:class:`frf_ident.app.excitation.ExcitationSession`; this module only wires it.
"""
from __future__ import annotations

import dataclasses
import json
import math
import threading
import time
from typing import Any, Optional, Sequence

from frf_ident import middleware as mw
from frf_ident.app.excitation import ExcitationSession
from frf_ident.app.excitation_settings import SessionSettings
from frf_ident.core.excitation.chirp_iteration import ChirpConfig
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.errors import FrfIdentInputError
from frf_ident.nodes import common as c
from frf_ident.nodes.operator_gate import OperatorGate
import numpy as np

__all__ = ['ExcitationNode', 'main']


def _config(node: Any, prefix: str, cls: type) -> Any:
    """Build a procedure config from parameters ``prefix.<field>`` (scalars and 1-D lists)."""
    kw = {}
    proto = cls()
    for f in dataclasses.fields(cls):
        value = getattr(proto, f.name)
        if isinstance(value, np.ndarray):
            if value.ndim == 1:
                got = c.param(node, f'{prefix}.{f.name}', value.tolist())
                kw[f.name] = np.asarray(got, dtype=float)
            elif f.name == 'u_des':   # flat list, one row per axis
                flat = c.param(node, f'{prefix}.{f.name}', [])
                if flat:
                    kw[f.name] = np.asarray(flat, float).reshape(-1, value.shape[1])
            continue
        if isinstance(value, (bool, int, float, str, list)):
            kw[f.name] = c.param(node, f'{prefix}.{f.name}', value)
    return cls(**kw)


#: node-level parameter names that were renamed: old -> new (a value set under the old name
#: is refused, never silently ignored)
RENAMED = {'position_bound_deg': 'plan_bound_deg'}


def settings_from_parameters(node: Any) -> SessionSettings:
    """Build the SessionSettings from the node's parameters (defaults: its own)."""
    for old, new in RENAMED.items():
        if not math.isnan(c.param(node, old, float('nan'))):     # set by the user
            raise c.Refused(f'parameter {old} is now {new} (multisine.{old} is the multisine '
                            f"design's own bound)")
    proto = SessionSettings()
    kw = {f.name: c.param(node, f.name, getattr(proto, f.name))
          for f in dataclasses.fields(SessionSettings) if f.name not in ('multisine', 'chirp')}
    return SessionSettings(**kw, multisine=_config(node, 'multisine', MultisineConfig),
                           chirp=_config(node, 'chirp', ChirpConfig))


class ExcitationNode:
    """
    Publishers, subscription, services and the watchdog timer around the session.

    Parameters
    ----------
    node : Any
        The node to wire (from :func:`frf_ident.middleware.create_node`); its parameters
        give the session settings, topics, model file and ``discovery_wait_s``.

    Raises
    ------
    Refused
        ``lockstep`` without ``use_sim_time``, or another publisher on the velocity topic.

    """

    def __init__(self, node: Any) -> None:
        from frf_ident.io.model_file import dry_run_plant, load_model
        self.node = node
        self.foxglove: Any = None          # the session may report before it is wired
        settings = settings_from_parameters(node)
        c.refuse_lockstep_without_sim(node, settings.lockstep)
        t = c.topics(node, ('joint_states_topic', 'velocity_topic', 'excitation_topic',
                            'experiment_topic', 'progress_topic'))
        self.velocity_topic = t['velocity_topic']
        model, robot, ctrl = load_model(c.param(node, 'model', '') or None)
        self.joints = list(robot.joint_names)
        torque_limit = np.minimum(ctrl.torque_limit, robot.torque_limits())
        JointState = mw.msg('sensor_msgs/msg/JointState')
        F64 = mw.msg('std_msgs/msg/Float64MultiArray')
        self.String = mw.msg('std_msgs/msg/String')
        self.cmd = F64(data=[0.0] * len(self.joints))
        self.exc_msg = JointState(name=list(self.joints), velocity=[0.0] * len(self.joints))
        self.cmd_pub = node.create_publisher(F64, t['velocity_topic'], mw.qos_default(c.DEEP))
        self.exc_pub = node.create_publisher(JointState, t['excitation_topic'],
                                             mw.qos_default(c.DEEP))
        self.exp_pub = node.create_publisher(self.String, t['experiment_topic'],
                                             mw.qos_transient_local(100))
        self.progress_pub = node.create_publisher(self.String, t['progress_topic'],
                                                  mw.qos_transient_local(10))
        clock = node.get_clock()
        # lockstep: staleness in simulation time (the plant's /clock); a robot: wall time
        sim_now = (lambda: clock.now().nanoseconds) if settings.lockstep else None
        self.session = ExcitationSession(settings, self.joints, robot.dt, torque_limit, self,
                                         model=(robot, ctrl, dry_run_plant(model, robot)),
                                         sim_now_ns=sim_now)
        self.dt_ns = self.session.dt_ns
        self.order: Optional[list[int]] = None
        self.names: Optional[list[str]] = None
        self.live = self._wire_live(node, torque_limit, robot.dt)
        self.foxglove = self._wire_foxglove(int(c.param(node, 'foxglove_port', 0)))
        self.refuse_second_publisher(float(c.param(node, 'discovery_wait_s', 0.5)))
        # arming and the operator heartbeat (docs/ros2.md, "Arming"); every request logged
        self.gate = OperatorGate(node, settings.lockstep, self.log)
        # every joint state, in order (also free-running): the torque of each sample is in its
        # own joint state, and a busy node works through a backlog instead of losing samples
        node.create_subscription(JointState, t['joint_states_topic'], self._on_state,
                                 mw.qos_default(c.DEEP), drain=True)
        Trigger = mw.srv('std_srvs/srv/Trigger')
        node.create_service(Trigger, '/frf/run_multisine', self._on_run_multisine, caller=True)
        node.create_service(Trigger, '/frf/run_iteration', self._on_run_iteration, caller=True)
        node.create_service(Trigger, '/frf/abort', self._on_abort, caller=True)
        # the watchdog thread: sim time from the node clock in lockstep, wall time on a robot
        self._stop = threading.Event()
        self._signalled = threading.Event()      # SIGINT/SIGTERM (spin's stop event)
        self._watchdog = threading.Thread(target=self._watch, daemon=True)
        self._watchdog.start()

    def _wire_live(self, node: Any, torque_limit: np.ndarray, dt: float) -> Any:
        """Wire the live estimate, its publishers and the uncertainty target (docs/live.md)."""
        from frf_ident.app.live import LiveMonitor
        from frf_ident.core.estimation.target import UncertaintyTarget
        target = UncertaintyTarget(float(c.param(node, 'target_sd_db', 0.0)),
                                   str(c.param(node, 'target_channels', 'diagonal')))
        if not c.param(node, 'live', True):
            if target.enabled:
                raise c.Refused('target_sd_db needs the live estimate (live: true)')
            return None
        t = c.topics(node, ('live_topic', 'warnings_topic'))
        F64 = mw.msg('std_msgs/msg/Float64MultiArray')
        self.Layout = mw.msg('std_msgs/msg/MultiArrayLayout')
        self.Dim = mw.msg('std_msgs/msg/MultiArrayDimension')
        self.F64 = F64
        # transient-local: a viewer that joins late gets the newest estimate at once
        self.live_pubs = {k: node.create_publisher(F64, f'{t["live_topic"]}/{k}',
                                                   mw.qos_transient_local(1))
                          for k in c.LIVE_FRAMES}
        self.warn_pub = node.create_publisher(self.String, t['warnings_topic'],
                                              mw.qos_transient_local(50))
        return LiveMonitor(self.joints, dt, self.session.offset, torque_limit, target, self,
                           stop=self.session.stop_at_target if target.enabled else None)

    def _wire_foxglove(self, port: int) -> Any:
        """Serve the live stream on a Foxglove WebSocket at ``port`` (0: none; docs/live.md)."""
        if not port:
            return None
        from frf_ident.io.foxglove_server import FoxgloveLive
        try:
            fox = FoxgloveLive(port, name='frf_ident excitation_node')
        except FrfIdentInputError as exc:
            raise c.Refused(str(exc)) from None
        self.log('info', f'Foxglove WebSocket on {fox.url} (the app: Open connection)')
        return fox

    def _now_ns(self) -> int:
        return int(self.node.get_clock().now().nanoseconds)

    def live_frame(self, topic: str, frame: Any) -> None:
        """
        Publish a live frame as a Float64MultiArray on /frf/live/<topic>.

        Parameters
        ----------
        topic : str
            'frf', 'distortion' or 'summary'.
        frame : ArrayFrame
            Its dims and data (frf_ident/io/live_frame.py).

        """
        layout = self.Layout(dim=[self.Dim(label=lab, size=n, stride=st)
                                  for lab, n, st in frame.dims], data_offset=0)
        self.live_pubs[topic].publish(self.F64(layout=layout, data=frame.data.tolist()))
        if self.foxglove is not None:
            self.foxglove.frame(topic, frame, self._now_ns())

    def warning(self, event: dict) -> None:
        """
        Publish an early warning as JSON on the warnings topic.

        Parameters
        ----------
        event : dict
            ``EarlyWarning.to_dict()``.

        """
        self.warn_pub.publish(self.String(data=json.dumps(event, sort_keys=True)))
        if self.foxglove is not None:
            self.foxglove.text('/frf/warnings', event, self._now_ns())

    def _watch(self) -> None:
        while not self._stop.wait(0.002):
            if self._signalled.is_set():
                # at once: the executor stops with the signal, and a run aborted later would
                # record "/joint_states stale" as its reason instead
                self.session.close()
                return
            self.session.watch()
            self.gate.watch(self.session)

    def spin(self, stop: threading.Event) -> None:
        """Spin the node until ``stop`` (a signal); the watchdog stops a run at the signal."""
        self._signalled = stop
        mw.spin(self.node, stop)

    # -- Outputs of the session ------------------------------------------------------------
    def reference(self, k: int, r: np.ndarray, x: np.ndarray) -> None:
        """
        Publish the excitation part (stamped) and then the velocity reference of a sample.

        Parameters
        ----------
        k : int
            Sample index; the excitation message is stamped k dt.
        r : ndarray, shape (n,)
            Velocity reference [rad/s], published on the velocity topic.
        x : ndarray, shape (n,)
            Excitation part of ``r`` [rad/s], published on the excitation topic.

        """
        if self.live is not None:
            self.live.reference(k, x)
        c.set_stamp(self.exc_msg, k * self.dt_ns)
        self.exc_msg.velocity = x.tolist()
        self.exc_pub.publish(self.exc_msg)   # first: recorders pair the command with this stamp
        self.cmd.data = r.tolist()
        self.cmd_pub.publish(self.cmd)

    def experiment(self, text: str) -> None:
        """
        Publish an experiment descriptor or event on the experiment topic.

        Parameters
        ----------
        text : str
            JSON text of the descriptor or event.

        """
        self.exp_pub.publish(self.String(data=text))
        if self.live is not None:
            self.live.experiment(text)

    def progress(self, event: dict) -> None:
        """
        Publish a progress event as JSON on the progress topic.

        Parameters
        ----------
        event : dict
            JSON-serialisable event (see :meth:`frf_ident.app.excitation_run.Outputs.progress`).

        """
        # compact: `ros2 topic echo` shows 128 characters unless --full-length
        self.progress_pub.publish(self.String(data=json.dumps(event, sort_keys=True,
                                                              separators=(',', ':'))))
        if self.foxglove is not None:
            self.foxglove.text('/frf/progress', event, self._now_ns())

    def log(self, level: str, text: str) -> None:
        """
        Write a line to the node's logger.

        Parameters
        ----------
        level : str
            'error', 'warn' or anything else for info.
        text : str
            The line.

        """
        # one call site per severity: rclpy refuses a severity change at the same call site
        logger = self.node.get_logger()
        if level == 'error':
            logger.error(text)
        elif level == 'warn':
            logger.warn(text)
        else:
            logger.info(text)

    # -- wiring ----------------------------------------------------------------------------
    def refuse_second_publisher(self, wait_s: float) -> None:
        """
        Refuse when another node publishes velocity references (two excitation engines).

        Parameters
        ----------
        wait_s : float
            Wall time [s] to keep checking for another publisher (discovery takes a while).

        Raises
        ------
        Refused
            Another publisher is on the velocity topic.

        """
        deadline = time.monotonic() + wait_s
        while True:
            n = self.node.count_publishers(self.velocity_topic)
            if n > 1:
                raise c.Refused(f'{n - 1} other publisher(s) on {self.velocity_topic}: another '
                                f'excitation engine is running; stop it first')
            if time.monotonic() >= deadline:
                return
            time.sleep(0.05)

    def _on_state(self, msg: Any) -> None:
        if self.names is None or list(msg.name) != self.names:
            self.names = list(msg.name)
            pos = {n: i for i, n in enumerate(self.names)}
            self.order = [pos[j] for j in self.joints]
        p, e, cols = msg.position, msg.effort, self.order
        effort = np.array([e[i] for i in cols]) if len(e) else None
        k, q = int(round(c.stamp_ns(msg) / self.dt_ns)), np.array([p[i] for i in cols])
        if len(msg.velocity) and (self.live is not None or self.foxglove is not None):
            v = np.array([msg.velocity[i] for i in cols])
            if self.live is not None:
                self.live.state(k, q, v, effort)
            if self.foxglove is not None:
                self.foxglove.joint_state(k * self.dt_ns, self.joints, q, v, effort)
        self.session.on_state(k, q, effort)

    def _start(self, starter: Any, response: Any, caller: Any) -> Any:
        try:
            self.gate.check()            # first: who may start motion at all
            n = self.node.count_publishers(self.velocity_topic)
            if n > 1:
                raise RuntimeError(f'{n - 1} other publisher(s) on {self.velocity_topic}')
            run = starter()
            self.gate.run_started(run)
            self.gate.log_request(caller, True, f'run {run.id} {run.name}')
            response.success = True
            response.message = json.dumps({'accepted': True, 'run': run.id,
                                           'procedure': run.name,
                                           'samples': run.stream.total})
        except Exception as exc:
            self.log('error', f'not started: {exc}')
            who = self.gate.log_request(caller, False, str(exc))
            response.success = False
            # refused: unsafe or invalid settings, the user's to change (not a failure)
            response.message = json.dumps({'accepted': False, 'error': str(exc),
                                           'refused': isinstance(exc, FrfIdentInputError),
                                           'caller': who})
        return response

    def _on_run_multisine(self, request: Any, response: Any, caller: Any) -> Any:
        return self._start(self.session.start_multisine, response, caller)

    def _on_run_iteration(self, request: Any, response: Any, caller: Any) -> Any:
        return self._start(self.session.start_chirp_iteration, response, caller)

    def _on_abort(self, request: Any, response: Any, caller: Any) -> Any:
        """Stop the running procedure: the reference ramps to zero within abort_ramp_s."""
        run = self.session.abort('abort requested (/frf/abort)')
        self.gate.log_request(caller, run is not None,
                              f'run {run.id} aborted' if run else 'no procedure is running')
        response.success = run is not None
        response.message = json.dumps({'aborted': True, 'run': run.id, 'procedure': run.name}
                                      if run is not None else
                                      {'aborted': False, 'error': 'no procedure is running'})
        return response

    def close(self) -> None:
        self._stop.set()
        self.session.close()
        self.gate.close()
        if self.live is not None:
            self.live.close()
        if self.foxglove is not None:
            self.foxglove.close()


def main(argv: Optional[Sequence[str]] = None) -> int:
    """
    ``ros2 run frf_ident excitation_node``.

    Parameters
    ----------
    argv : sequence of str, optional
        Command line (``--ros-args`` ...); default sys.argv.

    Returns
    -------
    int
        Exit code: 0, or 2 when the node refused its parameters.

    """
    return c.run_node('excitation_node', ExcitationNode, argv)


if __name__ == '__main__':
    raise SystemExit(main())
