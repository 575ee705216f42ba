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
Read the sensor from the record itself: quantised positions, a velocity from their difference.

Two sensor effects a drives engineer names before any plant effect, read from the recorded
signals, not fitted (issue 55 item 1):

- ``quantisation``: the positions move in whole steps of an encoder count r (every position
  change a whole multiple of r, SENSOR_GRID_SHARE of them within SENSOR_GRID_TOL of a count).
  Its noise floor: r / sqrt(12) on the position, r / (dt sqrt(6)) on a velocity formed as
  the difference of two readings.
- ``velocity_from_encoder``: the recorded velocity is the difference of two successive
  recorded positions over the sample time, v_k = (q_k - q_(k-1)) / dt: the mean velocity of
  the last sample, half a sample late (a delay of dt / 2 in the velocity loop). Evidence:
  v_k regressed on the backward difference and the next one takes weights 1 and 0 within
  SENSOR_TAP_TOL, and the backward difference leaves less than SENSOR_DIFF_EXPLAINS of what
  the central difference (the true velocity's best estimate) leaves.

Per axis :class:`AxisSensor` holds the reading and its numbers; :func:`sensor_effects` names
what the model lacks of it, on every axis that shows it, and :func:`with_sensor` writes it into
a model (``simulation.velocity_from_encoder`` holds for all axes: written only where every axis
shows it).

What the model lacks is judged against the model's own output, not only its file: the
nominal model simulated on the record's excitation (:func:`model_sensor`, by the simulator the
diagnosis uses; on a time series without a reference, following its measured velocity) is
read the same way, and a velocity its own simulation already forms as a position difference
is no effect, on either route. MuJoCo's semi-implicit step (Euler, implicit, implicitfast)
updates q_(k+1) = q_k + h v_(k+1), so an MJCF stepped once per sample outputs exactly the
backward difference (frf_ident/io/mjcf/loop.py): its record shows the sensor, and so does the
nominal MJCF. Our own plant (frf_ident/core/simulation/plant.py) outputs the true velocity
unless ``simulation.velocity_from_encoder`` is set.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import math

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.controller import PIVelocity
import numpy as np

from .common import bridge_gaps, drive_reference, Effect, simulate_like, Simulator
from .result import DiagnosisResult
from .thresholds import (SENSOR_DIFF_EXPLAINS, SENSOR_GRID_SHARE, SENSOR_GRID_TOL,
                         SENSOR_MIN_STEPS, SENSOR_RESOLUTION_MATCH, SENSOR_TAP_TOL)

__all__ = ['AxisSensor', 'describe_sensor', 'encoder_step', 'lacks_difference', 'model_sensor',
           'name_sensor', 'read_sensor', 'SENSOR_EFFECTS', 'sensor_effects', 'velocity_taps',
           'with_lacking_sensor', 'with_sensor']

#: the effect names of the sensor (report.json ``effects[].name``)
SENSOR_EFFECTS = ('velocity_from_encoder', 'quantisation')


@dataclass(frozen=True)
class AxisSensor:
    """What one axis' recorded signals say about its sensor."""

    axis: str
    #: [position unit per count] the step of the position reading (None: no grid)
    resolution: float | None
    #: share of the position changes that are whole multiples of ``resolution``
    grid_share: float
    #: v_k ~ alpha (q_k - q_(k-1)) / dt + beta (q_(k+1) - q_k) / dt
    taps: tuple[float, float]
    #: RMS of v minus the backward difference, and minus the central difference
    rms_backward: float
    rms_central: float
    dt: float

    @property
    def differenced(self) -> bool:
        """Return whether the velocity is the difference of two readings over a sample."""
        alpha, beta = self.taps
        return (abs(alpha - 1.0) <= SENSOR_TAP_TOL and abs(beta) <= SENSOR_TAP_TOL
                and self.rms_backward < SENSOR_DIFF_EXPLAINS * self.rms_central)

    @property
    def velocity_floor(self) -> float:
        """Return the RMS the quantisation puts on the velocity (0: no grid)."""
        if self.resolution is None:
            return 0.0
        per = math.sqrt(6.0) if self.differenced else math.sqrt(24.0)
        return self.resolution / (self.dt * per)


