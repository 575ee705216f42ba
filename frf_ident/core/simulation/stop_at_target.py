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
The offline multisine run with an uncertainty target: the same stop the excitation node makes.

Each segment runs period by period; :class:`~frf_ident.core.estimation.live.LiveMultisine`
estimates after every whole period and, once
:meth:`~frf_ident.core.estimation.target.UncertaintyTarget.met`, the segment ends there: its
excitation fades out over ``STOP_FADE_S`` and the procedure's tail (ramp down, settle, move
back) runs instead of the remaining runs (frf_ident/core/excitation/multisine_procedure.py
``multisine_tail``). The recording's segment then says how many periods it holds.
"""
from __future__ import annotations

from typing import Any, Callable

from frf_ident.core.estimation.live import LiveEstimate, LiveMultisine
from frf_ident.core.estimation.target import UncertaintyTarget
from frf_ident.core.excitation.multisine_procedure import multisine_tail, STOP_FADE_S
from frf_ident.core.excitation.procedures import Phase
from frf_ident.core.recording import Segment
import numpy as np

__all__ = ['run_multisine_to_target']


def _chunks(ph: Phase) -> list[tuple[int, int]]:
    """Sample ranges of a segment: its transient and first period, then one period each."""
    info = ph.segment
    n_per, n_tr = int(info['period_samples']), int(info['transient_periods'])
    edges = [0] + list(range((n_tr + 1) * n_per, ph.n_samples + 1, n_per))
    if edges[-1] != ph.n_samples:
        edges.append(ph.n_samples)
    return list(zip(edges[:-1], edges[1:]))


def run_multisine_to_target(loop: Any, phases: list[Phase], target: UncertaintyTarget,
                            on_estimate: Callable[[LiveEstimate], None] | None = None
                            ) -> dict[str, Any]:
    """
    Run a multisine procedure on ``loop`` (a ClosedLoop), stopping at ``target``.

    Parameters
    ----------
    loop : ClosedLoop
        The closed loop (frf_ident/core/simulation/runner.py), logging the run.
    phases : list of Phase
        The multisine procedure.
    target : UncertaintyTarget
        The stop rule (enabled).
    on_estimate : callable, optional
        Called with every live estimate.

    Returns
    -------
    dict
        ``stopped`` (bool), ``periods`` (MIMO periods of the final estimate), ``worst_sd_db``.

    """
    live = LiveMultisine(list(loop.plant.joint_names), 1.0 / loop.dt, 0)
    last: LiveEstimate | None = None
    i = 0
    while i < len(phases):
        ph = phases[i]
        if ph.segment is None:
            loop.run_phase(ph)
            i += 1
            continue
        k0, t0 = loop.k, loop.t
        live.start(ph.segment, k0, k0 + ph.n_samples)
        s = loop.engine.expand(ph, loop.q_last)
        stop_at = None
        for a, b in _chunks(ph):
            q, v, u = loop.run(s.reference[a:b], s.excitation[a:b])
            for done in live.block(k0 + a, q, v, u, s.excitation[a:b]):
                est = live.update(done)
                if est is None:
                    continue
                last = est
                if on_estimate is not None:
                    on_estimate(est)
                if target.met(est.magnitude_sd_db, done.periods):
                    stop_at = done
            if stop_at is not None:
                break
        if stop_at is None:
            loop.segments.append(Segment(t0, loop.t, dict(ph.segment)))
            i += 1
            continue
        info = dict(ph.segment)
        if stop_at.periods < int(info['periods']):
            info.update(periods=stop_at.periods, periods_planned=int(info['periods']))
        loop.segments.append(Segment(t0, stop_at.k_end * loop.dt, info))
        n_fade = max(1, int(round(STOP_FADE_S / loop.dt)))
        rest = ph.n_samples - (loop.k - k0)
        if rest > 0:
            n = min(n_fade, rest)
            w = 0.5 + 0.5 * np.cos(np.pi * (np.arange(n) + 1) / n)
            j = loop.k - k0
            exc = s.excitation[j:j + n] * w[:, None]
            loop.run(s.reference[j:j + n] - s.excitation[j:j + n] + exc, exc)
        for tail in multisine_tail(phases, i):
            loop.run_phase(tail)
        return {'stopped': True, 'periods': last.periods, 'worst_sd_db':
                target.worst_db(last.magnitude_sd_db)}
    return {'stopped': False, 'periods': None if last is None else last.periods,
            'worst_sd_db': None if last is None else target.worst_db(last.magnitude_sd_db)}
