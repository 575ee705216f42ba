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
The excitation session's running part: joint states in, references and descriptors out.

Timing: sample k has stamp k*dt. ``lockstep`` (simulation): references go up to ``lookahead``
samples ahead of the newest joint state and the controller consumes them in order; a 'move' or
'settle' sample waits for the joint state of that very sample. Free-running (a real robot, or
the plant on a wall timer): on joint state k the reference of sample k+1 goes out, computed from
the position at k.

:class:`SessionStreaming` is a part of :class:`frf_ident.app.excitation.ExcitationSession`
(its state is set up there); each joint state is checked against the live bounds and the torque
limit, and the watchdog's abort (:mod:`frf_ident.app.excitation_watch`) stops a run that
fails them.
"""
from __future__ import annotations

import math
import time
from typing import Any, Optional

from frf_ident.app.excitation_run import event_json, Run
from frf_ident.app.excitation_settings import SATURATION
from frf_ident.core.excitation.engine import PhaseEngine, PhaseStream, SegmentEvent
from frf_ident.core.recording import Segment
import numpy as np

__all__ = ['SessionStreaming']


class SessionStreaming:
    """The session's streaming: each joint state checked, the references it allows sent."""

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
            Measured effort [N m] (the torque of sample ``k - offset``, see
            :mod:`frf_ident.app.excitation_torque`), or None when the message carries none.

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
        self.out.experiment(event_json(event='procedure_end', procedure=run.name,
                                       t_start=run.start_k * self.dt,
                                       t_end=run.end_k * self.dt, steps_per_s=rate))
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

    def _anchor(self, run: Run, k: int) -> None:
        """Free-running: start the run's stream at joint state ``k``, the first after start."""
        self.next_k = k + self.lag
        run.stream = PhaseStream(self.engine, run.stream.phases, self.next_k)
        run.start_k = self.next_k
        run.anchored = True
