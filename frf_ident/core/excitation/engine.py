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
The one move/settle/excite phase engine, used offline (runner) and streamed (excitation node).

A procedure is a list of :class:`~frf_ident.core.excitation.procedures.Phase`. What a phase
sends depends on where the robot is when it starts: a 'move' plans from the measured position to
its target (relative to the operating point), a 'settle' holds the position the move planned to
reach (or the measured one), an 'excite' plays its reference. :class:`PhaseEngine` turns a phase
and the measured position into :class:`PhaseSamples` (feed-forward reference, excitation part,
optional position plan); :class:`PhaseStream` walks a whole procedure sample by sample for a
node that publishes one reference per joint state.

The offline :class:`~frf_ident.core.simulation.runner.ClosedLoop` runs each PhaseSamples as one
array (compiled plant); the excitation node calls :meth:`PhaseStream.next_sample` per sample.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from frf_ident.core.excitation.procedures import move_plan, Phase, POSITION_GAIN
import numpy as np

__all__ = ['PhaseEngine', 'PhaseSamples', 'PhaseStream', 'SegmentEvent', 'StreamSample']


@dataclass
class PhaseSamples:
    """
    What one phase sends, sample by sample.

    ``reference`` (N, n) is the feed-forward velocity reference, ``excitation`` (N, n) its
    excitation part, ``plan`` (N, n absolute positions, or None) the position plan the reference
    follows with feedback ``POSITION_GAIN (plan - q)``.

    Parameters
    ----------
    phase : Phase
        The phase these samples belong to.
    reference : ndarray, shape (N, n)
        Feed-forward velocity reference [rad/s] of the N samples for the n joints.
    excitation : ndarray, shape (N, n)
        Excitation part of ``reference`` [rad/s] (zero for move and settle phases).
    plan : ndarray, shape (N, n), optional
        Absolute position plan [rad] followed with position feedback (move, settle); None
        for an excite phase (the reference is sent as is).

    """

    phase: Phase
    reference: np.ndarray
    excitation: np.ndarray
    plan: np.ndarray | None = None

    @property
    def held(self) -> bool:
        """Tell whether each sample needs the position measured at it (move, settle)."""
        return self.plan is not None

    def command(self, i: int, q: np.ndarray | None) -> np.ndarray:
        """
        Velocity reference of sample ``i`` given the position ``q`` measured at it.

        Parameters
        ----------
        i
            Sample index within the phase.
        q
            Measured position at that sample (used only when the phase has a plan).

        Returns
        -------
        np.ndarray
            The reference to send, (n,).

        """
        if self.plan is None:
            return self.reference[i]
        return self.reference[i] + POSITION_GAIN * (self.plan[i] - q)


class PhaseEngine:
    """
    Expands phases into samples around the operating point ``q0``.

    Parameters
    ----------
    q0
        Operating point (absolute position [rad], the first measurement).
    dt
        Sample time [s].

    """

    def __init__(self, q0: np.ndarray, dt: float) -> None:
        self.q0 = np.asarray(q0, dtype=float).copy()
        self.n = self.q0.size
        self.dt = float(dt)
        self.hold: np.ndarray | None = None    # position a settle holds after a move

    def expand(self, ph: Phase, q_now: np.ndarray) -> PhaseSamples:
        """
        Expand phase ``ph`` into samples, starting at the measured position ``q_now``.

        Parameters
        ----------
        ph
            The phase.
        q_now
            Position measured at the phase's first sample.

        Returns
        -------
        PhaseSamples
            Reference, excitation and (move/settle) position plan.

        """
        if ph.kind == 'excite':
            exc = ph.excitation if ph.excitation is not None else np.zeros_like(ph.reference)
            return PhaseSamples(ph, ph.reference, exc)
        if ph.kind == 'move':
            ref, plan = move_plan(q_now, self.q0 + ph.target, ph.n_samples, self.dt)
            self.hold = plan[-1]
            return PhaseSamples(ph, ref, np.zeros_like(ref), plan)
        if ph.kind == 'settle':
            hold = np.asarray(q_now, float) if self.hold is None else self.hold
            self.hold = None
            zeros = np.zeros((ph.n_samples, self.n))
            return PhaseSamples(ph, zeros, zeros, np.tile(hold, (ph.n_samples, 1)))
        raise ValueError(f'unknown phase kind {ph.kind!r}')


@dataclass
class SegmentEvent:
    """
    A segment (an excitation phase with a descriptor) starting or ending at samples k0..k1.

    Parameters
    ----------
    event : str
        'start' or 'end'.
    info : dict
        The phase's segment descriptor (design, parameters ...).
    k0 : int
        Stream sample index of the segment's first sample.
    k1 : int
        Stream sample index one past the segment's last sample (k0 + number of samples).
    index : int
        Segment number within the stream (0 for the first segment).

    """

    event: str                 # 'start' | 'end'
    info: dict[str, Any]
    k0: int
    k1: int
    index: int                 # segment number within the stream


