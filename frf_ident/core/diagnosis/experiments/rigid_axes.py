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
Axes the nominal model holds rigid: the rotor inertia or the joint spring it lacks.

A joint the nominal model holds rigid in the measured band (its spring's antiresonance above
the Nyquist frequency, :func:`rigid_in_band`; e.g. an MJCF joint without the series-elastic
hinge pair, whose view puts an artificial share of its inertia behind a spring 20 Nyquist
frequencies up, frf_ident/io/mjcf/drive_map.py) has no motor/link split an FRF could shift:
the relative rescales of stage 0 and stage 2 (log scales, a few e-folds at most) reach neither
a resonance inside the band nor a rotor many times that artificial motor share. Two readings
of the measured FRFs of both loads, each against the analytic sampled FRF of the model so far
(its coupling and the other axes included), least squares of the complex log error:

- **rotor**: the axis' total inertia changed: an inertia added on the motor side (the
  rotor through the gear the model lacks), the link side kept;
- **spring**: a resonance inside the band: motor inertia, stiffness and damping, the link
  side kept, started from a grid of antiresonances over the band.

The spring is offered where it fits SPRING_COST_RATIO times better than the rotor and its
antiresonance and resonance both lie inside the measured band; else the rotor where it moves
the total inertia by MISMATCH_MIN_LOG. Each is a ``parameter_mismatch`` judged by simulation
like every other candidate (:func:`.acceptance.accept`). The stage reads in rounds: a spring
taken on one axis shifts the FRFs of the axes coupled to it, which are read again on top.
"""
from __future__ import annotations

from dataclasses import dataclass
import logging
import math

from frf_ident.core.model.params import RobotParams
from frf_ident.core.simulation.analytic import robot_frf_sampled
import numpy as np
from scipy import optimize

from .acceptance import accept
from .candidates import with_params
from .search import named, Search
from ..common import Effect
from ..thresholds import (MISMATCH_MIN_LOG, RIGID_ROUNDS, RIGID_SPRING_DAMPING,
                          RIGID_SPRING_GRID, SPRING_COST_RATIO)

__all__ = ['RigidReading', 'read_rigid_axis', 'rigid_axes', 'rigid_axis_candidate',
           'rigid_in_band']

log = logging.getLogger(__name__)

#: the added inertia a rotor reading may take, in units of the axis' total inertia (a negative
#: one comes off the link side)
ROTOR_RANGE = (-0.5, 4.0)
#: motor inertia of the spring grid, as shares of the nominal total inertia
SPRING_MOTOR_SHARES = (0.05, 0.15, 0.4)


def rigid_in_band(robot: RobotParams, axis: int) -> bool:
    """Return whether the axis' spring has its antiresonance above the Nyquist frequency."""
    a = robot.axes[axis]
    return math.sqrt(a.stiffness / a.link_inertia) / (2 * math.pi) > robot.sample_rate / 2


@dataclass(frozen=True)
class RigidReading:
    """The two readings of a rigid axis' FRFs: a rotor and a spring, with their costs."""

    #: inertia added on the motor side by the rotor reading [kg m^2], and its cost
    added_inertia: float
    rotor_cost: float
    #: motor inertia [kg m^2], stiffness [N m/rad], damping [N m s/rad] of the spring reading
    spring: tuple[float, float, float]
    spring_cost: float
    #: the spring's antiresonance and resonance [Hz], the measured band [Hz]
    antiresonance_hz: float
    resonance_hz: float
    band_hz: tuple[float, float]

    @property
    def spring_in_band(self) -> bool:
        """Tell whether antiresonance and resonance both lie inside the measured band."""
        lo, hi = self.band_hz
        return lo <= self.antiresonance_hz and self.resonance_hz <= hi


def _residual(meas: dict, axis: int):
    """Return f(robot) -> the complex log error of the axis' measured FRFs (both loads)."""
    sel = [(e.freq_hz, e.response[axis, axis]) for e in meas.values()]

    def res(rb: RobotParams) -> np.ndarray:
        out = []
        for f, pm in sel:
            e = np.log(pm / robot_frf_sampled(rb, f, inputs=[axis])[axis, 0])
            out += [e.real, e.imag]
        return np.concatenate(out)
    return res


def _spring_start(res, robot: RobotParams, axis: int, band: tuple[float, float]
                  ) -> np.ndarray:
    """Return the grid point (log Jm, log k, log d) of the lowest cost."""
    a = robot.axes[axis]
    total = a.motor_inertia + a.link_inertia
    best, x0 = math.inf, None
    for fa in np.geomspace(band[0], band[1], RIGID_SPRING_GRID):
        k = a.link_inertia * (2 * math.pi * fa) ** 2
        for share in SPRING_MOTOR_SHARES:
            jm = share * total
            d = RIGID_SPRING_DAMPING * 2 * math.sqrt(k * jm * a.link_inertia
                                                     / (jm + a.link_inertia))
            x = np.log([jm, k, d])
            c = float(np.sum(res(_spring(robot, axis, x)) ** 2))
            if c < best:
                best, x0 = c, x
    return x0


def _rotor(robot: RobotParams, axis: int, added: float) -> dict[str, float]:
    """Return the parameters of an inertia added to the axis (removed from the link side)."""
    a = robot.axes[axis]
    if added >= 0:
        return {'motor_inertia': a.motor_inertia + added}
    return {'link_inertia': a.link_inertia + added}


