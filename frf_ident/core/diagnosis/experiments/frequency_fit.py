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
Read a linear parameter mismatch off the measured FRFs by the physical fit, before simulating.

The flexible joint of :mod:`frf_ident.core.fit.physical` (the coupled robot of
:mod:`frf_ident.core.fit.coupled` where the model has link coupling) is fitted by maximum
likelihood to each estimate of the record (multisine: low load, chirp: high load) and, with
the same weights, to the same estimate of the nominal model's simulation. The difference of
the log parameters is what the measurement shows beyond the estimator's and the sampling's
bias (both fits carry it alike); its standard error is the measured fit's Cramer-Rao bound,
widened by the square root of the cost ratio where the model misses part of the record. A
motor inertia, link inertia or stiffness is named when it differs from the nominal at both
loads (MISMATCH_MIN_LOG and FD_MISMATCH_Z) and the two loads agree: by the rule stage 2 splits
linear from load-dependent springs by (the one-parameter stiffness scales of
:func:`.candidates.stiffness_seen` within LOAD_DEPENDENCE_MIN_LOG; a stiffening gear
preloaded by gravity shows nearly the same stiffness at both loads in the five-parameter fit,
whose link inertia absorbs the chirp's softer average), and within FD_MISMATCH_Z combined
standard errors for each named parameter. A load-dependent stiffness is a stiffening spring or
a backlash, read later by simulation. Nor is an axis named whose own channel the fit of a
weighted estimate leaves far above its noise (FD_STRUCTURE_RATIO): a resonance the model lacks
shifts the fitted parameters without any of them being off. Damping and viscous
friction are left to the later stages: the closed-loop FRF of a joint with Coulomb friction
looks like extra damping.
"""
from __future__ import annotations

from dataclasses import dataclass
import logging
import math
from typing import Any

from frf_ident.core.fit.cost import normalised_residual
from frf_ident.core.fit.coupled import fit_coupled
from frf_ident.core.fit.physical import fit_two_mass, PARAMETERS
from frf_ident.core.model.params import RobotParams
import numpy as np

from .candidates import stiffness_seen
from ..common import Effect
from ..thresholds import (FD_MISMATCH_Z, FD_STRUCTURE_RATIO, LOAD_DEPENDENCE_MIN_LOG,
                          MISMATCH_MIN_LOG)

__all__ = ['FD_KEYS', 'LinearShift', 'fd_parameter_mismatch', 'linear_shifts', 'load_dependence',
           'shifts_text']

log = logging.getLogger(__name__)

#: the linear parameters stage 0 may name (damping and viscous friction: friction confounds
#: them in a closed-loop FRF)
FD_KEYS = ('motor_inertia', 'link_inertia', 'stiffness')
_ROWS = [PARAMETERS.index(k) for k in FD_KEYS]


@dataclass
class LinearShift:
    """
    What one estimate shows of every axis' linear parameters against the nominal model.

    Attributes
    ----------
    key : str
        The estimate ('multisine' or 'chirp').
    log_scale : ndarray, shape (n_axes, len(FD_KEYS))
        log(measured fit / nominal simulation's fit) of each parameter of :data:`FD_KEYS`.
    std : ndarray, shape (n_axes, len(FD_KEYS))
        Its standard error (the measured fit's Cramer-Rao bound, relative, widened by
        sqrt(cost ratio) when the ratio exceeds 1).
    coupled : bool
        True when the coupled robot was fitted (the model has link coupling).
    channel_cost : ndarray, shape (n_axes,)
        The ML cost per degree of freedom the fit leaves on each axis' own channel (NaN where
        the estimate carries no variance).

    """

    key: str
    log_scale: np.ndarray
    std: np.ndarray
    coupled: bool
    channel_cost: np.ndarray

    @property
    def structure_missing(self) -> np.ndarray:
        """Return per axis whether the channel cost exceeds FD_STRUCTURE_RATIO (NaN: no)."""
        return np.nan_to_num(self.channel_cost, nan=0.0) > FD_STRUCTURE_RATIO


def _variance(est: Any) -> np.ndarray | None:
    """Return the estimate's variance (total, else noise) where usable, else None."""
    var = est.variance()
    if var is None or not np.all(np.isfinite(var) & (var > 0)):
        return None
    return np.asarray(var, dtype=float)


def _fit_axes(est: Any, var: np.ndarray | None, n: int, coupled: bool
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Return every axis' parameters (5, n), their widened standard errors and the costs.

    The cost (n,) is the sum of squared normalised residuals of each axis' own channel.
    """
    p = np.asarray(est.response)[:n, :n]
    if coupled:
        fit = fit_coupled(est.freq_hz, p, None if var is None else var[:n, :n], delay_s=None)
        value = fit.value[:5 * n].reshape(5, n)
        std = fit.std[:5 * n].reshape(5, n) * math.sqrt(max(1.0, fit.cost.ratio))
        cost = np.array([float(np.sum(normalised_residual(
            fit.model[i, i], p[i, i], None if var is None else var[i, i]) ** 2))
            for i in range(n)])
        return value, std, cost
    fits = [fit_two_mass(est.freq_hz, p[i, i], None if var is None else var[i, i],
                         delay_s=None) for i in range(n)]
    value = np.stack([f.value for f in fits], axis=1)
    std = np.stack([f.std * math.sqrt(max(1.0, f.cost.ratio)) for f in fits], axis=1)
    return value, std, np.array([f.cost.cost for f in fits])


def linear_shifts(meas: dict, sim_est: dict, robot: RobotParams) -> list[LinearShift]:
    """
    Return the shift of every axis' inertias and stiffness each estimate shows.

    Parameters
    ----------
    meas : dict
        The record's estimates (``Evaluator.meas_fit``: 'multisine', 'chirp'), square
        torque -> velocity FRFs in the model's axis order.
    sim_est : dict
        The same estimates of the nominal model's simulation of the record.
    robot : RobotParams
        The nominal model: the coupled robot is fitted when it has link coupling.

    Returns
    -------
    list of LinearShift
        One per estimate present in both (and square), in the order of ``meas``.

    """
    n = robot.n_axes
    coupled = n > 1 and robot.link_coupling is not None and bool(
        np.any(np.asarray(robot.link_coupling) != 0))
    out = []
    for key, est in meas.items():
        sim = sim_est.get(key)
        if sim is None or min(np.shape(est.response)[:2]) < n:
            continue
        var = _variance(est)
        try:
            v_meas, sd, c_meas = _fit_axes(est, var, n, coupled)
            v_sim, _, c_sim = _fit_axes(sim, var, n, coupled)      # same weights: same bias
        except (ValueError, np.linalg.LinAlgError) as err:
            # no reading of this load: stage 0 names nothing, stage 2 reads the axis
            log.debug('stage 0: the physical fit of the %s estimate failed (%s)', key, err)
            continue
        # the cost per degree of freedom of each axis' own channel (weighted estimates only)
        dof = max(2 * est.freq_hz.size - len(PARAMETERS), 1)
        cost = c_meas / dof if var is not None else np.full(n, np.nan)
        rows = np.asarray(_ROWS)
        ratio = v_meas[rows] / v_sim[rows]
        rel = sd[rows] / np.abs(v_meas[rows])
        ok = (ratio > 0) & np.isfinite(ratio) & np.isfinite(rel)
        out.append(LinearShift(key, np.where(ok, np.log(np.where(ok, ratio, 1.0)), 0.0).T,
                               np.where(ok, rel, np.inf).T, coupled, cost))
    return out


def load_dependence(meas: dict, sim_est: dict, robot: RobotParams) -> np.ndarray:
    """
    Return each axis' log stiffness scale the chirp sees minus the one the multisine sees.

    One parameter per load against the nominal simulation's estimate
    (:func:`.candidates.stiffness_seen`, the reading stage 2 splits linear from load-dependent
    springs by); 0 where an estimate is missing.

    Parameters
    ----------
    meas, sim_est : dict
        The record's estimates and the nominal simulation's (as :func:`linear_shifts`).
    robot : RobotParams
        The nominal model.

    Returns
    -------
    ndarray, shape (n_axes,)
        log(k_chirp / k_multisine) per axis.

    """
    return np.array([stiffness_seen(meas, sim_est, robot, i, 'chirp')
                     - stiffness_seen(meas, sim_est, robot, i, 'multisine')
                     for i in range(robot.n_axes)])


def fd_parameter_mismatch(shifts: list[LinearShift], robot: RobotParams, axis: int,
                          load_shift: float = 0.0) -> Effect | None:
    """
    Return the parameter mismatch of one axis the FRF fits show at both loads, or None.

    None when the spring is load-dependent (``load_shift`` at least LOAD_DEPENDENCE_MIN_LOG)
    or an estimate's cost test says the model misses structure on the axis (a resonance the
    model lacks shifts the fitted parameters without any of them being off).
    Else a parameter of :data:`FD_KEYS` is named when at both loads its log shift exceeds
    MISMATCH_MIN_LOG and FD_MISMATCH_Z standard errors, with the same sign, and the two
    loads agree (their difference is below LOAD_DEPENDENCE_MIN_LOG or within FD_MISMATCH_Z
    combined standard errors). Its value is the nominal times the inverse-variance mean of
    the two shifts; its standard error that mean's.

    Parameters
    ----------
    shifts : list of LinearShift
        :func:`linear_shifts` of the record; both 'multisine' and 'chirp' are needed.
    robot : RobotParams
        The nominal model.
    axis : int
        The axis.
    load_shift : float, optional
        Log stiffness scale the chirp (high load) sees minus the multisine's (low load), one
        parameter each against the nominal simulation (:func:`.candidates.stiffness_seen`).

    Returns
    -------
    Effect or None
        ``parameter_mismatch`` with the named parameters, their standard errors and the
        evidence (each load's shift and z), or None.

    """
    by = {s.key: s for s in shifts}
    if ('multisine' not in by or 'chirp' not in by or abs(load_shift) >= LOAD_DEPENDENCE_MIN_LOG
            or any(s.structure_missing[axis] for s in shifts)):
        return None
    ms, ch = by['multisine'], by['chirp']
    a = robot.axes[axis]
    changed: dict[str, float] = {}
    se: dict[str, float] = {}
    said = []
    for j, k in enumerate(FD_KEYS):
        d = np.array([ms.log_scale[axis, j], ch.log_scale[axis, j]])
        sd = np.array([ms.std[axis, j], ch.std[axis, j]])
        z = d / sd
        agree = abs(d[0] - d[1]) <= max(LOAD_DEPENDENCE_MIN_LOG,
                                        FD_MISMATCH_Z * math.hypot(*sd))
        if not (agree and np.all(np.abs(d) > MISMATCH_MIN_LOG)
                and np.all(np.abs(z) > FD_MISMATCH_Z) and d[0] * d[1] > 0):
            continue
        w = 1.0 / sd ** 2
        mean, sd_mean = float(w @ d / w.sum()), float(1.0 / math.sqrt(w.sum()))
        changed[k] = getattr(a, k) * math.exp(mean)
        se[k] = changed[k] * sd_mean
        said.append(f'{k} x{math.exp(mean):.3f} +- {sd_mean:.3f} (multisine x{math.exp(d[0]):.3f}'
                    f' z {z[0]:+.1f}, chirp x{math.exp(d[1]):.3f} z {z[1]:+.1f})')
    if not changed:
        return None
    what = 'coupled robot' if ms.coupled else 'two-mass joint'
    return Effect('parameter_mismatch', a.name, 0.0, changed,
                  f'frequency-domain ML fit of the {what} to the multisine (low load) and chirp '
                  f'(high load) FRFs against the same fit of the nominal simulation: '
                  + '; '.join(said) + f'; stiffness scale chirp/multisine '
                  f'x{math.exp(load_shift):.3f} (linear spring); the cost test finds no '
                  f'structure missing', axis, standard_error=se)


def shifts_text(shifts: list, load: np.ndarray, robot: RobotParams) -> str:
    """Return stage 0's log shifts and load dependence per axis, a trace line each."""
    axes = robot.axes
    lines = [f'stage 0 {sh.key}: log shift of ' + ', '.join(
        f'{a.name} ' + '/'.join(f'{d:+.3f}+-{e:.3f}' for d, e in zip(sh.log_scale[i], sh.std[i]))
        for i, a in enumerate(axes)) + ' (motor inertia/link inertia/stiffness)'
        + ''.join(f'; {a.name}: own channel {c:.3g} x its noise per dof'
                  + (' (structure missing)' if m else '')
                  for a, c, m in zip(axes, sh.channel_cost, sh.structure_missing)
                  if np.isfinite(c)) for sh in shifts]
    lines.append('stage 0 load dependence (stiffness scale chirp/multisine): ' + ', '.join(
        f'{a.name} x{math.exp(x):.3f}' for a, x in zip(axes, load)))
    return '\n'.join(lines)
