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
The excitation session's watchdog: stale joint states, the joint-state rate, the abort.

A run aborts when /joint_states is stale, the node missed more than ``stale_samples`` joint
states, a measured position leaves the live bound or a measured torque reaches its limit: the
reference ramps to zero, a zero reference is published and an ``aborted`` descriptor sent.
Free-running, one reference goes out per joint state, so the joint states must come at the
model's sample rate: a run is refused, or aborted, when they come regularly at a fifth of that
rate or less (the steps between the newest ``RATE_WINDOW``).

:class:`SessionWatchdog` is a part of :class:`frf_ident.app.excitation.ExcitationSession`.
"""
from __future__ import annotations

import time
from typing import Iterator, Optional

from frf_ident.app.excitation_run import event_json, Run
from frf_ident.app.excitation_settings import (abort_ramp_steps, RATE_WINDOW, REGULAR,
                                               SLOW_STEP)
import numpy as np

__all__ = ['paced', 'SessionWatchdog']


def paced(steps: int, period: float) -> Iterator[int]:
    """
    Yield 1 .. ``steps``, step s at ``(s - 1) * period`` after the first (wall time).

    Each step waits for its own time from the first, so sleeps that overshoot on a loaded PC
    do not add up over the abort ramp's 10 steps at 1 kHz (test/nodes/test_graph.py
    test_kill_plant once saw the zero reference 50.5 ms after the kill, its limit 50; ``python
    -m benchmarks.abort_ramp`` times it against sleeps one after the other).
    """
    t0 = time.monotonic()
    for s in range(1, steps + 1):
        yield s
        if s < steps:
            time.sleep(max(t0 + s * period - time.monotonic(), 0.0))


class SessionWatchdog:
    """The session's safety: the watchdog tick, the rate check and the abort."""

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
        steps = abort_ramp_steps(self.s.abort_ramp_s, self.dt)
        r0 = self.last_ref.copy()
        for s in paced(steps, self.s.abort_ramp_s / steps):
            self._publish(self.next_k, r0 * (1.0 - s / steps), np.zeros(self.n))
            self.next_k += 1
        self.out.experiment(event_json(event='aborted', procedure=run.name, reason=reason,
                                       t_start=run.start_k * self.dt,
                                       t_end=self.next_k * self.dt))
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

        The age counts from when the node took the newest joint state, not from when it
        came: joint states queued while the node planned a run count as fresh when worked
        through, so a robot that died in the planning is seen once the queue is empty (the
        planning time plus ``stale_samples`` later; test/nodes/test_free_running.py).
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
