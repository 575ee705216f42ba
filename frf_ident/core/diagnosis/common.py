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
Provide the shared pieces of the diagnosis.

Shared pieces of the diagnosis: effect names, the result record, simulation of a model on the
recorded excitation, splitting a recording into fit and held-out parts, and the metrics of
docs/CONTRACT.md §7 (frf_error_db, time_nrmse).
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording, Segment
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.core.simulation.plant import FlexibleJointPlant
import numpy as np

from .records import NotDetermined
from .thresholds import GAP_GUARD_S

EFFECTS = ('coulomb_friction', 'viscous_friction', 'stiffness_nonlinearity', 'backlash',
           'torque_ripple', 'time_delay', 'gravity', 'parameter_mismatch', 'second_mode',
           # the sensor, read from the record (sensor.py)
           'velocity_from_encoder', 'quantisation')
#: effects that bend the joint's spring (its stiffness depends on the deflection): rivals of
#: a mismatched linear stiffness, and what holds an axis' stiffness once taken
SPRING_SHAPES = ('stiffness_nonlinearity', 'backlash')


@dataclass
class Effect:
    """One diagnosed effect: docs/CONTRACT.md §7 entry plus the model change it implies."""

    name: str
    axis: str
    score: float
    parameters: dict[str, Any]
    evidence: str
    axis_index: int = 0
    gain: float = 0.0          # relative reduction of the fit loss when the effect is added
    support: float = 0.0       # |t| of the regression coefficient that proposed it (0: none)
    #: the parameters' standard errors, same keys (None: not estimated, e.g. a nominal term)
    standard_error: dict[str, Any] | None = None
    #: why a rule, not a simulation, kept it out (its report.json ``rejected`` reason)
    reason: str | None = None
    #: the parameters the record does not determine (empty: every value is determined); an
    #: effect with one does not count as found (its score is 0)
    not_determined: list[NotDetermined] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        out = {'name': self.name, 'axis': self.axis, 'score': round(float(self.score), 3),
               'parameters': _plain(self.parameters), 'evidence': self.evidence}
        if self.standard_error is not None:
            out['standard_error'] = _plain(self.standard_error)
        if self.not_determined:
            out['not_determined'] = [n.to_dict() for n in self.not_determined]
        return out


def _plain(x: Any) -> Any:
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(f'{float(x):.6g}')
    if isinstance(x, np.integer):
        return int(x)
    return x


def has_experiments(rec: Recording) -> bool:
    """
    Return whether the record holds identification experiments.

    Parameters
    ----------
    rec : Recording
        The record to inspect.

    Returns
    -------
    bool
        True when it has a reference column and at least one multisine or chirp segment (the
        experiments route of the diagnosis), else False (time-series route).

    """
    return rec.reference is not None and any(
        s.info.get('design') in ('multisine', 'chirp') for s in rec.segments)


def apply_effect(robot: RobotParams, eff: Effect) -> RobotParams:
    """
    Return the robot with the effect's parameters written into its axis (model-file keys).

    ``velocity_from_encoder`` is the model's (``simulation.velocity_from_encoder``).
    """
    params = copy.deepcopy(eff.parameters)
    top = {k: params.pop(k) for k in ('velocity_from_encoder',) if k in params}
    axes = list(robot.axes)
    axes[eff.axis_index] = replace(axes[eff.axis_index], **params)
    return replace(robot, axes=axes, **top)


def quiet(robot: RobotParams) -> RobotParams:
    """Return the model without measurement noise/quantisation: what a simulation predicts."""
    return robot.with_axes(velocity_noise=0.0, torque_noise=0.0, encoder_resolution=0.0)