def encoder_step(q: np.ndarray) -> tuple[float | None, float]:
    """
    Return the step of a quantised position reading and the share of changes on its grid.

    The largest r among the smallest nonzero change divided by 1-4 for which
    SENSOR_GRID_SHARE of the changes lie within SENSOR_GRID_TOL of a whole number of r (the
    smallest change may be several counts); None where no r passes or fewer than
    SENSOR_MIN_STEPS changes are seen.

    Examples
    --------
    >>> q = 2e-6 * np.round(np.cumsum(np.linspace(0, 3, 400)))
    >>> r, share = encoder_step(q)
    >>> round(r / 2e-6, 6), share
    (1.0, 1.0)
    >>> encoder_step(np.cumsum(np.random.default_rng(0).uniform(0, 1, 400)))[0] is None
    True

    """
    q = np.asarray(q, float)
    q = q[np.isfinite(q)]
    if q.size < 2:
        return None, 0.0
    d = np.abs(np.diff(q))
    nz = d[d > 1e-9 * max(float(np.abs(q).max()), 1e-300)]
    if nz.size < SENSOR_MIN_STEPS:
        return None, 0.0
    share = 0.0
    for k in (1, 2, 3, 4):
        r = float(nz.min()) / k
        n = nz / r
        share = float(np.mean(np.abs(n - np.round(n)) <= SENSOR_GRID_TOL))
        if share >= SENSOR_GRID_SHARE:
            return r, share
    return None, share


def velocity_taps(q: np.ndarray, v: np.ndarray, dt: float
                  ) -> tuple[tuple[float, float], float, float]:
    """
    Return the taps of v on the backward and the next difference, and two RMS residuals.

    Returns
    -------
    (alpha, beta), rms_backward, rms_central
        v_k ~ alpha (q_k - q_(k-1)) / dt + beta (q_(k+1) - q_k) / dt by least squares; the
        RMS of v_k minus the backward difference and minus the central difference.

    """
    b = np.diff(np.asarray(q, float)) / dt
    y = np.asarray(v, float)[1:-1]
    X = np.column_stack([b[:-1], b[1:]])
    ok = np.isfinite(y) & np.isfinite(X).all(axis=1)
    if ok.sum() < 8 or not np.any(X[ok]):
        return (math.nan, math.nan), math.nan, math.nan
    taps = np.linalg.lstsq(X[ok], y[ok], rcond=None)[0]
    rb = float(np.sqrt(np.mean((y[ok] - X[ok, 0]) ** 2)))
    rc = float(np.sqrt(np.mean((y[ok] - 0.5 * (X[ok, 0] + X[ok, 1])) ** 2)))
    return (float(taps[0]), float(taps[1])), rb, rc


def read_sensor(rec: Recording, names: list[str] | None = None) -> list[AxisSensor]:
    """Return per axis what the record's positions and velocities say about the sensor."""
    out = []
    for i, name in enumerate(names or rec.joint_names):
        r, share = encoder_step(rec.position[:, i])
        taps, rb, rc = velocity_taps(rec.position[:, i], rec.velocity[:, i], rec.dt)
        out.append(AxisSensor(name, r, share, taps, rb, rc, rec.dt))
    return out


