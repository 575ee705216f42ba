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
The excitation session's planning: a procedure planned, checked and started, or cut short.

Safety: a plan is checked before it runs: its planned position against the position bound,
and its peak torque, predicted by a dry run on the model from where the robot is (the
multisine plan with its moves, and the first chirp step; later chirp steps from what the
previous ones measured), against 0.95 of each limit. Free-running, a run starts at the first
joint state after its start (the node's executor was busy planning).

:class:`SessionPlanning` is a part of :class:`frf_ident.app.excitation.ExcitationSession`.
"""
from __future__ import annotations

import json
import time
from typing import Callable, Optional

from frf_ident.app.excitation_run import Run
from frf_ident.app.excitation_torque import fill_torque_gaps
from frf_ident.core.excitation.chirp_iteration import ChirpIteration
from frf_ident.core.excitation.engine import PhaseStream
from frf_ident.core.excitation.multisine_procedure import (multisine_procedure, multisine_tail,
                                                           STOP_FADE_S)
from frf_ident.core.excitation.plan_checks import check_position_bound
from frf_ident.core.recording import Segment
from frf_ident.core.simulation.runner import check_plan_torque
from frf_ident.errors import SafetyError
import numpy as np

__all__ = ['SessionPlanning']


class SessionPlanning:
    """The session's starts: the multisine, the chirp iteration's steps, a stop at target."""

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

        Its later steps are capped where their planned position would leave the plan's
        position bound (:mod:`frf_ident.core.excitation.chirp_position`): the plan check
        refuses such a step, so the iteration must not ask for one.

        Returns
        -------
        ChirpIteration
            The session's chirp iteration, kept across its steps.

        """
        if self.chirp is None:
            self.chirp = ChirpIteration(self.s.chirp, self.n, self.fs, self.torque_limit,
                                        position_bound=self.bound)
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
            if s.get('position_cap'):
                self.out.log('info', f'chirp iteration {s["iteration"] + 1}: '
                                     f'{it.position_cap.describe()}')
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