def bridge_gaps(rec: Recording) -> tuple[Recording, np.ndarray]:
    """
    Bridge the rows a recording lacks and return the mask of them.

    A bag read with ``gaps='mark'`` has NaN joint states inside gaps it lost. Filters and the
    closed-loop simulation must run through them, no comparison may use them: position,
    velocity and effort are interpolated linearly in time there, and the rows (widened by
    GAP_GUARD_S on both sides) lose their reference (NaN), so the experiment diagnosis leaves
    them plus a settling time out (``evaluator.missing_reference``) and the time-series
    diagnosis masks them.

    Parameters
    ----------
    rec : Recording
        The recording, possibly with non-finite joint-state rows.

    Returns
    -------
    rec : Recording
        The same recording when nothing is missing, else a bridged copy.
    missing : ndarray of bool, shape (N,)
        The bridged rows, widened by GAP_GUARD_S.

    """
    bad = ~(np.all(np.isfinite(rec.position), axis=1) & np.all(np.isfinite(rec.velocity), axis=1)
            & np.all(np.isfinite(rec.effort), axis=1))
    if not bad.any():
        return rec, bad
    if bad.all():
        raise ValueError('recording has no complete joint-state row')
    ok = ~bad

    def fill(x):
        return np.column_stack([np.interp(rec.t, rec.t[ok], x[ok, j])
                                for j in range(x.shape[1])])
    g = int(round(GAP_GUARD_S * rec.fs))
    wide = np.convolve(bad, np.ones(2 * g + 1), mode='same') > 0
    ref = None
    if rec.reference is not None:
        ref = np.array(rec.reference, dtype=float)
        ref[wide] = np.nan
    out = Recording(rec.t, list(rec.joint_names), fill(rec.position), fill(rec.velocity),
                    fill(rec.effort), ref, rec.excitation, list(rec.segments), dict(rec.meta))
    return out, wide


def drive_reference(rec: Recording) -> np.ndarray:
    """
    Return the velocity reference :func:`simulate_like` drives the model with.

    Where the reference is missing the controller's input is unknown: the simulation follows
    the measured velocity there, and the diagnosis leaves these stretches out of every
    comparison (evaluator.missing_reference) instead of commanding zero velocity.
    """
    if rec.reference is None:
        raise ValueError('recording has no reference; closed-loop simulation impossible')
    return np.where(np.isfinite(rec.reference), rec.reference, rec.velocity)


def simulate_like(rec: Recording, robot: RobotParams, ctrl: PIVelocity, *,
                  reference: np.ndarray | None = None, keep: tuple[str, ...] = ()
                  ) -> Recording:
    """
    Simulate ``robot`` in closed loop on the recording's reference and return the result.

    Run ``robot`` in closed loop with ``ctrl`` on the recording's velocity reference (the
    same excitation through the same controller) and return a Recording with the same
    segments, so that it can be estimated exactly like the measurement. ``reference`` is
    :func:`drive_reference` of ``rec`` where the caller keeps it (it simulates many models).
    Without noise and quantisation (what a model predicts) but the sensor fields in ``keep``
    (``encoder_resolution``, ``velocity_noise``, ``torque_noise``: each axis' own), the
    noise seeded alike in every call.
    """
    r = drive_reference(rec) if reference is None else reference
    model = quiet(robot)
    if keep:
        model = replace(model, axes=[replace(a, **{k: getattr(b, k) for k in keep})
                                     for a, b in zip(model.axes, robot.axes)])
    plant = FlexibleJointPlant(replace(model, sample_rate=rec.fs))
    plant.reset(seed=0)
    c = ctrl.copy()
    c.dt = rec.dt
    c.reset(plant.equilibrium_torque())
    res = plant.simulate(reference=r, controller=c, keep_states=False)
    return as_simulation(rec, res.position, res.velocity, res.effort)


class Simulator(Protocol):
    """
    What simulates a model like a record: :func:`simulate_like`'s signature.

    The diagnosis simulates its candidate models through one of these (dependency
    inversion): by default :func:`simulate_like`, our own plant; an adapter may inject
    another engine, e.g. MuJoCo for a nominal model naming an MJCF
    (frf_ident/io/mjcf/candidate.py), which simulates each candidate as the MJCF it would
    write. It must be deterministic in ``robot`` (simulations are kept by the model's repr)
    and may run in a forked worker process.
    """

    def __call__(self, rec: Recording, robot: RobotParams, ctrl: PIVelocity, *,
                 reference: np.ndarray | None = None) -> Recording:
        """Return ``robot`` simulated in closed loop on ``rec``'s reference (its segments)."""


def unheld_by(simulator: Any) -> dict[str, str]:
    """Return the effects ``simulator`` cannot hold (name -> why); none for our plant."""
    return dict(getattr(simulator, 'unheld', None) or {})