def model_sensor(rec: Recording, robot: RobotParams, ctrl: PIVelocity,
                 simulator: Simulator | None = None) -> list[AxisSensor] | None:
    """
    Return what the nominal model's own output says about its sensor, read as the record's.

    ``robot`` simulated in closed loop on the record's (gap-bridged) reference by
    ``simulator`` (default our plant, :func:`.common.simulate_like`; MuJoCo for a model naming
    an MJCF), read by :func:`read_sensor`. Both routes: a record without a reference (a plain
    time series) drives the simulation with its measured velocity as the reference, as
    :func:`.common.drive_reference` does inside a reference's gaps; the simulation need not
    reproduce the record, its output only shows how the model forms its velocity. None where
    no axis of the record shows a differenced velocity (nothing the model could lack).
    """
    if not any(s.differenced for s in read_sensor(rec, robot.joint_names)):
        return None
    bridged, _ = bridge_gaps(rec)
    ref = bridged.velocity if bridged.reference is None else drive_reference(bridged)
    sim = (simulator or simulate_like)(bridged, robot, ctrl, reference=ref)
    return read_sensor(sim, robot.joint_names)


def lacks_difference(reading: list[AxisSensor], robot: RobotParams,
                     shown: list[AxisSensor] | None = None) -> list[bool]:
    """
    Return per axis whether the record's velocity is differenced and the model's is not.

    Not where the model file has ``simulation.velocity_from_encoder``, nor where the model's
    own simulation (``shown``, :func:`model_sensor`) already outputs the difference.

    Examples
    --------
    >>> from frf_ident.core.model.schema import default_model_dict, robot_from_dict
    >>> robot = robot_from_dict(default_model_dict())
    >>> diff = AxisSensor('joint_1', None, 0.0, (1.0, 0.0), 1e-4, 1e-2, 1e-3)
    >>> true = AxisSensor('joint_1', None, 0.0, (0.5, 0.5), 1e-2, 1e-4, 1e-3)
    >>> lacks_difference([diff], robot), lacks_difference([diff], robot, [true])
    ([True], [True])
    >>> lacks_difference([diff], robot, [diff]), lacks_difference([true], robot)
    ([False], [False])

    """
    return [s.differenced and not robot.velocity_from_encoder
            and not (shown is not None and shown[i].differenced)
            for i, s in enumerate(reading)]


def sensor_effects(reading: list[AxisSensor], robot: RobotParams,
                   score: list[float] | None = None,
                   shown: list[AxisSensor] | None = None) -> list[Effect]:
    """
    Return the sensor effects the model lacks, on every axis that shows them.

    Parameters
    ----------
    reading : list of AxisSensor
        :func:`read_sensor` of the record, the model's axes.
    robot : RobotParams
        The nominal model (a sensor it already has is no effect).
    score : list of float, optional
        Per axis the share of its misfit the sensor removes (experiments route); 0 if omitted.
    shown : list of AxisSensor, optional
        :func:`model_sensor`: the model's own simulation read the same way (a velocity it
        already outputs as a position difference is no effect); None: the model file only.

    Returns
    -------
    list of Effect

    """
    out = []
    every = all(s.differenced for s in reading)
    lacks = lacks_difference(reading, robot, shown)
    for i, s in enumerate(reading):
        ax = robot.axes[i]
        sc = score[i] if score is not None else 0.0
        if lacks[i]:
            said = ('' if every else "; not every axis shows it, and the model file's "
                    'simulation.velocity_from_encoder holds for all: not written')
            out.append(Effect(
                'velocity_from_encoder', ax.name, sc, {'velocity_from_encoder': True},
                f'the recorded velocity is the difference of two recorded positions over a '
                f'sample (weights {s.taps[0]:.3f} on the last difference, {s.taps[1]:.3f} on '
                f'the next; RMS {s.rms_backward:.3g} left by it against {s.rms_central:.3g} by '
                f'the central difference): the mean velocity of the last sample, '
                f'{1e3 * s.dt / 2:.3g} ms late{said}', i))
        known = ax.encoder_resolution
        if s.resolution is not None and not (
                known > 0 and abs(s.resolution / known - 1) <= SENSOR_RESOLUTION_MATCH):
            out.append(Effect('quantisation', ax.name, sc, {'encoder_resolution': s.resolution},
                              quantisation_evidence(s), i))
    return out


