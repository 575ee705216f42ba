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
Fit the gravity the robot's kinematics imply: its base parameters, jointly over the axes.

The time-series diagnosis fits gravity per axis as free sinusoids of joint-angle sums, each
axis its own amplitudes and phases, a constant load beside them. Given the kinematics (a URDF,
evaluated in :mod:`frf_ident.io.kinematics`, which passes the arrays in), the gravity torque of
every axis is ``basis(q) @ theta``: the same few base parameters ``theta`` (the combinations
of link masses and centres of mass the torques can show) for all axes, none on an axis whose
joint is vertical. :func:`fit_kinematic_gravity` refits the diagnosis' scalar terms of every
axis (friction, inertia, a constant load) together with ``theta`` in one linear least squares
over all axes, and writes the result as the model file's sinusoid terms (exactly, for arms
whose joints after a vertical first one are parallel; refused otherwise).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Any, Callable

from frf_ident.core.model.params import RobotParams
from frf_ident.core.progress import Progress
from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError
import numpy as np

from ..common import bridge_gaps, Effect
from ..prediction import predict_metrics
from ..regressors import gravity_sets, model_residual, moving, regressor_groups
from ..residual import lowpass
from ..result import DiagnosisResult
from ..selection import block_standard_errors
from ..thresholds import FC_HZ
from ..timeseries.effects import EFFECT_OF

__all__ = ['fit_kinematic_gravity', 'GravityBasis', 'KinematicGravityFit', 'kinematic_gravity',
           'sinusoid_terms']

#: the scalar terms refitted beside the gravity (the time-series route's group names)
SCALARS = ('gravity_torque', 'coulomb_friction', 'viscous_friction', 'motor_inertia',
           'urdf_inertia', 'urdf_gravity')
#: a gravity that the sinusoids of joint-angle sums leave more of than this share (RMS) is
#: not one the model file can hold (its joints are not parallel after a vertical one)
EXACT = 1e-6
#: poses drawn uniformly over [-pi, pi] per joint (seed 0) to write the gravity as sinusoids
SAMPLE_POSES = 64


@dataclass(frozen=True)
class GravityBasis:
    """The robot's kinematics as the diagnosis needs them: the gravity's base regressor."""

    #: where the kinematics came from (the URDF's path), for the evidence and the report
    source: str
    #: joint positions (M, n) [rad] -> base regressor (M, n, p) in the record's torque units
    basis: Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class KinematicGravityFit:
    """The gravity's base parameters, fitted jointly over the axes (``kinematic_gravity``)."""

    source: str
    base_parameters: list[float]
    standard_errors: list[float]
    #: the held-out time_nrmse the diagnosis' own per-axis sinusoids had
    free_sinusoids_held_out: float

    def to_dict(self) -> dict[str, Any]:
        """Return the report's entry."""
        return {'source': self.source, 'base_parameters': list(self.base_parameters),
                'standard_errors': list(self.standard_errors),
                'free_sinusoids_held_out': self.free_sinusoids_held_out}


def kinematic_gravity(res: DiagnosisResult, rec: Recording, robot: RobotParams,
                      gravity: GravityBasis, progress: Progress
                      ) -> tuple[DiagnosisResult, KinematicGravityFit | None]:
    """
    Replace the diagnosis' free gravity sinusoids with the gravity of the kinematics.

    The base regressor at the record's positions (between samples) and at SAMPLE_POSES poses
    spread over the configuration space; :func:`fit_kinematic_gravity` fits the base
    parameters jointly over the axes. The time-series route only (None otherwise).
    """
    if res.mode != 'timeseries':
        progress(f'note: --urdf {gravity.source} is used by the time-series route only')
        return res, None
    q = 0.5 * (rec.position[1:] + rec.position[:-1])
    poses = np.random.default_rng(0).uniform(-np.pi, np.pi, (SAMPLE_POSES, robot.n_axes))
    res, fit = fit_kinematic_gravity(res, rec, robot, gravity.basis(q),
                                     (poses, gravity.basis(poses)), source=gravity.source)
    progress(f'{gravity.source}: gravity of the kinematics, {len(fit.base_parameters)} base '
             f'parameters fitted jointly over the axes (held-out time_nrmse '
             f'{fit.free_sinusoids_held_out:.3f} with free sinusoids per axis, '
             f'{res.metrics.extended.time_nrmse:.3f} with these)')
    return res, fit


