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
The live estimate of the excitation node: samples in, estimates, warnings and the stop out.

Why the excitation node: it takes every joint state in order already, knows each sample's
excitation and the segment boundaries exactly, and it is the node that must end the run when
the target is met (an estimate made elsewhere would reach it a loop's round trip later).

:class:`LiveMonitor` gets, in the node's executor thread, each segment descriptor, each
sample's excitation and each joint state (a few array writes: the 1 kHz loop does not notice).
A worker thread does the rest after every whole period: the BLA of the periods so far
(frf_ident/core/estimation/live.py), the frames for /frf/live/frf, /frf/live/distortion and
/frf/live/summary (frf_ident/io/live_frame.py), the early warnings, and, when the
uncertainty target is met, :meth:`frf_ident.app.excitation.ExcitationSession.stop_at_target`.
"""
from __future__ import annotations

import json
import math
import queue
import threading
from typing import Any, Callable, Optional, Protocol

from frf_ident.core.estimation.early_warnings import EarlyWarning, WarningMonitor
from frf_ident.core.estimation.live import LiveEstimate, LiveMultisine, PeriodDone
from frf_ident.core.estimation.target import UncertaintyTarget
from frf_ident.io.live_frame import (ArrayFrame, distortion_frame, frf_frame, LINE_SLOTS,
                                     summary_frame)
import numpy as np

__all__ = ['EstimateOut', 'LiveMonitor', 'LiveOutputs', 'periods_left', 'status_line']


class LiveOutputs(Protocol):
    """Where the live stream goes (the node implements it with publishers)."""

    def live_frame(self, topic: str, frame: ArrayFrame) -> None:
        """Publish a frame (topic: frf, distortion or summary under /frf/live)."""

    def warning(self, event: dict[str, Any]) -> None:
        """Publish an early warning, a JSON-ready dict, on the warnings topic."""

    def progress(self, event: dict[str, Any]) -> None:
        """Publish a progress event (the session's /frf/progress)."""

    def log(self, level: str, text: str) -> None:
        """Write a log line."""


def periods_left(est: LiveEstimate, target: UncertaintyTarget) -> Optional[int]:
    """
    Return the MIMO periods the run is predicted to take still.

    With a target: its prediction (sd ~ 1/sqrt(periods)), at most the design's periods left;
    without one: the design's periods left (the run goes to its cap).

    Parameters
    ----------
    est : LiveEstimate
        The newest estimate.
    target : UncertaintyTarget
        The run's stop rule (``sd_db`` 0: none).

    Returns
    -------
    int or None
        None when neither is known.

    """
    cap = (None if est.planned_periods is None
           else max(0, est.planned_periods - est.periods))
    left = target.periods_left(est.magnitude_sd_db, est.periods)
    if left is None:
        return cap if not target.enabled else None
    return left if cap is None else min(left, cap)


def status_line(est: LiveEstimate, target: UncertaintyTarget) -> str:
    """
    Return the one line a person follows: periods, worst sd, target and periods left.

    Parameters
    ----------
    est : LiveEstimate
        The newest estimate.
    target : UncertaintyTarget
        The run's stop rule (``sd_db`` 0: none).

    Returns
    -------
    str
        e.g. 'multisine: 9 periods (2 realisations), worst sd 0.62 dB (target 0.50 dB),
        ~5 periods left'.

    """
    worst = target.worst_db(est.magnitude_sd_db)
    text = (f'multisine: {est.periods} periods ({est.realisations} realisation'
            f'{"s" if est.realisations != 1 else ""}), worst sd '
            + (f'{worst:.2f} dB' if math.isfinite(worst) else 'undefined'))
    if target.enabled:
        text += f' (target {target.sd_db:g} dB)'
    left = periods_left(est, target)
    if left is not None:
        text += f', ~{left} period{"" if left == 1 else "s"} left'
    return text


class EstimateOut:
    """
    Publish each live estimate: the three frames, the progress event and its status line.

    Parameters
    ----------
    target : UncertaintyTarget
    out : LiveOutputs

    """

    def __init__(self, target: UncertaintyTarget, out: LiveOutputs) -> None:
        self.target, self.out = target, out
        self.wide = False

    def publish(self, est: LiveEstimate) -> None:
        """
        Publish one estimate.

        Parameters
        ----------
        est : LiveEstimate
            The newest estimate.

        """
        f = est.frf
        if f.freq_hz.size > LINE_SLOTS and not self.wide:
            self.wide = True
            self.out.log('warn', f'live view: {f.freq_hz.size} lines, the first {LINE_SLOTS} '
                                 f'are published (the estimate at the end has all)')
        sd = est.magnitude_sd_db
        self.out.live_frame('frf', frf_frame(f.freq_hz, f.response, sd, est.phase_sd_deg,
                                             est.coherence, f.outputs, f.inputs))
        if f.distortion is not None:
            self.out.live_frame('distortion', distortion_frame(f.distortion.to_dict()))
        worst = self.target.worst_db(sd)
        left = periods_left(est, self.target)
        self.out.live_frame('summary', summary_frame({
            't_s': est.t, 'periods': est.periods, 'realisations': est.realisations,
            'worst_sd_db': worst, 'target_sd_db': self.target.sd_db, 'periods_left': left,
            'final': float(est.final), 'min_coherence': float(np.nanmin(est.coherence))
            if np.any(np.isfinite(est.coherence)) else None}))
        line = status_line(est, self.target)
        self.out.progress({'event': 'estimate', 'periods': est.periods,
                           'worst_sd_db': round(worst, 4) if math.isfinite(worst) else None,
                           'target_sd_db': self.target.sd_db, 'periods_left': left,
                           't': round(est.t, 3), 'line': line})
        self.out.log('info', line)


class LiveMonitor:
    """
    Follow a streamed procedure; estimate, publish, warn and stop (module docstring).

    Parameters
    ----------
    joints : list of str
        Joint names (model order).
    dt : float
        Sample time [s].
    effort_lag : int
        Joint state k carries the torque of sample ``k - effort_lag``.
    torque_limit : ndarray, shape (n,)
        Per axis [N m] (warnings).
    target : UncertaintyTarget
        The stop rule (``sd_db`` 0: estimates only).
    out : LiveOutputs
        Where frames, warnings and lines go.
    stop : callable, optional
        ``stop(k_end, periods) -> bool``: end the run after that period (the session's
        ``stop_at_target``); None: never stop.

    """

    def __init__(self, joints: list[str], dt: float, effort_lag: int,
                 torque_limit: np.ndarray, target: UncertaintyTarget, out: LiveOutputs,
                 stop: Optional[Callable[[int, int], bool]] = None) -> None:
        self.joints, self.dt, self.lag = list(joints), float(dt), int(effort_lag)
        self.limit = np.asarray(torque_limit, float)
        self.target, self.out, self.stop_cb = target, out, stop
        self.lock = threading.Lock()
        self.jobs: queue.Queue = queue.Queue()
        self.estimates = 0
        self._reset()
        self.worker = threading.Thread(target=self._work, daemon=True, name='live-estimate')
        self.worker.start()

    def _reset(self) -> None:
        self.live = LiveMultisine(self.joints, 1.0 / self.dt, self.lag)
        self.warnings = WarningMonitor(self.joints, self.limit)
        self.peak = np.zeros(len(self.joints))
        self.stopped = False
        self.publisher = EstimateOut(self.target, self.out)

    # -- the executor thread (per message) -----------------------------------------------------
    def experiment(self, text: str) -> None:
        """
        Take a descriptor or event the session sent on /frf/experiment.

        Parameters
        ----------
        text : str
            Its JSON text.

        """
        d = json.loads(text)
        event = d.get('event')
        if event == 'start' and d.get('design') in ('multisine', 'constant_velocity'):
            with self.lock:
                self.live.start(d, int(round(d['t_start'] / self.dt)),
                                int(round(d['t_end'] / self.dt)))
        elif event in ('procedure_end', 'aborted'):
            self.jobs.put(('reset', event))

    def reference(self, k: int, x: np.ndarray) -> None:
        """
        Take the excitation part of sample ``k``.

        Parameters
        ----------
        k : int
            Sample index.
        x : ndarray, shape (n,)
            The excitation part of the velocity reference [rad/s].

        """
        if self.live.open:
            with self.lock:
                self.live.excitation(k, x)

    def state(self, k: int, q: np.ndarray, y: np.ndarray, effort: Optional[np.ndarray]) -> None:
        """
        Take joint state ``k`` (model joint order).

        Parameters
        ----------
        k : int
            Sample index (the joint state's stamp / dt).
        q, y : ndarray, shape (n,)
            Position [rad], velocity [rad/s].
        effort : ndarray, shape (n,) or None
            Torque [N m] of sample ``k - effort_lag``.

        """
        if not self.live.open:
            return
        with self.lock:
            done = self.live.sample(k, q, y, effort)
        if effort is not None and len(effort):
            np.maximum(self.peak, np.abs(effort), out=self.peak)
        for d in done:
            self.jobs.put(('period', d))

    def close(self) -> None:
        """Stop the worker (what is queued is dropped)."""
        self.jobs.put(('close', None))
        self.worker.join(2.0)

    # -- the worker thread ---------------------------------------------------------------------
    def _work(self) -> None:
        while True:
            kind, item = self.jobs.get()
            if kind == 'close':
                return
            try:
                if kind == 'reset':
                    self._reset()
                elif not self.stopped:
                    self._period(item)
            except Exception as exc:      # the run goes on without its live view
                self.out.log('error', f'live estimate failed: {type(exc).__name__}: {exc}')

    def _period(self, done: PeriodDone) -> None:
        for w in self.warnings.torque(self.peak.copy(), done.k_end * self.dt):
            self._warn(w)
        est = self.live.update(done)
        if est is None:
            return
        self.estimates += 1
        self.publisher.publish(est)
        for w in self.warnings.estimate(est):
            self._warn(w)
        sd = est.magnitude_sd_db
        if self.stop_cb is not None and self.target.met(sd, done.periods) and \
                self.stop_cb(done.k_end, done.periods):
            self.stopped = True
            with self.lock:
                if done.key in self.live.segments and not done.last:
                    self.live.stop(done.key, done.k_end)

    def _warn(self, w: EarlyWarning) -> None:
        self.out.warning(w.to_dict())
        self.out.log('warn', f'early warning ({w.kind}): {w.message}')