def quantisation_evidence(s: AxisSensor) -> str:
    """Return the evidence sentence of a quantised position reading and its noise floor."""
    how = 'differenced over a sample' if s.differenced else 'if differenced centrally'
    text = (f'every position change is a whole number of steps of {s.resolution:.4g} '
            f'({100 * s.grid_share:.1f} % within {SENSOR_GRID_TOL:g} of a step): noise of '
            f'{s.resolution / math.sqrt(12):.3g} RMS on the position, '
            f'{s.velocity_floor:.3g} RMS on the velocity ({how})')
    if s.differenced:
        text += (f'; the velocity noise beyond the difference: {s.rms_backward:.3g} RMS '
                 f'({s.velocity_floor / max(s.rms_backward, 1e-300):.3g} times less)')
    return text


def with_sensor(robot: RobotParams, reading: list[AxisSensor],
                shown: list[AxisSensor] | None = None) -> RobotParams:
    """
    Return the model with the sensor the record shows written in.

    ``simulation.velocity_from_encoder`` where every axis' velocity is differenced and the
    model's own output (``shown``, :func:`model_sensor`) is not already; each axis'
    ``encoder_resolution`` where its positions are quantised.
    """
    axes = [replace(a, encoder_resolution=s.resolution) if s.resolution is not None else a
            for a, s in zip(robot.axes, reading)]
    every = (bool(reading) and all(s.differenced for s in reading)
             and any(lacks_difference(reading, robot, shown)))
    return replace(robot, axes=axes,
                   velocity_from_encoder=robot.velocity_from_encoder or every)


def with_lacking_sensor(rec: Recording, robot: RobotParams, simulated: Recording
                        ) -> RobotParams:
    """
    Return ``robot`` with the sensor ``rec`` shows and ``robot``'s own output lacks.

    ``simulated`` is ``robot`` simulated on ``rec``'s excitation (the experiments route's
    nominal simulation), read as the record is (:func:`model_sensor`); ``robot`` itself (the
    same object) where it lacks nothing.
    """
    reading = read_sensor(rec, robot.joint_names)
    shown = read_sensor(simulated, robot.joint_names)
    if not sensor_effects(reading, robot, shown=shown):
        return robot
    return with_sensor(robot, reading, shown)


def describe_sensor(robot: RobotParams, with_it: RobotParams) -> str:
    """Return what :func:`with_sensor` changed, for a log line."""
    parts = ['velocity from encoder differences'] if (
        with_it.velocity_from_encoder and not robot.velocity_from_encoder) else []
    parts += [f'{b.name} encoder step {b.encoder_resolution:.3g}'
              for a, b in zip(robot.axes, with_it.axes)
              if b.encoder_resolution != a.encoder_resolution]
    return ', '.join(parts) or 'nothing new'


def name_sensor(res: DiagnosisResult, rec: Recording, robot: RobotParams,
                shown: list[AxisSensor] | None = None) -> DiagnosisResult:
    """
    Return the result with the sensor effects the record shows, and the model with them.

    ``shown`` is :func:`model_sensor` of the nominal model: what its own output already shows
    is no effect.

    The experiments route searched against the model with the sensor (its extended model has
    it, its held-out misfit without it is ``detail.misfit['without_sensor']``): each axis'
    score is the share of its misfit above the floor the sensor removes. The time-series
    route's inverse dynamics do not depend on it: score 0, named where the model's own
    simulation (``shown``) does not output the difference either.
    """
    reading = read_sensor(rec, robot.joint_names)
    misfit = getattr(res.detail, 'misfit', None) or {}
    score = None
    if 'without_sensor' in misfit:
        score = [float(np.clip((w - b) / max(w - 1.0, 1e-12), 0.0, 1.0))
                 for w, b in zip(misfit['without_sensor'], misfit['baseline'])]
    found = sensor_effects(reading, robot, score, shown)
    if not found:
        return res
    return replace(res, effects=sorted(found + list(res.effects), key=lambda e: -e.score),
                   extended=with_sensor(res.extended, reading, shown))