def sinusoid_terms(q: np.ndarray, g: np.ndarray, i: int, names: list[str]
                   ) -> list[dict[str, Any]]:
    """
    Return axis i's gravity g(q) as the model file's terms G sin(sum of q_j + phi).

    Parameters
    ----------
    q : ndarray, shape (M, n)
        Poses spread over the configuration space [rad].
    g : ndarray, shape (M,)
        Axis i's gravity torque at those poses.
    i : int
        The axis.
    names : list of str
        The joint names.

    Returns
    -------
    list of dict
        ``{'amplitude', 'phase', 'joints'}`` per contiguous joint set containing the axis
        that carries a share of g; empty when g is zero.

    Raises
    ------
    EstimationError
        g is no sum of such sinusoids (more than EXACT of its RMS left).

    """
    scale = float(np.sqrt(np.mean(g ** 2)))
    if scale == 0.0:
        return []
    sets = gravity_sets(q.shape[1], i)
    X = np.column_stack([f(q[:, list(js)].sum(axis=1)) for js in sets for f in (np.sin, np.cos)])
    c, *_ = np.linalg.lstsq(X, g, rcond=None)
    left = float(np.sqrt(np.mean((g - X @ c) ** 2)))
    if left > EXACT * scale:
        raise EstimationError(f'the gravity the kinematics give axis {names[i]} is no sum of '
                              f'sinusoids of joint-angle sums ({left / scale:.2g} of it left): '
                              f'the model file cannot hold it (joints after a vertical one '
                              f'must be parallel)')
    out = []
    for k, js in enumerate(sets):
        a_s, a_c = c[2 * k], c[2 * k + 1]
        if math.hypot(a_s, a_c) > EXACT * scale:
            out.append({'amplitude': float(math.hypot(a_s, a_c)),
                        'phase': float(math.atan2(a_c, a_s)),
                        'joints': [names[j] for j in js]})
    return out


def fit_kinematic_gravity(res: DiagnosisResult, rec: Recording, robot: RobotParams,
                          basis: np.ndarray, samples: tuple[np.ndarray, np.ndarray], *,
                          source: str = 'the kinematics', fc: float = FC_HZ
                          ) -> tuple[DiagnosisResult, KinematicGravityFit]:
    """
    Return the time-series result with the gravity of the kinematics in place of its own.

    Parameters
    ----------
    res : DiagnosisResult
        The time-series diagnosis of ``rec`` against ``robot``.
    rec : Recording
        The record.
    robot : RobotParams
        The nominal model.
    basis : ndarray, shape (N-1, n, p)
        The gravity's base regressor at the record's positions between samples (NaN where
        unknown), in the record's torque units (motor side).
    samples : (ndarray (M, n), ndarray (M, n, p))
        Poses spread over the configuration space and the base regressor there (to write
        the gravity as sinusoid terms).
    source : str
        Where the kinematics came from (for the evidence).
    fc : float
        Analysis band [Hz].

    Returns
    -------
    (DiagnosisResult, KinematicGravityFit)
        Effects: per axis the refitted scalar terms it had (and a constant load where gravity
        acts) and its gravity, the extended model's metrics taken again; the base parameters
        and their standard errors.

    """
    rec_b, lost = bridge_gaps(rec)
    f, qh, vh, ah = model_residual(rec_b, robot)
    fs, n, p = rec_b.fs, robot.n_axes, basis.shape[2]
    move = moving(vh, rec_b.velocity, fs, fc)
    ok = res.fit_rows & ~(lost[1:] | lost[:-1]) & np.isfinite(basis).all(axis=(1, 2))
    had = {(e.axis, k) for e in res.effects for k in e.parameters}
    # an axis whose gravity is its share of the URDF's keeps that share (refitted) instead
    bas = [np.zeros(basis.shape[::2]) if (ax.name, 'urdf_gravity') in had
           else lowpass(np.nan_to_num(basis[:, i, :]), fs, fc) for i, ax in enumerate(robot.axes)]
    keys = [(i, k) for i, ax in enumerate(robot.axes) for k in SCALARS
            if (ax.name, k) in had or (k == 'gravity_torque' and np.any(bas[i]))]
    rows = f.shape[0]
    groups: dict[str, np.ndarray] = {}
    # the URDF's torques along the record, once for all axes (pinocchio per sample)
    urdf = (None if robot.urdf is None else
            {'urdf_inertia': np.nan_to_num(robot.urdf.inertia(qh, vh, ah)),
             'urdf_gravity': np.nan_to_num(robot.urdf.gravity(qh))})
    for i in range(n):
        own = regressor_groups(qh, vh, ah, fs, fc, i, 0.0, [], ())
        for k, x in (urdf or {}).items():
            own[k] = lowpass(x[:, i:i + 1], fs, fc)
        for j, k in keys:
            col = groups.setdefault(f'{j}:{k}', np.zeros((n * rows, 1)))
            if j == i:
                col[i * rows:(i + 1) * rows] = own[k]
        for m in range(p):
            groups.setdefault(f'base:{m}', np.zeros((n * rows, 1)))[
                i * rows:(i + 1) * rows, 0] = bas[i][:, m]
    y = np.concatenate([lowpass(f[:, i], fs, fc) for i in range(n)])
    fit = np.concatenate([ok & move[:, i] for i in range(n)])
    names = list(groups)
    X = np.column_stack([groups[k] for k in names])
    coef = dict(zip(names, np.linalg.lstsq(X[fit], y[fit], rcond=None)[0]))
    se = {k: float(v[0]) for k, v in block_standard_errors(groups, names, y, fit, fs).items()}
    theta = np.array([coef[f'base:{m}'] for m in range(p)])
    return _with_gravity(res, rec_b, robot, keys, coef, se, theta, samples, source, fc)


