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
a periodic :meth:`watch`; the session answers through the :class:`Outputs` it was given
(publish a reference, a descriptor, a progress or end event, a log line).

Timing: sample k has stamp k*dt. ``lockstep`` (simulation): references go up to ``lookahead``
samples ahead of the newest joint state and the controller consumes them in order; a 'move' or
'settle' sample waits for the joint state of that very sample. Free-running (a real robot, or
the plant on a wall timer): on joint state k the reference of sample k+1 goes out, computed from
the position at k.

Sample pairing of the torque (what the chirp iteration collects; docs/CONTRACT.md §3):
lockstep -- the simulated plant answers command k with joint state k+1, whose effort is the
torque applied from t_k, so the torque of sample k is the effort of joint state k+1;
free-running -- the effort of joint state k is the torque applied at t_k (a robot's measured
torque; the free-running plant node reports it so), so the torque of sample k is in joint state k.
Every segment descriptor declares this lag (``effort_lag``); recorders keep joint states as
published and the bag reader applies it, so every recorder and replay path pairs alike.

Safety: a plan is checked before it runs: its planned position against the position bound,
and its peak torque, predicted by a dry run on the model from where the robot is (the
multisine plan with its moves, and the first chirp step; later chirp steps from what the
previous ones measured), against 0.95 of each limit. Free-running, a run starts at the first
joint state after its start (the node's executor was busy planning). A run aborts when
/joint_states is stale, the node missed more than ``stale_samples`` joint states, a measured
position leaves the live bound or a measured torque reaches its limit: the reference ramps to
zero, a zero reference is published and an ``aborted`` descriptor sent. Free-running, one
reference goes out per joint state, so the joint states must come at the model's sample rate:
a run is refused, or aborted, when they come regularly at a fifth of that rate or less (the
steps between the newest ``RATE_WINDOW``).
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
import json
import math
import threading
import time
from typing import Any, Callable, Optional, Protocol

from frf_ident.core.excitation.engine import PhaseEngine, PhaseStream, SegmentEvent
from frf_ident.core.excitation.procedures import (check_position_bound, ChirpConfig,
                                                  ChirpIteration, multisine_procedure,
                                                  multisine_tail, MultisineConfig,
                                                  STOP_FADE_S)
from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Segment
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.core.simulation.runner import check_plan_torque
from frf_ident.errors import DesignError, SafetyError
import numpy as np

__all__ = ['ExcitationSession', 'fill_torque_gaps', 'Outputs', 'SessionSettings',
           'torque_sample_offset']


def torque_sample_offset(lockstep: bool) -> int:
    """
    Joint state k carries the torque of sample ``k - offset`` (see the module docstring).

    Parameters
    ----------
    lockstep
        True for the lockstep simulation, False free-running (real robot).

    Returns
    -------
    int
        1 in lockstep, 0 free-running.

    """
    return 1 if lockstep else 0


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


#: the longest ramp to zero an abort may take [s]
MAX_ABORT_RAMP_S = 0.1
#: a measured torque at this share of its limit is a saturated drive: the run aborts (the
#: procedures aim at 0.95 of the limit at most, procedures.TORQUE_MARGIN)
SATURATION = 0.995
#: free-running: the joint states whose stamp steps judge their rate (at least half of them)
RATE_WINDOW = 16
#: free-running: a median step of this many samples between the joint states the node sees,
#: regular, refuses or aborts a run: the robot publishes at a fifth of the model's rate or
#: less. (A busy node that misses joint states still measures an unbiased FRF: the reference
#: stays the instrument, only the spectrum the robot gets changes; the free-running graph of
#: test/nodes/test_free_running.py runs on a loaded machine.)
SLOW_STEP = 5
#: free-running: the share of steps within 15 % (at least one sample) of their median that
#: makes them regular (a robot's stamps jitter by a share of its own period)
REGULAR = 0.75
#: the longest run of missed joint states whose torque a chirp step fills in [samples]
MAX_TORQUE_GAP = 2


@dataclass
class SessionSettings:
    """
    Parameters of the excitation node (defaults are the node's parameter defaults).

    Parameters
    ----------
    lockstep : bool, optional
        Lockstep simulation (references ahead of the joint states); default False:
        free-running (a real robot).
    lookahead : int, optional
        Lockstep: references published ahead of the newest joint state [samples].
    stale_s : float, optional
        Watchdog, lockstep: simulation time [s] the plant's clock (/clock) may run ahead of
        the newest joint state the node saw before a run aborts.
    plant_silent_s : float, optional
        Watchdog, lockstep: wall time [s] without any joint state (the simulated plant died
        or hangs) before a run aborts.
    stale_samples : int, optional
        Watchdog, free-running: the same limit in samples.
    start_grace_s : float, optional
        Wall time [s] the first answer of a run may take (the watchdog waits at least this).
    abort_ramp_s : float, optional
        Wall time [s] within which an abort ramps the reference to zero.
    plan_bound_deg : float, optional
        Bound [deg] of the planned position around the operating point (checked before a
        run); distinct from ``multisine.position_bound_deg``, the multisine design's bound of
        its constant-velocity run.
    live_position_bound_deg : float, optional
        Bound [deg] of the measured position around the operating point (a run aborts
        beyond it).
    progress_period_s : float, optional
        Wall time [s] between progress events.
    multisine : MultisineConfig, optional
        Design of the multisine procedure.
    chirp : ChirpConfig, optional
        Design of the chirp iteration.

    """

    lockstep: bool = False         # free-running unless the simulation says otherwise
    lookahead: int = 20            # lockstep: references published ahead [samples]
    # watchdog, lockstep: simulation s the plant's clock runs ahead of the newest joint state.
    # The plant waits for references, so its clock leads by `lookahead` samples (20 ms) at most
    # while nothing is lost: 0.5 s is a measurement that really went missing, however slowly
    # a loaded PC runs the simulation (issue 44: wall-time staleness aborted 3 of 4 runs at
    # load 4-12, stalls of 1.46 s wall)
    stale_s: float = 0.5
    # watchdog, lockstep: wall s without any joint state (a dead or hung simulated plant; its
    # /clock stops too). Far above the 1.46 s stalls of a loaded 2-core PC; only a dead plant
    # reaches it (a simulation drives no robot: there is no hurry)
    plant_silent_s: float = 10.0
    # watchdog, free-running, in samples: 50 ms at 1 kHz. A Python node on a Linux PC
    # without a real-time kernel saw joint-state gaps of 3.6-23 ms in 12 of 13 runs, 69 ms in
    # one (`make bench`, section nodes; README, 'stale_samples'): 10 aborted good runs
    stale_samples: int = 50
    start_grace_s: float = 0.2     # the first answer of a run may take this long
    abort_ramp_s: float = 0.01     # ramp to zero reference within this wall time
    plan_bound_deg: float = 4.0            # planned position bound around the operating point
    live_position_bound_deg: float = 8.0   # measured position bound (abort)
    progress_period_s: float = 0.5         # wall s between progress events
    multisine: MultisineConfig = field(default_factory=MultisineConfig)
    chirp: ChirpConfig = field(default_factory=ChirpConfig)

    def __post_init__(self) -> None:
        """Refuse settings that switch a safety check off or make it slow (DesignError)."""
        positive = {'stale_s': self.stale_s, 'stale_samples': self.stale_samples,
                    'plant_silent_s': self.plant_silent_s,
                    'start_grace_s': self.start_grace_s, 'abort_ramp_s': self.abort_ramp_s,
                    'plan_bound_deg': self.plan_bound_deg,
                    'live_position_bound_deg': self.live_position_bound_deg,
                    'progress_period_s': self.progress_period_s, 'lookahead': self.lookahead}
        for name, value in positive.items():
            if not (math.isfinite(value) and value > 0):
                raise DesignError(f'{name}={value} must be a positive number')
        if self.abort_ramp_s > MAX_ABORT_RAMP_S:
            raise DesignError(f'abort_ramp_s={self.abort_ramp_s} s: an abort must stop the '
                              f'robot within {MAX_ABORT_RAMP_S} s')
        if self.live_position_bound_deg < self.plan_bound_deg:
            raise DesignError(f'live_position_bound_deg={self.live_position_bound_deg} is below '
                              f'plan_bound_deg={self.plan_bound_deg}: every run would '
                              'abort on its planned motion')


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


class ExcitationSession:
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

    # -- measurements -------------------------------------------------------------------------
    def on_state(self, k: int, q: np.ndarray, effort: Optional[np.ndarray]) -> None:
        """
        Joint state of sample ``k`` (position ``q``, effort or None) in model joint order.

        Parameters
        ----------
        k : int
            Sample index of the joint state (stamp / dt); states not newer than the last one
            are ignored.
        q : ndarray, shape (n,)
            Measured position [rad]; the first one received becomes the operating point.
        effort : ndarray, shape (n,) or None
            Measured effort [N m] (the torque of sample ``k - offset``, see the module
            docstring), or None when the message carries none.

        """
        with self.lock:
            if not self.s.lockstep and k > self.k_js >= 0:
                self.steps.append(k - self.k_js)
            if k <= self.k_js:
                return
            run = self.run
            if not np.all(np.isfinite(q)):
                # no position: the live bound cannot be checked, so this is no joint state
                # (a stream of them trips the watchdog), and a running procedure stops
                if run is not None and not run.done.is_set():
                    self._abort(f'measured position {q.tolist()} is not finite')
                return
            now = time.monotonic()
            unseen = k - self.k_js - 1
            if run is not None and k > run.start_k + 1:
                run.max_gap = max(run.max_gap, now - self.t_js)
            self.k_js, self.q_js, self.t_js = k, q, now
            if self.q0 is None:
                self.q0 = q.copy()
                self.engine = PhaseEngine(self.q0, self.dt)
            if self.next_k < 0:
                self.next_k = k
            if run is None or run.done.is_set():
                return
            if not run.anchored:
                self._anchor(run, k)
            elif not self.s.lockstep and unseen > self.s.stale_samples:
                self._abort(f'the excitation node did not see {unseen} joint states (limit '
                            f'stale_samples={self.s.stale_samples}): it stalled while the '
                            f'robot ran on')
                return
            # judged only after a step of two or more samples: at the model's rate (every
            # state one sample on) the per-state cost stays one comparison
            rate = self._rate_problem() if unseen >= 1 else None
            if rate is not None:
                self._abort(rate)
                return
            if np.any(np.abs(q - self.q0) > self.live_bound):
                self._abort(f'measured position {np.degrees(q - self.q0).round(2).tolist()} deg '
                            f'from the operating point exceeds the live bound '
                            f'{math.degrees(self.live_bound):.2f} deg')
                return
            if (effort is not None and len(effort)
                    and np.any(np.abs(effort) >= SATURATION * self.torque_limit)):
                self._abort(f'measured torque {np.round(effort, 1).tolist()} N m reaches the '
                            f'limits {self.torque_limit.tolist()}: the drives saturate')
                return
            if run.collect and effort is not None and len(effort):
                j = k - self.offset
                for idx, (k0, k1, _r) in enumerate(run.stream.segments):
                    if k0 <= j < k1:
                        run.u[idx][j - k0] = effort
            self._stream()
            if run.end_k is not None and k >= run.end_k:   # the plant applied the last one
                self._finish(run)
            elif now - run.t_progress >= self.s.progress_period_s:
                run.t_progress = now
                self.out.progress(self._progress(run, 'progress'))

    # -- streaming ----------------------------------------------------------------------------
    def _segment(self, ev: SegmentEvent) -> None:
        # every descriptor says which sample a joint state's effort belongs to: recorders
        # store joint states as published, the bag reader pairs (frf_ident/bag/pairing.py)
        info = dict(ev.info, effort_lag=self.offset)
        text = Segment(ev.k0 * self.dt, ev.k1 * self.dt, info).descriptor(ev.event)
        self.out.experiment(text)
        if self.run is not None and self.run.collect and ev.event == 'start':
            self.run.u[ev.index] = np.full((ev.k1 - ev.k0, self.n), np.nan)

    def _publish(self, k: int, r: np.ndarray, x: np.ndarray) -> None:
        self.out.reference(k, r, x)
        self.last_ref = r

    def _stream(self) -> None:
        """Publish the references the newest joint state allows (lookahead window)."""
        run = self.run
        st = run.stream
        while run.end_k is None and self.next_k <= self.k_js + self.lookahead - 1 + self.lag:
            if st.done:
                run.end_k = self.next_k
                break
            if st.needs_measurement() and self.next_k - self.k_js > self.lag:
                break
            sample = st.next_sample(self.q_js)
            for ev in sample.events:
                if ev.event == 'start':
                    self._segment(ev)
            self._publish(sample.k, sample.reference, sample.excitation)
            for ev in sample.events:
                if ev.event == 'end':
                    self._segment(ev)
            self.next_k = st.k

    def _rate_problem(self) -> Optional[str]:
        """
        Free-running: why the robot's joint-state rate does not suit the model, or None.

        A robot stamps its joint states from its control loop: at a lower rate than the
        model's, the steps between them are regular (``REGULAR`` of them at the median). A
        node too busy to take each one sees irregular steps; that is left to the watchdog
        (``stale_samples``): the FRF stays unbiased (``SLOW_STEP``).
        """
        d = np.asarray(self.steps, float)
        if self.s.lockstep or d.size < RATE_WINDOW // 2:
            return None
        step = float(np.median(d))
        if step < SLOW_STEP or np.mean(np.abs(d - step) <= max(1.0, 0.15 * step)) < REGULAR:
            return None
        return (f"/joint_states come every {step:g} samples of the model's sample_rate "
                f'{self.fs:g} Hz (about {self.fs / step:.0f} Hz), so most references would '
                "never reach the robot: set the robot's joint-state rate "
                f"(joint_state_broadcaster update_rate) to {self.fs:g} Hz, or the model file's "
                'sample_rate to the rate the robot publishes')

    def _progress(self, run: Run, event: str, **extra: Any) -> dict:
        wall = time.monotonic() - run.t0
        st = run.stream
        return dict(event=event, run=run.id, procedure=run.name, samples=st.sent,
                    of=st.total, fraction=round(st.sent / max(st.total, 1), 4),
                    wall_s=round(wall, 3), **extra)

    def _finish(self, run: Run) -> None:
        if not self.s.lockstep and np.any(self.last_ref != 0):
            # free-running: the controller keeps the last reference it got, and the last
            # settle sample is a small position correction, not zero: the robot would drift
            self._publish(self.next_k, np.zeros(self.n), np.zeros(self.n))
            self.next_k += 1
        wall = time.monotonic() - run.t0
        steps = run.end_k - run.start_k
        rate = steps / max(wall, 1e-9)
        self.out.log('info', f'{run.name}: {steps} samples in {wall:.2f} s wall ({rate:.0f} '
                             f'steps/s), longest joint-state gap {1e3 * run.max_gap:.1f} ms')
        self.out.experiment(_json(event='procedure_end', procedure=run.name,
                                  t_start=run.start_k * self.dt, t_end=run.end_k * self.dt,
                                  steps_per_s=rate))
        base = {'steps_per_s': rate, 'max_gap_ms': 1e3 * run.max_gap,
                'experiment_time_s': steps * self.dt}
        try:
            result = dict(run.on_end(run), **base)
            run.result = result
            self.out.progress(self._progress(run, 'finished', success=True, result=result))
        except Exception as exc:   # reported on the progress topic, never raised into DDS
            run.error = f'{type(exc).__name__}: {exc}'
            self.out.log('error', f'{run.name} failed: {run.error}')
            self.out.progress(self._progress(run, 'finished', success=False, error=run.error))
        run.done.set()

    # -- starting runs ------------------------------------------------------------------------
    def _refuse_while_running(self) -> None:
        run = self.run
        if run is not None and not run.done.is_set():
            raise RuntimeError(f'experiment {run.name!r} is still running')

    def _start(self, name: str, phases: list, collect: bool,
               on_end: Callable[[Run], dict], remedy: Optional[str]) -> Run:
        """Start a run; its torque is predicted unless ``remedy`` (for a refusal) is None."""
        if self.q0 is None:
            raise RuntimeError('no /joint_states received yet: is the robot (plant) running?')
        self._refuse_while_running()
        with self.lock:
            rate = self._rate_problem()
        if rate is not None:
            raise SafetyError(rate)
        check_position_bound(phases, np.zeros(self.n), self.bound, self.dt)
        if remedy is not None and self.model is not None:
            # outside the lock, which the watchdog thread takes; the node's executor is busy
            # here (no joint states), so a free-running run starts at the next one (_anchor)
            robot, ctrl = self.model[:2]
            dry = self.model[2] if len(self.model) > 2 else None     # MuJoCo's, for an MJCF
            peak = check_plan_torque(phases, robot, ctrl, self.torque_limit, name, remedy,
                                     self.q_js, origin=self.q0, plant=dry)
            self.out.log('info', f'{name}: predicted peak torque '
                                 f'{np.round(peak, 1).tolist()} N m on the model')
        with self.lock:
            self._refuse_while_running()     # again: another start may have come meanwhile
            self.next_k = max(self.next_k, self.k_js + self.lag)
            self.runs += 1
            run = Run(self.runs, name, PhaseStream(self.engine, phases, self.next_k), collect,
                      on_end)
            self.run = run
            self.t_js = time.monotonic()
            self.out.progress(self._progress(run, 'started'))
            run.anchored = self.s.lockstep     # lockstep: the stream waits for its states
            if run.anchored:
                self._stream()
        return run

    def _anchor(self, run: Run, k: int) -> None:
        """Free-running: start the run's stream at joint state ``k``, the first after start."""
        self.next_k = k + self.lag
        run.stream = PhaseStream(self.engine, run.stream.phases, self.next_k)
        run.start_k = self.next_k
        run.anchored = True

    def start_multisine(self) -> Run:
        """
        Start the multisine procedure; returns at once (the end comes as an event).

        Returns
        -------
        Run
            The started run; its ``done`` event is set when it finished or aborted.

        Raises
        ------
        RuntimeError
            No joint state received yet, or another procedure is still running.
        SafetyError
            The planned position leaves the position bound, the predicted peak torque
            reaches 0.95 of a limit, or (free-running) the joint states come at a fifth of
            the model's sample rate or less.

        """
        with self.lock:
            self._refuse_while_running()     # first: planning blocks the node for seconds
        phases, design = multisine_procedure(self.s.multisine, self.n, self.fs)

        def end(run: Run) -> dict:
            return {'procedure': 'multisine', 'segments': len(run.stream.segments),
                    'lines': int(design.harmonics.size)}
        return self._start('multisine', phases, False, end, remedy=self.s.multisine.remedy())

    def chirp_iteration(self) -> ChirpIteration:
        """
        Return the chirp iteration (created on first use).

        Returns
        -------
        ChirpIteration
            The session's chirp iteration, kept across its steps.

        """
        if self.chirp is None:
            self.chirp = ChirpIteration(self.s.chirp, self.n, self.fs, self.torque_limit)
        return self.chirp

    def start_chirp_iteration(self) -> Run:
        """
        Start one chirp-iteration step; the update runs when its last sample is in.

        Returns
        -------
        Run
            The started run; its ``done`` event is set when it finished or aborted.

        Raises
        ------
        RuntimeError
            The iteration has already converged or ran its ``max_iterations`` steps, no joint
            state received yet, or another procedure is still running.
        SafetyError
            The planned position leaves the position bound, the predicted peak torque (first
            step: on the model; later steps: from the measured ones) exceeds a limit, or
            (free-running) the joint states come at a fifth of the model's sample rate or
            less.

        """
        with self.lock:
            self._refuse_while_running()     # first: planning blocks the node for seconds
        it = self.chirp_iteration()
        if it.history and it.history[-1].get('converged'):
            raise RuntimeError('the chirp iteration has already converged')
        if len(it.history) >= self.s.chirp.max_iterations:
            raise RuntimeError(f'the chirp iteration ran its max_iterations='
                               f'{self.s.chirp.max_iterations} steps without converging '
                               f'(last error {it.history[-1].get("max_abs_error_db", "?")} dB)')
        last = it.history[-1] if it.history else {}
        pred = last.get('predicted_peak_torque')
        if pred is not None and np.any(np.asarray(pred) > self.torque_limit + 1e-9):
            raise SafetyError(f'predicted torque {pred} exceeds the limit '
                              f'{self.torque_limit.tolist()}; refusing to run')

        def end(run: Run) -> dict:
            r_runs = [r for (_k0, _k1, r) in run.stream.segments]
            u_runs = [fill_torque_gaps(run.u[i]) for i in range(len(run.stream.segments))]
            s = it.update(r_runs, u_runs)
            return {'procedure': 'chirp_iteration', 'iteration': s['iteration'],
                    'error_db': s['max_abs_error_db'],
                    'error_db_per_channel': np.asarray(s['error_db_per_channel']).tolist(),
                    'converged': bool(s['converged']),
                    'max_abs_torque': np.asarray(s['max_abs_torque']).tolist()}
        return self._start(f'chirp_iteration_{it.iteration}', it.phases(), True, end,
                           remedy=None if it.history else self.s.chirp.remedy())

    def stop_at_target(self, k_end: int, periods: int) -> bool:
        """
        End the running multisine where its uncertainty target was met (frf_ident/app/live.py).

        The running segment ends after its whole period ending at ``k_end``: its excitation
        fades out over ``STOP_FADE_S`` from the next reference not yet sent, an ``end``
        descriptor with ``stopped`` ``{t_end, periods}`` goes out (docs/CONTRACT.md §3), and
        the procedure's tail (ramp down, settle, move back) replaces the runs left. When the
        segment has ended already (its last period met the target), the tail follows it.

        Parameters
        ----------
        k_end : int
            One past the last sample of the period that met the target.
        periods : int
            The steady periods the segment holds up to there.

        Returns
        -------
        bool
            False when no multisine segment is running or just ended (nothing changed).

        """
        with self.lock:
            run = self.run
            if run is None or run.done.is_set() or not run.stream.segments:
                return False
            st = run.stream
            i = st.phase_index
            i_seg = max((j for j, ph in enumerate(st.phases[:i + 1]) if ph.segment is not None),
                        default=None)
            if i_seg is None or st.phases[i_seg].segment.get('design') != 'multisine':
                return False
            seg_ph = st.phases[i_seg]
            tail = multisine_tail(st.phases, i_seg)
            k0, k1, _ = st.segments[-1]
            if i == i_seg and k_end < k1:
                if not st.stop_segment(int(round(STOP_FADE_S * self.fs)), tail):
                    return False
                info = dict(seg_ph.segment, effort_lag=self.offset)
                d = json.loads(Segment(k0 * self.dt, k1 * self.dt, info).descriptor('end'))
                d['stopped'] = {'t_end': k_end * self.dt, 'periods': int(periods)}
                self.out.experiment(json.dumps(d, sort_keys=True))
            elif i - i_seg <= len(tail) - 2:
                st.replace_after_current(tail[i - i_seg:])
            else:
                return False
            self.out.log('info', f'{run.name}: uncertainty target met after {periods} '
                                 f'period(s) of segment {len(st.segments)}: the run ends')
            return True

    # -- safety -------------------------------------------------------------------------------
    def _abort(self, reason: str, level: str = 'error') -> None:
        """Ramp the reference to zero within abort_ramp_s (wall), publish zero, report."""
        run = self.run
        if run is None or run.done.is_set():
            return
        run.error = reason
        # the ramp goes out after the newest joint state (a stall or an abort before the run's
        # first joint state leaves next_k behind it: the recording would date it back)
        self.next_k = max(self.next_k, self.k_js + self.lag)
        run.end_k = self.next_k
        self.out.log(level, f'experiment {run.name!r} aborted: {reason}')
        steps = 4
        r0 = self.last_ref.copy()
        for s in range(1, steps + 1):
            self._publish(self.next_k, r0 * (1.0 - s / steps), np.zeros(self.n))
            self.next_k += 1
            if s < steps:
                time.sleep(self.s.abort_ramp_s / steps)
        self.out.experiment(_json(event='aborted', procedure=run.name, reason=reason,
                                  t_start=run.start_k * self.dt, t_end=self.next_k * self.dt))
        self.out.progress(self._progress(run, 'finished', success=False, error=reason,
                                         aborted=True))
        run.done.set()

    def watch(self) -> None:
        """
        Watchdog tick: abort the running procedure when the joint states went stale.

        Lockstep (simulation): in simulation time, the plant's clock ahead of the newest joint
        state by more than ``stale_s``; and in wall time only ``plant_silent_s`` without any
        joint state (a dead plant). Free-running (a robot): ``stale_samples`` sample times of
        wall time without a joint state.
        """
        with self.lock:
            run = self.run
            if run is None or run.done.is_set():
                return
            age = time.monotonic() - self.t_js
            if self.s.lockstep:
                reason = self._stale_lockstep(run, age)
            else:
                limit = self.s.stale_samples * self.dt
                if self.k_js <= run.start_k:
                    limit = max(limit, self.s.start_grace_s)
                reason = (f'/joint_states stale for {1e3 * age:.0f} ms (limit '
                          f'{1e3 * limit:.0f} ms)') if age > limit else None
            if reason is not None:
                self._abort(reason)

    def _stale_lockstep(self, run: Run, age: float) -> Optional[str]:
        """Lockstep: why the joint states count as stale (sim time, or a silent plant)."""
        if self.next_k <= self.k_js:
            return None             # nothing published waits for an answer
        if self.sim_now_ns is not None and self.k_js >= 0:
            lead = (self.sim_now_ns() - self.k_js * self.dt_ns) * 1e-9
            if lead > self.s.stale_s:
                return (f'/joint_states stale for {1e3 * lead:.0f} ms of simulation time '
                        f'(limit stale_s={1e3 * self.s.stale_s:.0f} ms): the plant ran on '
                        f'without them')
        limit = self.s.plant_silent_s
        if self.k_js <= run.start_k:
            limit = max(limit, self.s.start_grace_s)
        if age > limit:
            return (f'/joint_states stale for {1e3 * age:.0f} ms wall (limit '
                    f'plant_silent_s={1e3 * limit:.0f} ms): is the plant running?')
        return None

    def abort(self, reason: str) -> Optional[Run]:
        """
        Abort the running procedure on request (ramp to zero, ``aborted`` events).

        Parameters
        ----------
        reason
            Why (logged, and in the ``aborted`` descriptor and progress event).

        Returns
        -------
        Run or None
            The aborted run, None when no run was running.

        """
        with self.lock:
            run = self.run
            if run is None or run.done.is_set():
                return None
            self._abort(reason, level='warn')     # asked for: no error
            return run

    def close(self) -> None:
        """Abort a running procedure (shutdown)."""
        with self.lock:
            if self.run is not None and not self.run.done.is_set():
                self._abort('shutdown')


def fill_torque_gaps(u: np.ndarray, max_gap: int = MAX_TORQUE_GAP) -> np.ndarray:
    """
    Fill the torque samples of joint states the node missed, linearly between their neighbours.

    At an end of the segment the nearest sample is held.

    A free-running node acts on the newest joint state only, so a busy one misses some (their
    torque stays NaN). Gaps of up to ``max_gap`` samples are filled. A filled sample at a
    sine's crest at the chirp's 60 Hz and 1 kHz reads 7 % (one missed) or 16 % (two) low, but
    the step's peak and spectrum come from every sample over many cycles: with every third
    joint state missed the peak torque was 0.02 % off (test/app/test_excitation_safety.py).

    Parameters
    ----------
    u : ndarray, shape (N, n)
        Torque per sample [N m], NaN where no joint state was seen.
    max_gap : int, optional
        The longest run of missing samples that is filled.

    Returns
    -------
    ndarray, shape (N, n)
        ``u`` with its gaps filled.

    Raises
    ------
    RuntimeError
        A gap is longer than ``max_gap``.

    """
    miss = np.isnan(u).any(axis=1)
    if not miss.any():
        return u
    k = np.arange(len(u))
    edges = np.diff(np.r_[0, miss.astype(int), 0])
    longest = int((np.flatnonzero(edges < 0) - np.flatnonzero(edges > 0)).max())
    if longest > max_gap:
        raise RuntimeError(f'{int(miss.sum())} of {len(u)} torque samples missing from '
                           f'/joint_states, the longest gap {longest} samples (at most '
                           f'{max_gap} are filled): did the node fall behind '
                           'or the robot drop joint states?')
    out = u.copy()
    for j in range(u.shape[1]):
        out[miss, j] = np.interp(k[miss], k[~miss], u[~miss, j])
    return out


def _json(**d: Any) -> str:
    return json.dumps(d, sort_keys=True)
