"""
In-memory recording of an identification run.

The neutral form between runner, bag and estimator.

A :class:`Recording` holds uniformly sampled time series of all joints plus the experiment
segments (what was excited when). The bag adapter writes it to the docs/CONTRACT.md §3 topics
and reads it back; the estimators only ever see a Recording, so estimation from a bag equals
estimation from the in-memory run.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import json
from typing import Any

from frf_ident.core.jsonable import json_default
import numpy as np


@dataclass
class Segment:
    """
    One experiment segment (docs/CONTRACT.md §3, /frf/experiment descriptor).

    ``info`` carries everything estimation needs and is JSON-serialisable. Keys used by the
    estimators (see ``frf_ident.core.excitation.procedures``):

    - ``design``: 'multisine' | 'chirp' | 'constant_velocity' | 'idle'
    - ``procedure``: name of the procedure (e.g. 'multisine_bla', 'chirp_iteration')
    - ``experiment``: MIMO experiment index m (0-based)
    - ``realisation``: multisine realisation p (0-based)
    - ``periods`` / ``transient_periods`` / ``period_samples``: multisine timing
    - ``freq_hz``: excited (multisine) or analysed (chirp) frequencies
    - ``f_low``, ``f_high``, ``t_sweep``: chirp design
    - ``iteration``: chirp iteration number (1-based)
    """

    t_start: float
    t_end: float
    info: dict[str, Any] = field(default_factory=dict)

    def descriptor(self, event: str) -> str:
        """JSON text published on /frf/experiment at segment start (event='start') or end."""
        d = {'event': event, 't_start': float(self.t_start), 't_end': float(self.t_end)}
        d.update(self.info)
        return json.dumps(d, sort_keys=True, default=json_default)

    @classmethod
    def from_descriptor(cls, text: str) -> tuple[str, 'Segment']:
        d = json.loads(text)
        event = d.pop('event', 'start')
        t0 = float(d.pop('t_start'))
        t1 = float(d.pop('t_end'))
        return event, cls(t0, t1, d)


@dataclass
class Recording:
    """
    Uniformly sampled closed-loop data.

    Attributes
    ----------
    t : (N,) sample times [s] (uniform, spacing ``dt``)
    joint_names : names, length n
    position, velocity, effort : (N, n) measured position [rad], velocity y [rad/s],
        applied motor torque u [N m]
    reference : (N, n) velocity reference r [rad/s] (NaN where none was commanded)
    excitation : (N, n) the excitation part of r (the reference minus offsets / constant velocity)
    segments : experiment segments, in time order
    meta : free-form (model, seed, summaries of procedures)

    """

    t: np.ndarray
    joint_names: list[str]
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    reference: np.ndarray | None = None
    excitation: np.ndarray | None = None
    segments: list[Segment] = field(default_factory=list)
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=float).reshape(-1)
        n = len(self.joint_names)
        for name in ('position', 'velocity', 'effort', 'reference', 'excitation'):
            val = getattr(self, name)
            if val is None:
                continue
            val = np.asarray(val, dtype=float)
            if val.ndim == 1:
                val = val[:, None]
            if val.shape != (self.t.size, n):
                raise ValueError(f'{name} shape {val.shape} != ({self.t.size}, {n})')
            setattr(self, name, val)

    @property
    def dt(self) -> float:
        if self.t.size < 2:
            raise ValueError('recording has fewer than 2 samples')
        return float(np.median(np.diff(self.t)))

    @property
    def fs(self) -> float:
        return 1.0 / self.dt

    def index_of(self, t: float) -> int:
        """Index of the sample at (or first after) time t."""
        return int(np.searchsorted(self.t, t - 0.25 * self.dt))

    def slice(self, t_start: float, t_end: float) -> slice:  # noqa: A003
        """Sample slice covering [t_start, t_end)."""
        return slice(self.index_of(t_start), self.index_of(t_end))

    def segments_where(self, **match: Any) -> list[Segment]:
        """Segments whose info matches every given key/value."""
        return [s for s in self.segments if all(s.info.get(k) == v for k, v in match.items())]
