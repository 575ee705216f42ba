"""excitation_node (+ iteration_service): runs the core procedure phases over the node graph.

The process holds two nodes:

- ``excitation_node`` streams the phases of :mod:`frf_ident.core.excitation.procedures` (multisine
  procedure, chirp iterations) as velocity references on /velocity_controller/commands, the
  excitation part with its sample stamp on /frf/excitation, and ``Segment.descriptor`` JSON on
  /frf/experiment (reliable, transient-local).
- ``iteration_service`` offers ``/frf/run_iteration`` (Trigger): one step of the chirp
  iteration (run the current phases, collect r and u, ``ChirpIteration.update``); the reply
  message is JSON ``{iteration, error_db, bag, converged, ...}``. ``/frf/run_multisine``
  (Trigger) runs the multisine procedure. Both answer when the run has ended.

Timing: sample k has stamp k*dt. In lockstep the references are published up to ``lookahead``
samples ahead of the last joint state; a 'move' phase waits for the joint state of its first
sample (its reference starts from the measured position, as in the offline runner).

Safety: the plan is checked before it runs (predicted position within +-``position_bound_deg``
around the operating point; for chirps the iteration's predicted torque within the limit).
While running, a watchdog aborts when /joint_states is stale (``stale_s`` wall in lockstep,
``stale_samples`` samples free-running) or a measured position leaves the bound: the reference
is ramped to zero within ``abort_ramp_s`` (wall), a zero reference is published, and an
``aborted`` descriptor with the reason goes to /frf/experiment.
"""
from __future__ import annotations

import dataclasses
import json
import math
import threading
import time
from typing import Any, Optional, Sequence

import numpy as np

from frf_ident import middleware as mw
from frf_ident.nodes import common as c


def _config(node: Any, prefix: str, cls: type, **defaults: Any) -> Any:
    """A procedure config dataclass from parameters ``prefix.<field>`` (scalars and 1-D lists)."""
    kw = {}
    proto = cls()
    for f in dataclasses.fields(cls):
        value = getattr(proto, f.name)
        default = defaults.get(f.name, value)
        if isinstance(value, np.ndarray):
            if value.ndim == 1:
                got = c.param(node, f'{prefix}.{f.name}', np.asarray(default).tolist())
                kw[f.name] = np.asarray(got, dtype=float)
            elif f.name == 'u_des':   # flat list, one row per axis
                flat = c.param(node, f'{prefix}.{f.name}', [])
                if flat:
                    kw[f.name] = np.asarray(flat, float).reshape(-1, value.shape[1])
            continue
        if isinstance(value, (bool, int, float, str, list)):
            kw[f.name] = c.param(node, f'{prefix}.{f.name}', default)
    return cls(**kw)


class Run:
    """One streamed plan: a list of phases and where its samples are."""

    def __init__(self, name: str, phases: list, start_k: int, collect: bool) -> None:
        self.name, self.phases, self.collect = name, phases, collect
        self.start_k = start_k
        self.i_phase = 0
        self.i_sample = 0
        self.ref: Optional[np.ndarray] = None
        self.exc: Optional[np.ndarray] = None
        self.plan: Optional[np.ndarray] = None
        self.seg_ranges: list[tuple[int, int, np.ndarray]] = []   # (k0, k1, reference)
        self.u: dict[int, np.ndarray] = {}                         # segment index -> torque
        self.end_k: Optional[int] = None
        self.done = threading.Event()
        self.max_gap = 0.0
        self.steps_per_s = 0.0
        self.t0 = time.monotonic()
        self.error: Optional[str] = None