def _spring(robot: RobotParams, axis: int, x: np.ndarray) -> RobotParams:
    jm, k, d = np.exp(x)
    return with_params(robot, axis, motor_inertia=float(jm), stiffness=float(k),
                       damping=float(d))


def read_rigid_axis(meas: dict, robot: RobotParams, axis: int) -> RigidReading:
    """
    Return the rotor and the spring reading of a rigid axis' measured FRFs.

    Parameters
    ----------
    meas : dict
        The record's estimates ('multisine', 'chirp'), square torque -> velocity FRFs.
    robot : RobotParams
        The model so far (the axis rigid in it).
    axis : int
        The axis.

    Returns
    -------
    RigidReading

    """
    res = _residual(meas, axis)
    a = robot.axes[axis]
    total = a.motor_inertia + a.link_inertia

    def rotor_cost(dj: float) -> float:
        return float(np.sum(res(with_params(robot, axis, **_rotor(robot, axis,
                                                                  dj * total))) ** 2))
    rot = optimize.minimize_scalar(rotor_cost, bounds=ROTOR_RANGE, method='bounded',
                                   options={'xatol': 1e-4})
    band = (min(float(e.freq_hz[0]) for e in meas.values()),
            max(float(e.freq_hz[-1]) for e in meas.values()))
    x0 = _spring_start(res, robot, axis, band)
    sol = optimize.least_squares(lambda x: res(_spring(robot, axis, x)), x0,
                                 bounds=(x0 - 4.0, x0 + 4.0), x_scale=1.0)
    jm, k, d = (float(v) for v in np.exp(sol.x))
    wa = math.sqrt(k / a.link_inertia)
    return RigidReading(float(rot.x) * total, float(rot.fun), (jm, k, d),
                        float(np.sum(sol.fun ** 2)), wa / (2 * math.pi),
                        wa * math.sqrt(1 + a.link_inertia / jm) / (2 * math.pi), band)


def rigid_axis_candidate(meas: dict, robot: RobotParams, axis: int) -> Effect | None:
    """
    Return the spring or the rotor a rigid axis' FRFs show, as a parameter mismatch, or None.

    The spring where it fits SPRING_COST_RATIO times better than the rotor and lies inside
    the band; else the rotor where it moves the total inertia by MISMATCH_MIN_LOG.
    """
    r = read_rigid_axis(meas, robot, axis)
    a = robot.axes[axis]
    total = a.motor_inertia + a.link_inertia
    fits = (f'rotor reading: {r.added_inertia:+.4g} kg m^2 on the motor side, cost '
            f'{r.rotor_cost:.4g}; spring reading: motor inertia {r.spring[0]:.4g} kg m^2, '
            f'stiffness {r.spring[1]:.4g} N m/rad, damping {r.spring[2]:.4g} N m s/rad, '
            f'antiresonance {r.antiresonance_hz:.3g} Hz, resonance {r.resonance_hz:.3g} Hz, '
            f'cost {r.spring_cost:.4g}; band {r.band_hz[0]:.3g}-{r.band_hz[1]:.3g} Hz')
    if r.spring_in_band and r.spring_cost * SPRING_COST_RATIO < r.rotor_cost:
        jm, k, d = r.spring
        return Effect('parameter_mismatch', a.name, 0.0,
                      {'motor_inertia': jm, 'stiffness': k, 'damping': d},
                      f'a resonance the rigid joint lacks, inside the measured band: the '
                      f'two-mass joint fits its FRFs (both loads) '
                      f'{r.rotor_cost / r.spring_cost:.3g} x better than a rotor inertia; {fits}',
                      axis)
    if abs(math.log1p(r.added_inertia / total)) > MISMATCH_MIN_LOG:
        return Effect('parameter_mismatch', a.name, 0.0, _rotor(robot, axis, r.added_inertia),
                      f'the total inertia of the rigid joint is {total + r.added_inertia:.4g} kg '
                      f'm^2, not {total:.4g}: a rotor inertia it lacks; {fits}', axis)
    return None


def rigid_axes(s: Search) -> None:
    """
    Stage 0b: the rotor inertia or the joint spring an axis the model holds rigid lacks.

    :func:`rigid_axis_candidate` of every axis rigid in the band, against the
    model so far, judged by simulation; an axis that took nothing is read again on top of
    what the others took (a spring shifts the FRFs of the axes coupled to it), springs
    first: a neighbour's rotor read before the spring would take the spring's coupling.
    """
    ev, robot = s.ev, s.robot
    todo = [i for i in range(robot.n_axes) if rigid_in_band(robot, i)]
    found: list[Effect] = []
    for _ in range(RIGID_ROUNDS):
        cands = [c for c in (rigid_axis_candidate(ev.meas_fit, s.ext, i) for i in todo)
                 if c is not None]
        springs = [c for c in cands if 'stiffness' in c.parameters]
        offer = springs or cands
        for c in offer:
            s.say(f'  {c.axis} rigid in the band: {c.evidence}')
        if not offer:
            break
        s.ext, s.cur = accept(ev, robot, s.kept, offer, s.cur, s.say)
        found += offer
        took = {c.axis_index for c in offer if c in s.kept}
        todo = [i for i in todo if i not in took]
        if not took and not springs:
            break
    s.stage0 += found
    s.cands += found
    log.info('stage 0b (axes rigid in the band): %d candidate(s), %s', len(found),
             named(s.kept))