def as_simulation(rec: Recording, position: np.ndarray, velocity: np.ndarray,
                  effort: np.ndarray) -> Recording:
    """Return simulated signals as a Recording with the segments and reference of ``rec``."""
    return Recording(rec.t.copy(), list(rec.joint_names), position, velocity, effort,
                     rec.reference, rec.excitation, list(rec.segments), {'simulated': True})


def split_recording(rec: Recording) -> tuple[Recording, Recording, str]:
    """
    Split an identification recording into fit and validation views.

    Fit and validation views of an identification recording (same samples, different
    segments): multisine realisations 0..n_p-2 and the last chirp iteration for fitting; the
    last multisine realisation and the second-last chirp iteration held out.
    """
    segs = rec.segments
    ms = [s for s in segs if s.info.get('design') == 'multisine']
    cv = [s for s in segs if s.info.get('design') == 'constant_velocity']
    ch = [s for s in segs if s.info.get('design') == 'chirp']
    fit, val, said = list(cv), list(cv), []
    if ms:
        n_p = 1 + max(s.info['realisation'] for s in ms)
        if n_p >= 2:
            fit += [s for s in ms if s.info['realisation'] < n_p - 1]
            val += [Segment(s.t_start, s.t_end, dict(s.info, realisation=0))
                    for s in ms if s.info['realisation'] == n_p - 1]
            said.append(f'multisine realisation {n_p} of {n_p}')
        else:
            fit += ms
    if ch:
        its = sorted({s.info['iteration'] for s in ch})
        fit += [s for s in ch if s.info['iteration'] == its[-1]]
        if len(its) >= 2:
            val += [s for s in ch if s.info['iteration'] == its[-2]]
            said.append(f'chirp iteration {its[-2]} (fit on iteration {its[-1]})')
    key = lambda s: s.t_start  # noqa: E731
    mk = lambda sg: Recording(rec.t, rec.joint_names, rec.position, rec.velocity,  # noqa: E731
                              rec.effort, rec.reference, rec.excitation, sorted(sg, key=key),
                              rec.meta)
    text = ('held out (not used for fitting): ' + ' and '.join(said)) if said else \
        'no held-out experiments in the recording: metrics on the fit data'
    return mk(fit), mk(val), text


def segment_mask(rec: Recording, designs=('multisine', 'chirp')) -> np.ndarray:
    """Return a mask of the samples inside the recording's segments of the given designs."""
    m = np.zeros(rec.t.size, bool)
    for s in rec.segments:
        if s.info.get('design') in designs:
            m[rec.slice(s.t_start, s.t_end)] = True
    return m


def rms_about_mean(x: np.ndarray) -> Any:
    """Return the RMS of ``x`` about its mean (over the first axis), the scale of :func:`nrmse`."""
    return np.sqrt(np.mean((x - np.mean(x, 0)) ** 2))


def nrmse(meas: np.ndarray, model: np.ndarray, mask: np.ndarray | None = None, *,
          scale: Any = None) -> float:
    """
    Return the RMS of the output error over RMS of the measured output (both mean-free).

    ``scale`` is :func:`rms_about_mean` of the (masked) measurement where the caller keeps it.
    """
    if mask is not None:
        meas, model = meas[mask], model[mask]
    den = rms_about_mean(meas) if scale is None else scale
    return float(np.sqrt(np.mean((meas - model) ** 2)) / max(den, 1e-300))


def diag_ratio(pm, ps) -> np.ndarray:
    """Return the diagonal elements P_measured/P_model, shape (n, n_freq)."""
    n = min(pm.response.shape[0], pm.response.shape[1])
    idx = np.arange(n)
    return pm.response[idx, idx] / ps.response[idx, idx]


def frf_error_db(pairs, axis: int | None = None) -> float:
    """
    Return the FRF error in dB of model against measurement.

    docs/CONTRACT.md §7: RMS over the analysed lines of 20 log10 |P_measured / P_model|
    (diagonal elements; only that of ``axis`` when given).
    """
    sel = slice(None) if axis is None else slice(axis, axis + 1)
    vals = [20 * np.log10(np.abs(diag_ratio(pm, ps)[sel])).ravel() for pm, ps in pairs]
    v = np.concatenate(vals) if vals else np.array([np.nan])
    v = v[np.isfinite(v)]
    return float(np.sqrt(np.mean(v ** 2))) if v.size else float('nan')
