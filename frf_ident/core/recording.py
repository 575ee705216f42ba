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

__all__ = ['JOINT_STATE_FRF_UNIT', 'JOINT_STATE_UNITS', 'Recording', 'Segment']


@dataclass
class Segment:
    """
    One experiment segment (docs/CONTRACT.md §3, /frf/experiment descriptor).

    Parameters
    ----------
    t_start, t_end : float
        The segment's time span [t_start, t_end) in s.
    info : dict, optional
        Everything estimation needs, JSON-serialisable (see below).

    Notes
    -----
    Keys of ``info`` used by the estimators (see ``frf_ident.core.excitation.procedures``, the
    procedures' modules ``multisine_procedure`` and ``chirp_iteration``):

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
        """
        Return the JSON text published on /frf/experiment at the segment's start or end.

        Parameters
        ----------
        event : str
            ``'start'`` or ``'end'``.

        Returns
        -------
        str
            JSON object with ``event``, ``t_start``, ``t_end`` and the ``info`` keys, keys
            sorted, numpy values converted.

        """
        d = {'event': event, 't_start': float(self.t_start), 't_end': float(self.t_end)}
        d.update(self.info)
        return json.dumps(d, sort_keys=True, default=json_default)

    @classmethod
    def from_descriptor(cls, text: str) -> tuple[str, 'Segment']:
        """
        Parse a descriptor written by :meth:`descriptor`.

        Parameters
        ----------
        text : str
            The JSON text.

        Returns
        -------
        event : str
            The descriptor's ``event`` (``'start'`` when absent).
        segment : Segment
            The segment; every other key goes to ``info``.

        Raises
        ------
        json.JSONDecodeError
            ``text`` is not JSON.
        KeyError
            ``t_start`` or ``t_end`` is missing.

        """
        d = json.loads(text)
        event = d.pop('event', 'start')
        t0 = float(d.pop('t_start'))
        t1 = float(d.pop('t_end'))
        return event, cls(t0, t1, d)


#: the units of a revolute joint's sensor_msgs/JointState fields (REP 103: SI), which a
#: recording has where an import map states no others
JOINT_STATE_UNITS = {'position': 'rad', 'velocity': 'rad/s', 'effort': 'N m'}
#: the unit of an FRF from motor torque to motor velocity of such a joint
JOINT_STATE_FRF_UNIT = f"({JOINT_STATE_UNITS['velocity']})/({JOINT_STATE_UNITS['effort']})"


@dataclass
class Recording:
    """
    Uniformly sampled closed-loop data.

    The constructor converts the signals to float arrays; a 1-D signal is one joint.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times [s] (uniform, spacing ``dt``).
    joint_names : list of str
        Joint names, n of them.
    position, velocity, effort : array_like, shape (N, n)
        Measured position [rad], velocity y [rad/s], applied motor torque u [N m].
    reference : array_like, shape (N, n), optional
        Velocity reference r [rad/s] (NaN where none was commanded).
    excitation : array_like, shape (N, n), optional
        The excitation part of r (the reference minus offsets / constant velocity).
    segments : list of Segment, optional
        Experiment segments, in time order.
    meta : dict, optional
        Free-form (model, seed, summaries of procedures).

    Raises
    ------
    ValueError
        A signal is not shaped (N, n).

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

    # --- named fields of ``meta``: the entries the other layers read, one definition each ---
    @property
    def gaps(self) -> list[tuple[float, float]]:
        """Return the [t_first, t_last] [s] of every stretch of joint states a bag lost."""
        return [(float(a), float(b)) for a, b in self.meta.get('gaps') or []]

    @property
    def units(self) -> dict[str, Any]:
        """Return the import map's units per joint, {joint: {signal: unit}} (robot: empty)."""
        u = self.meta.get('units')
        return u if isinstance(u, dict) else {}

    @property
    def summary(self) -> dict[str, Any]:
        """Return the procedures' summary a run recorded (poses, pose_rad; empty without)."""
        s = self.meta.get('summary')
        return s if isinstance(s, dict) else {}

    @property
    def import_info(self) -> dict[str, Any]:
        """Return how an imported table was read (source, map, derived signals; or empty)."""
        i = self.meta.get('import')
        return i if isinstance(i, dict) else {}

    @property
    def segments_left_out(self) -> list[list[float]]:
        """Return the [t_start, t_end] of the segments a time range cut (left out, named)."""
        return list(self.meta.get('segments_left_out') or [])

    def output_columns(self) -> list[int]:
        """
        Return the joints whose velocity is an output of the FRF.

        Returns
        -------
        list of int
            Every joint, or only the outputs of an import layout (meta['layout']: a shaker's
            channel carries an effort and no motion, a sensor's a motion and no effort).

        """
        layout = self.meta.get('layout') if isinstance(self.meta, dict) else None
        if not isinstance(layout, dict):
            return list(range(len(self.joint_names)))
        names = {c['name'] for c in layout.get('outputs', [])}
        return [k for k, n in enumerate(self.joint_names) if n in names]

    @property
    def is_layout(self) -> bool:
        """Return whether the recording is an import layout of inputs and outputs (no robot)."""
        return isinstance(self.meta, dict) and isinstance(self.meta.get('layout'), dict)

    def unit(self, name: str, signal: str) -> str:
        """
        Return the unit of one signal of joint ``name``: as an import map states it, else SI.

        Parameters
        ----------
        name : str
            A joint name.
        signal : str
            'position', 'velocity' or 'effort'.

        Returns
        -------
        str
            meta['units'][name][signal], or the sensor_msgs/JointState unit of a revolute
            joint (:data:`JOINT_STATE_UNITS`: rad, rad/s, N m) where the recording says
            nothing.

        """
        units = self.meta.get('units', {}) if isinstance(self.meta, dict) else {}
        return units.get(name, {}).get(signal, JOINT_STATE_UNITS[signal])

    @property
    def dt(self) -> float:
        """Return the sample time [s], the median spacing of ``t`` (ValueError below 2 samples)."""
        if self.t.size < 2:
            raise ValueError('recording has fewer than 2 samples')
        # the median of a long record costs ~1 ms and estimators ask often: kept while ``t``
        # is the same array
        cached = self.__dict__.get('_dt_of')
        if cached is None or cached[0] is not self.t:
            cached = (self.t, float(np.median(np.diff(self.t))))
            self.__dict__['_dt_of'] = cached
        return cached[1]

    @property
    def fs(self) -> float:
        """Return the sample rate 1 / dt [Hz]."""
        return 1.0 / self.dt

    def index_of(self, t: float) -> int:
        """
        Return the index of the sample at (or first after) time t.

        A sample up to a quarter sample before ``t`` counts as at ``t``.

        Parameters
        ----------
        t : float
            Time in s.

        Returns
        -------
        int
            The index (``N`` when t is after the last sample).

        """
        return int(np.searchsorted(self.t, t - 0.25 * self.dt))

    def slice(self, t_start: float, t_end: float) -> slice:  # noqa: A003
        """
        Return the sample slice covering [t_start, t_end).

        Parameters
        ----------
        t_start, t_end : float
            Times in s (see :meth:`index_of`).

        Returns
        -------
        slice
            Indices of the samples in the span.

        """
        return slice(self.index_of(t_start), self.index_of(t_end))

    def select_joints(self, names: list[str]) -> 'Recording':
        """
        Return the recording restricted to the named joints, in that order.

        Parameters
        ----------
        names : list of str
            Joint names of this recording.

        Returns
        -------
        Recording
            The same samples, segments and meta, the signals of ``names`` only.

        Raises
        ------
        ValueError
            A name is not one of the recording's joints.

        """
        idx = [list(self.joint_names).index(n) for n in names]

        def pick(a):
            return None if a is None else a[:, idx]
        return Recording(self.t, list(names), pick(self.position), pick(self.velocity),
                         pick(self.effort), pick(self.reference), pick(self.excitation),
                         list(self.segments), dict(self.meta))

    def segments_where(self, **match: Any) -> list[Segment]:
        """
        Return the segments whose info matches every given key/value.

        Parameters
        ----------
        **match
            ``info`` keys and the values they must equal (e.g. ``design='multisine'``).

        Returns
        -------
        list of Segment
            The matching segments, in time order.

        """
        return [s for s in self.segments if all(s.info.get(k) == v for k, v in match.items())]