@dataclass
class StreamSample:
    """
    One streamed sample: reference, excitation part and the segment events at it.

    Parameters
    ----------
    k : int
        Sample index (stamp k dt).
    reference : ndarray, shape (n,)
        Velocity reference [rad/s] to send, position feedback included.
    excitation : ndarray, shape (n,)
        Excitation part of the reference [rad/s].
    events : list of SegmentEvent, optional
        'start' of a segment beginning at this sample, 'end' of one ending with it (usually
        none).

    """

    k: int
    reference: np.ndarray
    excitation: np.ndarray
    events: list[SegmentEvent] = field(default_factory=list)


class PhaseStream:
    """
    A procedure streamed one sample at a time from sample index ``start_k``.

    Parameters
    ----------
    engine
        The phase engine (operating point, move/settle bookkeeping).
    phases
        The procedure.
    start_k
        Sample index of the first sample.

    """

    def __init__(self, engine: PhaseEngine, phases: list[Phase], start_k: int) -> None:
        self.engine = engine
        self.phases = list(phases)
        self.k = int(start_k)
        self.total = sum(p.n_samples for p in self.phases)
        self.sent = 0
        self._i_phase = 0
        self._i = 0
        self._cur: PhaseSamples | None = None
        #: (k0, k1, reference) of every segment started so far
        self.segments: list[tuple[int, int, np.ndarray]] = []

    @property
    def done(self) -> bool:
        """Tell whether every sample has been produced."""
        return self._i_phase >= len(self.phases)

    def needs_measurement(self) -> bool:
        """
        Tell whether the next sample needs the position measured at that very sample.

        Returns
        -------
        bool
            True when the next sample belongs to a move or settle phase (position
            feedback); False for an excite phase or when the stream is done.

        """
        if self.done:
            return False
        if self._cur is not None:
            return self._cur.held
        return self.phases[self._i_phase].kind in ('move', 'settle')

    @property
    def phase_index(self) -> int:
        """Return the index in :attr:`phases` of the phase the next sample belongs to."""
        return self._i_phase

    def replace_after_current(self, then: list[Phase]) -> None:
        """
        Run ``then`` after the current phase instead of the rest of the procedure.

        Parameters
        ----------
        then : list of Phase
            The phases that follow the current one.

        """
        keep = self._i_phase + (1 if self._cur is not None else 0)
        self.phases = self.phases[:keep] + list(then)
        self.total = (self.sent - self._i + sum(p.n_samples for p in self.phases[self._i_phase:]))

    def stop_segment(self, n_fade: int, then: list[Phase]) -> bool:
        """
        End the running excite segment from the next sample: fade out, then run ``then``.

        The excitation part of the segment's remaining samples fades to zero over
        ``n_fade`` samples (a raised cosine; the constant velocity under it goes on, so the
        position stays inside the segment's planned path), after which ``then`` replaces the
        rest of the procedure. No 'end' event follows for the segment: the caller reports
        where it stopped.

        Parameters
        ----------
        n_fade : int
            Samples of the fade (at most the segment's remaining ones).
        then : list of Phase
            The phases to run after the fade (the procedure's tail).

        Returns
        -------
        bool
            False when no segment is running (nothing changed).

        """
        if self.done or self._cur is None or self.phases[self._i_phase].segment is None:
            return False
        ph, i = self.phases[self._i_phase], self._i
        n = max(1, min(int(n_fade), ph.n_samples - i))
        w = 0.5 + 0.5 * np.cos(np.pi * (np.arange(n) + 1) / n)
        exc = ph.excitation[i:i + n] * w[:, None]
        base = ph.reference[i:i + n] - ph.excitation[i:i + n]
        fade = Phase('excite', n, reference=base + exc, excitation=exc)
        self.phases = self.phases[:self._i_phase] + [fade] + list(then)
        self._i, self._cur = 0, None
        self.total = self.sent + sum(p.n_samples for p in self.phases[self._i_phase:])
        return True

    def next_sample(self, q: np.ndarray | None) -> StreamSample:
        """
        Produce the next sample, given the newest measured position ``q``.

        Parameters
        ----------
        q
            Position measured at the sample (required when :meth:`needs_measurement`).

        Returns
        -------
        StreamSample
            Index, reference, excitation and segment start/end events.

        """
        if self.done:
            raise IndexError('the procedure has no more samples')
        ph = self.phases[self._i_phase]
        events = []
        if self._cur is None:
            self._cur = self.engine.expand(ph, q)
            if ph.segment is not None:
                k0, k1 = self.k, self.k + ph.n_samples
                self.segments.append((k0, k1, ph.reference))
                events.append(SegmentEvent('start', ph.segment, k0, k1,
                                           len(self.segments) - 1))
        cur, i = self._cur, self._i
        out = StreamSample(self.k, cur.command(i, q), cur.excitation[i], events)
        self.k += 1
        self.sent += 1
        self._i += 1
        if self._i >= ph.n_samples:
            if ph.segment is not None:
                k0, k1, _ = self.segments[-1]
                events.append(SegmentEvent('end', ph.segment, k0, k1, len(self.segments) - 1))
            self._i_phase += 1
            self._i = 0
            self._cur = None
        return out