def _with_gravity(res, rec, robot, keys, coef, se, theta, samples, source, fc):
    """Return the result of :func:`fit_kinematic_gravity` built from its coefficients."""
    names = robot.joint_names
    q_s, b_s = samples
    score = {(e.axis, k): e.score for e in res.effects for k in e.parameters}
    axes, effects = [], []
    text = ', '.join(f'{t:.4g} \u00b1 {se[f"base:{m}"]:.2g}' for m, t in enumerate(theta))
    for i, ax in enumerate(robot.axes):
        ch: dict[str, Any] = {}
        for j, k in keys:
            if j != i:
                continue
            ch[k] = getattr(ax, k) + float(coef[f'{i}:{k}'])
            effects.append(Effect(
                EFFECT_OF.get(k, k),
                ax.name, score.get((ax.name, k), 0.0), {k: ch[k]},
                f'{k} = {ch[k]:.4g} \u00b1 {se[f"{i}:{k}"]:.2g}, fitted jointly with the '
                f'gravity of {source}', i, standard_error={k: se[f'{i}:{k}']}))
        terms = ([] if (i, 'urdf_gravity') in keys
                 else sinusoid_terms(q_s, b_s[:, i, :] @ theta, i, names))
        if terms:
            ch['gravity'] = list(ax.gravity) + terms
            effects.append(Effect(
                'gravity', ax.name, score.get((ax.name, 'gravity'), 0.0), {'gravity': terms},
                f'gravity of the rigid bodies of {source}: its {theta.size} base parameters '
                f'fitted jointly on all axes ({text}, torque units); on this axis '
                + ', '.join(f'{t["amplitude"]:.3g} sin({" + ".join("q_" + j for j in t["joints"])}'
                            f' {t["phase"]:+.2f})' for t in terms), i,
                standard_error={'gravity': [None] * len(ax.gravity) + [None] * len(terms)}))
        axes.append(replace(ax, **ch))
    ext = replace(robot, axes=axes)
    m = predict_metrics(rec, ext, fc=fc, mask=res.held_out_rows)
    fit = KinematicGravityFit(source, theta.tolist(),
                              [se[f'base:{k}'] for k in range(theta.size)],
                              res.metrics.extended.time_nrmse)
    kept = [r for r in res.rejected if r.name != 'gravity']
    return replace(res, effects=sorted(effects, key=lambda e: -e.score), rejected=kept,
                   metrics=replace(res.metrics, extended=m.scores), extended=ext), fit