class Excitation:
    """The excitation engine of the excitation_node."""

    def __init__(self, node: Any) -> None:
        from frf_ident.core.excitation.procedures import ChirpConfig, MultisineConfig
        from frf_ident.io.model_file import load_model
        self.node = node
        self.log = node.get_logger()
        model_path = c.param(node, 'model', '')
        self.lockstep = bool(c.param(node, 'lockstep', True))
        self.lookahead = int(c.param(node, 'lookahead', 20)) if self.lockstep else 1
        self.stale_s = float(c.param(node, 'stale_s', 0.5))
        self.stale_samples = int(c.param(node, 'stale_samples', 3))
        self.start_grace_s = float(c.param(node, 'start_grace_s', 0.2))
        self.abort_ramp_s = float(c.param(node, 'abort_ramp_s', 0.01))
        self.bound = math.radians(float(c.param(node, 'position_bound_deg', 4.0)))
        self.live_bound = math.radians(float(c.param(node, 'live_position_bound_deg', 8.0)))
        t = c.topics(node, ('joint_states_topic', 'velocity_topic', 'excitation_topic',
                            'experiment_topic'))
        self.ms_cfg = _config(node, 'multisine', MultisineConfig)
        self.chirp_cfg = _config(node, 'chirp', ChirpConfig)
        model, robot, ctrl = load_model(model_path or None)
        self.joints = list(robot.joint_names)
        self.n = len(self.joints)
        self.dt = robot.dt
        self.fs = 1.0 / self.dt
        self.dt_ns = int(round(self.dt * 1e9))
        self.torque_limit = np.minimum(ctrl.torque_limit, robot.torque_limits())
        JointState = mw.msg('sensor_msgs/msg/JointState')
        F64 = mw.msg('std_msgs/msg/Float64MultiArray')
        String = mw.msg('std_msgs/msg/String')
        self.String = String
        self.cmd = F64(data=[0.0] * self.n)
        self.exc_msg = JointState(name=list(self.joints), velocity=[0.0] * self.n)
        self.cmd_pub = node.create_publisher(F64, t['velocity_topic'], mw.qos_default(c.DEEP))
        self.exc_pub = node.create_publisher(JointState, t['excitation_topic'],
                                             mw.qos_default(c.DEEP))
        self.exp_pub = node.create_publisher(String, t['experiment_topic'],
                                             mw.qos_transient_local(100))
        node.create_subscription(JointState, t['joint_states_topic'], self._on_state,
                                 mw.qos_default(c.DEEP))
        self.lock = threading.RLock()
        self.k_js = -1                    # index of the newest joint state
        self.q_js: Optional[np.ndarray] = None
        self.q0: Optional[np.ndarray] = None   # operating point (first joint state)
        self.t_js = time.monotonic()
        self.next_k = -1                  # sample index of the next reference to publish
        self.last_ref = np.zeros(self.n)
        self.run: Optional[Run] = None
        self.order: Optional[list[int]] = None
        self.names: Optional[list[str]] = None
        self.chirp = None
        self.hold: Optional[np.ndarray] = None   # position a settle phase holds after a move
        self._stop = threading.Event()
        self._watchdog = threading.Thread(target=self._watch, daemon=True)
        self._watchdog.start()

    # -- joint states ---------------------------------------------------------------------------
    def _cols(self, msg: Any) -> list[int]:
        if self.names is None or list(msg.name) != self.names:
            self.names = list(msg.name)
            pos = {n: i for i, n in enumerate(self.names)}
            self.order = [pos[j] for j in self.joints]
        return self.order

    def _on_state(self, msg: Any) -> None:
        k = int(round(c.stamp_ns(msg) / self.dt_ns))
        with self.lock:
            if k <= self.k_js:
                return
            cols = self._cols(msg)
            p, e = msg.position, msg.effort
            q = np.array([p[i] for i in cols])
            now = time.monotonic()
            run = self.run
            if run is not None and k > run.start_k + 1:
                run.max_gap = max(run.max_gap, now - self.t_js)
            self.k_js, self.q_js, self.t_js = k, q, now
            if self.q0 is None:
                self.q0 = q.copy()
            if self.next_k < 0:
                self.next_k = k
            run = self.run
            if run is None or run.done.is_set():
                return
            if np.any(np.abs(q - self.q0) > self.live_bound):
                self._abort(f'measured position {np.degrees(q - self.q0).round(2).tolist()} deg '
                            f'from the operating point exceeds the live bound '
                            f'{math.degrees(self.live_bound):.2f} deg')
                return
            if run.collect and e:   # effort of joint state k = torque applied at sample k-1
                j = k - 1
                for idx, (k0, k1, _r) in enumerate(run.seg_ranges):
                    if k0 <= j < k1:
                        run.u[idx][j - k0] = [e[i] for i in cols]
            self._pump()
            if run.end_k is not None and k >= run.end_k:
                self._finish(run)

    # -- streaming ------------------------------------------------------------------------------
    def _descriptor(self, seg_info: dict, event: str, k0: int, k1: int) -> None:
        from frf_ident.core.recording import Segment
        text = Segment(k0 * self.dt, k1 * self.dt, seg_info).descriptor(event)
        self.exp_pub.publish(self.String(data=text))

    def _event(self, **d: Any) -> None:
        self.exp_pub.publish(self.String(data=json.dumps(d, sort_keys=True)))

    def _publish_ref(self, k: int, r: np.ndarray, x: np.ndarray) -> None:
        c.set_stamp(self.exc_msg, k * self.dt_ns)
        self.exc_msg.velocity = x.tolist()
        self.exc_pub.publish(self.exc_msg)   # first: recorders pair the command with this stamp
        self.cmd.data = r.tolist()
        self.cmd_pub.publish(self.cmd)
        self.last_ref = r

    def _pump(self) -> None:
        """Publish references up to ``lookahead`` samples past the newest joint state."""
        from frf_ident.core.excitation.procedures import POSITION_GAIN, move_plan
        run = self.run
        while run.end_k is None and self.next_k <= self.k_js + self.lookahead - 1 + \
                (0 if self.lockstep else 1):
            if run.i_phase >= len(run.phases):
                run.end_k = self.next_k        # done once the plant applied the last command
                break
            ph = run.phases[run.i_phase]
            held = ph.kind in ('move', 'settle')
            if held and self.k_js != self.next_k:
                break       # position-held phases need the measured position of each sample
            if run.i_sample == 0:
                run.plan = None
                if ph.kind == 'move':    # as ClosedLoop.run_phase: plan from the measured q
                    run.ref, run.plan = move_plan(self.q_js, self.q0 + ph.target,
                                                  ph.n_samples, self.dt)
                    self.hold = run.plan[-1]
                    run.exc = np.zeros_like(run.ref)
                elif ph.kind == 'settle':
                    hold = self.q_js if self.hold is None else self.hold
                    self.hold = None
                    run.ref = np.zeros((ph.n_samples, self.n))
                    run.plan = np.tile(hold, (ph.n_samples, 1))
                    run.exc = run.ref
                else:
                    run.ref = ph.reference
                    run.exc = ph.excitation if ph.excitation is not None else \
                        np.zeros_like(ph.reference)
                if ph.segment is not None:
                    k0, k1 = self.next_k, self.next_k + ph.n_samples
                    run.seg_ranges.append((k0, k1, ph.reference))
                    if run.collect:
                        run.u[len(run.seg_ranges) - 1] = np.full((ph.n_samples, self.n), np.nan)
                    self._descriptor(ph.segment, 'start', k0, k1)
            i = run.i_sample
            if run.plan is not None:
                r = run.ref[i] + POSITION_GAIN * (run.plan[i] - self.q_js)
                self._publish_ref(self.next_k, r, run.exc[i])
            else:
                self._publish_ref(self.next_k, run.ref[i], run.exc[i])
            self.next_k += 1
            run.i_sample += 1
            if run.i_sample >= ph.n_samples:
                if ph.segment is not None:
                    k0, k1, _ = run.seg_ranges[-1]
                    self._descriptor(ph.segment, 'end', k0, k1)
                run.i_phase += 1
                run.i_sample = 0

    def _finish(self, run: Run) -> None:
        wall = time.monotonic() - run.t0
        steps = run.end_k - run.start_k
        run.steps_per_s = steps / wall
        self.log.info(f'{run.name}: {steps} samples in {wall:.2f} s wall ({steps / wall:.0f} '
                      f'steps/s), longest joint-state gap {1e3 * run.max_gap:.1f} ms')
        self._event(event='procedure_end', procedure=run.name, t_start=run.start_k * self.dt,
                    t_end=run.end_k * self.dt, steps_per_s=steps / wall)
        run.done.set()

    def start(self, name: str, phases: list, collect: bool = False,
              timeout_s: float = 10.0) -> Run:
        deadline = time.monotonic() + timeout_s
        while self.next_k < 0:           # need the first joint state (operating point)
            if time.monotonic() > deadline:
                raise RuntimeError('no /joint_states received: is the plant running?')
            time.sleep(0.01)
        with self.lock:
            if self.run is not None and not self.run.done.is_set():
                raise RuntimeError(f'experiment {self.run.name!r} is still running')
            run = Run(name, phases, self.next_k, collect)
            self.run = run
            self.t_js = time.monotonic()
            self._pump()
        return run

    # -- safety ---------------------------------------------------------------------------------
    def check_plan(self, phases: list, start: np.ndarray) -> None:
        from frf_ident.core.excitation.procedures import check_position_bound
        check_position_bound(phases, start, self.bound, self.dt)

    def _abort(self, reason: str) -> None:
        """Ramp the reference to zero within abort_ramp_s (wall), publish zero, report."""
        run = self.run
        if run is None or run.done.is_set():
            return
        run.error = reason
        run.end_k = self.next_k
        self.log.error(f'experiment {run.name!r} aborted: {reason}')
        steps = 4
        r0 = self.last_ref.copy()
        for s in range(1, steps + 1):
            w = 1.0 - s / steps
            self._publish_ref(self.next_k, r0 * w, np.zeros(self.n))
            self.next_k += 1
            if s < steps:
                time.sleep(self.abort_ramp_s / steps)
        self._event(event='aborted', procedure=run.name, reason=reason,
                    t_start=run.start_k * self.dt, t_end=self.next_k * self.dt)
        run.done.set()

    def _watch(self) -> None:
        while not self._stop.wait(0.002):
            with self.lock:
                run = self.run
                if run is None or run.done.is_set():
                    continue
                limit = self.stale_s if self.lockstep else self.stale_samples * self.dt
                if self.k_js <= run.start_k:   # first answer of a run: allow start-up time
                    limit = max(limit, self.start_grace_s)
                waiting = self.next_k > self.k_js or not self.lockstep
                age = time.monotonic() - self.t_js
                if waiting and age > limit:
                    self._abort(f'/joint_states stale for {1e3 * age:.0f} ms (limit '
                                f'{1e3 * limit:.0f} ms)')

    def close(self) -> None:
        self._stop.set()
        with self.lock:
            if self.run is not None and not self.run.done.is_set():
                self._abort('shutdown')

    # -- procedures -----------------------------------------------------------------------------
    def run_multisine(self, timeout_s: Optional[float] = None) -> dict:
        from frf_ident.core.excitation.procedures import multisine_procedure
        phases, design = multisine_procedure(self.ms_cfg, self.n, self.fs)  # checks the bound
        run = self.start('multisine', phases)
        if not run.done.wait(timeout_s):
            raise TimeoutError('multisine procedure did not finish')
        if run.error:
            raise RuntimeError(run.error)
        return {'procedure': 'multisine', 'segments': len(run.seg_ranges),
                'lines': int(design.harmonics.size),
                'experiment_time_s': (run.end_k - run.start_k) * self.dt,
                'steps_per_s': run.steps_per_s, 'max_gap_ms': 1e3 * run.max_gap}

    def chirp_iteration(self) -> Any:
        from frf_ident.core.excitation.procedures import ChirpIteration
        if self.chirp is None:
            self.chirp = ChirpIteration(self.chirp_cfg, self.n, self.fs, self.torque_limit)
        return self.chirp

    def run_chirp_iteration(self, timeout_s: Optional[float] = None) -> dict:
        it = self.chirp_iteration()
        if it.history and it.history[-1].get('converged'):
            return dict(it.history[-1], note='already converged')
        last = it.history[-1] if it.history else {}
        pred = last.get('predicted_peak_torque')
        if pred is not None and np.any(np.asarray(pred) > self.torque_limit + 1e-9):
            raise RuntimeError(f'predicted torque {pred} exceeds the limit '
                               f'{self.torque_limit.tolist()}; refusing to run')
        phases = it.phases()
        self.check_plan(phases, np.zeros(self.n))
        run = self.start(f'chirp_iteration_{it.iteration}', phases, collect=True)
        if not run.done.wait(timeout_s):
            raise TimeoutError('chirp iteration did not finish')
        if run.error:
            raise RuntimeError(run.error)
        r_runs = [r for (_k0, _k1, r) in run.seg_ranges]
        u_runs = [run.u[i] for i in range(len(run.seg_ranges))]
        if any(np.isnan(u).any() for u in u_runs):
            raise RuntimeError('torque samples missing from /joint_states')
        return dict(it.update(r_runs, u_runs), steps_per_s=run.steps_per_s,
                    max_gap_ms=1e3 * run.max_gap)


