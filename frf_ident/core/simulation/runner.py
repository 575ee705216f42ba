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
Offline runner: executes procedure phases in closed loop on a simulated or plug-in plant.

The plant is a :class:`~frf_ident.core.simulation.plant.FlexibleJointPlant` or another plant
with its batch ``simulate`` (run at compiled speed, the PI inside the kernel; MuJoCo's plant in
:mod:`frf_ident.io.mjcf.plant`) or any docs/CONTRACT.md §4 plug-in with ``dt``,
``joint_names``, ``reset()`` and ``step(torque) -> (position, velocity, effort)``, driven sample
by sample through the same
PI. Everything lands in one :class:`~frf_ident.core.recording.Recording` on a single timeline.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import logging
import math
import time
from typing import Any, Callable

from frf_ident.core.estimation.live import LiveEstimate
from frf_ident.core.estimation.target import UncertaintyTarget
from frf_ident.core.excitation.chirp_iteration import ChirpConfig, ChirpIteration
from frf_ident.core.excitation.engine import PhaseEngine
from frf_ident.core.excitation.multisine_procedure import multisine_procedure, MultisineConfig
from frf_ident.core.excitation.plan_checks import check_position_bound, check_torque_bound
from frf_ident.core.excitation.procedures import Phase, POSITION_GAIN
from frf_ident.core.model.params import RobotParams
from frf_ident.core.progress import Progress, sink
from frf_ident.core.recording import Recording, Segment
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.core.simulation.stop_at_target import run_multisine_to_target
from frf_ident.errors import FrfIdentInputError
import numpy as np

_log = logging.getLogger(__name__)