def _iteration_node(exc: Excitation, bag: str) -> Any:
    node = mw.create_node('iteration_service')
    bag = c.param(node, 'bag', bag)

    def handle(request: Any, response: Any) -> Any:
        try:
            s = exc.run_chirp_iteration()
            response.success = True
            response.message = json.dumps({
                'iteration': s['iteration'], 'error_db': s['max_abs_error_db'],
                'error_db_per_channel': s['error_db_per_channel'],
                'converged': bool(s['converged']), 'max_abs_torque': s['max_abs_torque'],
                'bag': bag})
        except Exception as exc_:
            exc.log.error(f'chirp iteration failed: {exc_}')
            response.success = False
            response.message = json.dumps({'error': str(exc_), 'bag': bag})
        return response

    def handle_multisine(request: Any, response: Any) -> Any:
        try:
            s = exc.run_multisine()
            response.success = True
            response.message = json.dumps(dict(s, bag=bag))
        except Exception as exc_:
            exc.log.error(f'multisine failed: {exc_}')
            response.success = False
            response.message = json.dumps({'error': str(exc_), 'bag': bag})
        return response

    Trigger = mw.srv('std_srvs/srv/Trigger')
    node.create_service(Trigger, '/frf/run_iteration', handle)
    node.create_service(Trigger, '/frf/run_multisine', handle_multisine)
    return node


def main(argv: Optional[Sequence[str]] = None) -> int:
    c.init(argv)
    stop = c.StopOnSignal()
    node = mw.create_node('excitation_node')
    stop.nodes.append(node)
    autostart = c.param(node, 'autostart', '')
    exc = Excitation(node)
    srv_node = _iteration_node(exc, '')
    stop.nodes.append(srv_node)
    t = threading.Thread(target=mw.spin, args=(srv_node, stop.event), daemon=True)
    t.start()
    node.get_logger().info(f'excitation on {exc.joints}, fs {exc.fs:g} Hz, lockstep='
                           f'{exc.lockstep}, lookahead {exc.lookahead}')
    c.announce_ready('excitation_node')
    c.announce_ready('iteration_service')
    if autostart == 'multisine':
        threading.Thread(target=exc.run_multisine, daemon=True).start()
    try:
        mw.spin(node, stop.event)
    finally:
        exc.close()
        t.join(1.0)
        mw.shutdown()
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