class ClosedLoop:
    """A plant in closed loop with the velocity PI; runs reference arrays and keeps the log."""

    def __init__(self, plant: Any, controller: PIVelocity,
                 position: np.ndarray | None = None,
                 origin: np.ndarray | None = None) -> None:
        for attr in ('dt', 'joint_names', 'reset', 'step'):
            if not hasattr(plant, attr):
                raise FrfIdentInputError(f'plant {type(plant).__name__} lacks {attr!r} '
                                         f'(docs/CONTRACT.md §4 plug-in interface)')
        self.plant = plant
        self.ctrl = controller
        self.dt = float(plant.dt)
        self.n = len(plant.joint_names)
        if controller.n_axes != self.n:
            raise FrfIdentInputError(f'controller has {controller.n_axes} axes, plant '
                                     f'{self.n} joints {plant.joint_names}')
        # a plant with the batch interface (our own, MuJoCo's) runs whole phases compiled
        self.fast = isinstance(plant, FlexibleJointPlant) or callable(
            getattr(plant, 'simulate', None))
        if position is not None and not self.fast:
            raise FrfIdentInputError('a start position needs a plant with simulate() and '
                                     'reset(position=): the plug-in interface resets to its '
                                     'own rest state')
        if self.fast:
            plant.reset(position=position)
        else:
            plant.reset()
        self.k = 0
        if self.fast:
            self.q_last = plant.state[0].copy()
            self.y_last = np.zeros(self.n)
        else:   # a plug-in reports a measurement only after a step: hold for one sample
            hold = np.asarray(controller.integral, dtype=float)
            q, v, _ = plant.step(hold)
            self.q_last, self.y_last = np.asarray(q, float), np.asarray(v, float)
        self.q0 = self.q_last.copy()
        # the same engine the excitation node streams; moves go to targets around ``origin``
        self.engine = PhaseEngine(self.q0 if origin is None else np.asarray(origin, float),
                                  self.dt)
        self.log: dict[str, list[np.ndarray]] = {k: [] for k in ('q', 'v', 'u', 'r', 'x')}
        self.segments: list[Segment] = []

    @property
    def t(self) -> float:
        return self.k * self.dt

    def run(self, reference: np.ndarray, excitation: np.ndarray | None = None,
            plan: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Run the reference (N, n); returns and logs (position, velocity, effort).

        With ``plan`` (N, n absolute positions) the reference gets position feedback
        r + POSITION_GAIN (plan - q), as for moves; the reference actually used is logged.
        """
        r = np.ascontiguousarray(reference, dtype=float)
        if self.fast:
            res = self.plant.simulate(reference=r, controller=self.ctrl, position_plan=plan,
                                      position_gain=POSITION_GAIN)
            q, v, u, r = res.position, res.velocity, res.effort, res.reference
            self.q_last = self.plant.state[0].copy()
        else:
            q, v, u = (np.empty_like(r) for _ in range(3))
            r = r.copy()
            for k in range(r.shape[0]):
                q[k], v[k] = self.q_last, self.y_last
                if plan is not None:
                    r[k] += POSITION_GAIN * (plan[k] - self.q_last)
                u[k] = self.ctrl.step(r[k], self.y_last)
                qn, vn, _ = self.plant.step(u[k])
                self.q_last, self.y_last = np.asarray(qn, float), np.asarray(vn, float)
        self.log['q'].append(q)
        self.log['v'].append(v)
        self.log['u'].append(u)
        self.log['r'].append(r)
        self.log['x'].append(np.zeros_like(r) if excitation is None else excitation)
        self.k += r.shape[0]
        return q, v, u

    def run_phase(self, ph: Phase) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Run one procedure phase from the current position; returns (q, v, u)."""
        t0 = self.t
        s = self.engine.expand(ph, self.q_last)
        out = self.run(s.reference, s.excitation, plan=s.plan)
        if ph.kind == 'excite' and ph.segment is not None:
            self.segments.append(Segment(t0, self.t, dict(ph.segment)))
        return out

    def recording(self, meta: dict[str, Any] | None = None) -> Recording:
        cat = {k: np.concatenate(v) if v else np.zeros((0, self.n)) for k, v in self.log.items()}
        t = np.arange(cat['q'].shape[0]) * self.dt
        return Recording(t, list(self.plant.joint_names), cat['q'], cat['v'], cat['u'],
                         cat['r'], cat['x'], list(self.segments), dict(meta or {}))


def predict_peak_torque(phases: list[Phase], robot: RobotParams, controller: PIVelocity,
                        position: np.ndarray | None = None,
                        origin: np.ndarray | None = None, plant: Any = None) -> np.ndarray:
    """
    Dry-run a plan on the nominal model and return the peak torque of every axis.

    The plan's phases run in closed loop with a copy of ``controller`` on a noiseless
    :class:`~frf_ident.core.simulation.plant.FlexibleJointPlant` of ``robot`` (its friction,
    gravity and other effects included), from rest at ``position``. What a robot will need is
    this plus what its model lacks: the runtime saturation check stays the last guard.

    Parameters
    ----------
    phases : list of Phase
        The plan, as :func:`~frf_ident.core.excitation.multisine_procedure.multisine_procedure` or
        :meth:`~frf_ident.core.excitation.chirp_iteration.ChirpIteration.phases` return it.
    robot : RobotParams
        The nominal model.
    controller : PIVelocity
        The velocity controller (not modified).
    position : array_like, shape (n,), optional
        Link positions [rad] the plan starts from (where the robot is now); default zero.
    origin : array_like, shape (n,), optional
        The operating point [rad] the plan's move targets are relative to; default
        ``position``.
    plant : object, optional
        A noiseless plant with ``simulate`` and ``reset(position=)`` to run the plan on instead
        (the MJCF of a model that names one, simulated by MuJoCo); default our plant of
        ``robot``.

    Returns
    -------
    ndarray, shape (n,)
        Peak absolute motor torque [N m] of every axis over the whole plan.

    """
    if plant is None:
        quiet = [replace(a, velocity_noise=0.0, torque_noise=0.0) for a in robot.axes]
        plant = FlexibleJointPlant(replace(robot, axes=quiet))
    ctrl = controller.copy()
    q0 = np.zeros(robot.n_axes) if position is None else np.asarray(position, dtype=float)
    ctrl.reset(plant.equilibrium_torque(q0))
    loop = ClosedLoop(plant, ctrl, position=q0, origin=origin)
    peak = np.zeros(loop.n)
    for ph in phases:
        _q, _v, u = loop.run_phase(ph)
        if u.size:
            peak = np.maximum(peak, np.max(np.abs(u), axis=0))
    return peak


def check_plan_torque(phases: list[Phase], robot: RobotParams, controller: PIVelocity,
                      torque_limit: np.ndarray, name: str, remedy: str,
                      position: np.ndarray | None = None,
                      origin: np.ndarray | None = None, plant: Any = None) -> np.ndarray:
    """
    Predict a plan's peak torque and refuse the plan when it reaches 0.95 of a limit.

    :func:`predict_peak_torque` followed by
    :func:`~frf_ident.core.excitation.plan_checks.check_torque_bound`: what the excitation node
    and ``identify`` run before every plan they can predict.

    Parameters
    ----------
    phases, robot, controller, position, origin, plant
        As for :func:`predict_peak_torque`.
    torque_limit : array_like, shape (n,)
        Torque limit [N m] of every axis.
    name : str
        The plan's name, for the message.
    remedy : str
        What lowers the plan's torque, for the message.

    Returns
    -------
    ndarray, shape (n,)
        The predicted peak torque [N m] of every axis.

    Raises
    ------
    SafetyError
        An axis' predicted peak reaches 0.95 of its limit.

    """
    peak = predict_peak_torque(phases, robot, controller, position, origin, plant)
    check_torque_bound(peak, torque_limit, robot.joint_names, name, remedy)
    return peak


@dataclass
class IdentificationConfig:
    multisine: MultisineConfig | None = field(default_factory=MultisineConfig)
    chirp: ChirpConfig | None = field(default_factory=ChirpConfig)
    #: the multisine ends at its first whole period meeting it (None or 0 dB: no target)
    target: UncertaintyTarget | None = None

    @property
    def position_bound(self) -> float:
        """Return the planned-position bound [rad]: the multisine's (its default without one)."""
        return math.radians((self.multisine or MultisineConfig()).position_bound_deg)


def run_identification(plant: Any, controller: PIVelocity,
                       config: IdentificationConfig | None = None, *,
                       progress: Progress | None = None,
                       meta: dict[str, Any] | None = None,
                       model: RobotParams | None = None, dry_run: Any = None,
                       on_estimate: Callable[[LiveEstimate], None] | None = None
                       ) -> Recording:
    """
    Run the Section 7 procedures (multisine with compensation run, iterated chirps).

    Parameters
    ----------
    plant : FlexibleJointPlant or plug-in
        The robot (docs/CONTRACT.md §4 interface).
    controller : PIVelocity
        The velocity controller in the loop.
    config : IdentificationConfig, optional
        The procedures; default both with their defaults.
    progress : callable, optional
        Called with one line per segment and per chirp iteration.
    meta : dict, optional
        Copied into the recording's metadata.
    model : RobotParams, optional
        The nominal model: the multisine plan and the first chirp step are refused when their
        peak torque predicted on it (:func:`predict_peak_torque`) reaches 0.95 of a limit,
        as the excitation node refuses them on a robot. None: no prediction.
    dry_run : object, optional
        The noiseless plant the prediction runs on instead of our plant of ``model``
        (:func:`predict_peak_torque`'s ``plant``).
    on_estimate : callable, optional
        Called with the multisine's live estimate after every whole MIMO period (as the
        excitation node publishes it); the run is the same with and without it.

    Returns
    -------
    Recording
        All segments on one timeline; ``meta['summary']`` holds per procedure the experiment
        time and, for the chirp iteration, every iteration's error to u_des.

    Raises
    ------
    SafetyError
        A plan's planned position or predicted torque is beyond its bound.

    """
    cfg = config or IdentificationConfig()
    say = sink(progress)
    loop = ClosedLoop(plant, controller)
    fs = 1.0 / loop.dt
    summary: dict[str, Any] = {}
    wall0 = time.perf_counter()
    # every plan is checked before anything runs: a refusal costs no experiment
    phases, design = (multisine_procedure(cfg.multisine, loop.n, fs)
                      if cfg.multisine is not None else (None, None))
    # the chirp's later steps are capped where their planned position would leave the bound,
    # as the excitation node's (frf_ident/app/excitation_plan.py)
    it = (ChirpIteration(cfg.chirp, loop.n, fs, controller.torque_limit,
                         position_bound=cfg.position_bound)
          if cfg.chirp is not None else None)
    for plan in (phases, it and it.phases()):
        if plan is not None:
            check_position_bound(plan, np.zeros(loop.n), cfg.position_bound, loop.dt)
    if model is not None:
        for name, plan, remedy in (('multisine', phases, cfg.multisine),
                                   ('chirp_iteration_1', it and it.phases(), cfg.chirp)):
            if plan is not None:
                peak = check_plan_torque(plan, model, controller, controller.torque_limit,
                                         name, remedy.remedy(), loop.q0, plant=dry_run)
                say(f"{name}: predicted peak torque {' / '.join(f'{p:.1f}' for p in peak)} N m "
                    'on the model (limits '
                    f"{' / '.join(f'{u:.0f}' for u in controller.torque_limit)} N m)")
    if phases is not None:
        t_start = loop.t
        n_exc = sum(1 for p in phases if p.segment)
        stop = None
        targeted = cfg.target is not None and cfg.target.enabled
        live = None
        if targeted or on_estimate is not None:
            live = run_multisine_to_target(loop, phases, cfg.target or UncertaintyTarget(),
                                           on_estimate)
        if targeted:
            stop = live
            say(f"multisine: {'stopped at' if stop['stopped'] else 'did not reach'} the "
                f'target {cfg.target.sd_db:g} dB after {stop["periods"]} periods (worst sd '
                f'{stop["worst_sd_db"]:.2f} dB)')
        if live is None:
            done = 0
            for ph in phases:
                loop.run_phase(ph)
                if ph.segment:
                    done += 1
                    _log.debug(f'multisine: segment {done}/{n_exc} ({ph.segment["design"]}, '
                               f'realisation {ph.segment["realisation"]}, '
                               f'experiment {ph.segment["experiment"]})')
        summary['multisine'] = {'experiment_time_s': loop.t - t_start, 'target': stop,
                                'segments': n_exc, 'lines': int(design.harmonics.size),
                                'period_s': design.period,
                                'constant_velocity':
                                    next(p.segment for p in phases if p.segment)[
                                        'constant_velocity']}
    if it is not None:
        t_start = loop.t
        iterations = []
        for _ in range(cfg.chirp.max_iterations):
            r_runs, u_runs = [], []
            plan = it.phases()
            if iterations:          # the first step was checked before anything ran
                check_position_bound(plan, np.zeros(loop.n), cfg.position_bound, loop.dt)
            for ph in plan:
                _, _, u = loop.run_phase(ph)
                if ph.segment:
                    r_runs.append(ph.reference)
                    u_runs.append(u)
            s = it.update(r_runs, u_runs)
            iterations.append(s)
            say(f"chirp iteration {s['iteration']}: max |u - u_des| "
                f"{s['max_abs_error_db']:.2f} dB, peak |u| "
                f"{max(s['max_abs_torque']):.1f} N m"
                + (' (converged)' if s['converged'] else ''))
            if s.get('position_cap'):
                say(f"chirp iteration {s['iteration']}: {it.position_cap.describe()}")
            if s['converged']:
                break
        summary['chirp'] = {'experiment_time_s': loop.t - t_start, 'iterations': iterations,
                            'converged': bool(iterations[-1]['converged']),
                            'final_iteration': iterations[-1]['iteration'],
                            'analysis_freq_hz': it.freqs.tolist(),
                            'torque_limit': controller.torque_limit.tolist()}
    summary['total_experiment_time_s'] = loop.t
    summary['wall_time_s'] = time.perf_counter() - wall0
    m = dict(meta or {})
    m['summary'] = summary
    m['operating_point'] = loop.q0.tolist()
    return loop.recording(m)
