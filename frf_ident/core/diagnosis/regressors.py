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
Build the regressors of the time-series diagnosis from the measured motion.

The model's residual, the regressor groups of each candidate effect (low-passed like the
residual), which axes move, and which joint sets carry a configuration-dependent load.
"""
from __future__ import annotations

import math

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
import numpy as np

from .residual import (coulomb_and_ripple, effective_samples, inverse_dynamics_residual, is_rigid,
                       lowpass)
from .selection import f_test, lstsq
from .thresholds import ALPHA, BEARING_SHARE, MIN_TRAVEL, ONE_WAY, REST_NOISE, REST_SHARE

#: the groups of a URDF's torques (model keys ``urdf_inertia``, ``urdf_gravity``): one share of
#: a shape the URDF fixes each (no free phase to cancel over a short travel: no leave-range-out)
URDF_GROUPS = ('urdf_inertia', 'urdf_gravity')


def model_residual(rec: Recording, robot: RobotParams) -> tuple[np.ndarray, ...]:
    """
    Return u - (torque the model needs for the measured motion), between samples.

    Linear part from :func:`.residual.inverse_dynamics_residual`, plus the model's own Coulomb
    friction, torque ripple, gravity and share of its URDF's inertia and Coriolis torque
    (``urdf_inertia``; link positions taken as the motor positions: the deflection is far
    below the gravity terms' angular scale).

    Parameters
    ----------
    rec : Recording
        Measured positions [rad], velocities [rad/s] and efforts [N m] of the model's axes.
    robot : RobotParams
        The model whose residual is wanted.

    Returns
    -------
    f, q, v, a : ndarray, shape (N-1, n)
        Residual torque and position, velocity, acceleration between samples.

    """
    f, qh, vh, ah = inverse_dynamics_residual(rec.position, rec.velocity, rec.effort, rec.dt,
                                              robot)
    # the flexible inverse dynamics carries the load in its link-side equation
    grav = robot.gravity_load(qh) if is_rigid(robot, rec.fs) else np.zeros_like(qh)
    pose = robot.urdf_torque(qh, vh, ah)
    return f - coulomb_and_ripple(robot, qh, vh) - grav - pose, qh, vh, ah


def gravity_sets(n: int, i: int) -> list[tuple[int, ...]]:
    """Return the contiguous joint sets containing axis i (the coupled-arm sums)."""
    return [tuple(range(a, b + 1)) for a in range(0, i + 1) for b in range(i, n)]


def link_sets(runs: list[list[int]], i: int) -> list[tuple[int, ...]]:
    """
    Return the joint sets whose angle sums tilt the links that load axis i.

    In a serial arm the links from axis i outward load it; the absolute angle of link j is
    the sum of the joints of the run of parallel bearing axes (:func:`gravity_bearing`) from
    its first axis up to j. So axis i, in a run b..e, depends on the sets (b..j) for
    i <= j <= e; an axis outside every run on none.

    Parameters
    ----------
    runs : list of list of int
        The runs of bearing axes (:func:`gravity_bearing`).
    i : int
        The axis.

    Returns
    -------
    list of tuple of int
        The joint sets, shortest first.

    """
    for run in runs:
        if i in run:
            return [tuple(range(run[0], j + 1)) for j in range(i, run[-1] + 1)]
    return []


def _travels(q: np.ndarray, js: tuple[int, ...]) -> bool:
    """Return whether the angle sum of joint set ``js`` spans more than MIN_TRAVEL."""
    return bool(np.ptp(q[:, list(js)].sum(axis=1)) > MIN_TRAVEL)


def one_way_sets(q: np.ndarray, v: np.ndarray, sets: list[tuple[int, ...]], rows: np.ndarray,
                 fs: float, fc: float) -> list[tuple[int, ...]]:
    """
    Return the joint sets whose angle sum moves (MIN_TRAVEL), but one way only on ``rows``.

    On a single sweep of an angle every quantity along the path (the speed of each axis, a
    velocity-dependent friction law, the configuration-dependent inertia) is a function of
    that angle, so a sinusoid of it fits whatever the model lacks there and is no evidence
    of a load that depends on the configuration. Gravity of a set is tested only where its
    angle sum is seen going both ways (at least ONE_WAY of the rows in each direction, as
    for the Coulomb friction of a one-way axis).

    Parameters
    ----------
    q, v : ndarray, shape (N, n)
        Positions and velocities (between samples).
    sets : list of tuple of int
        The joint sets.
    rows : ndarray of bool, shape (N,)
        The rows the set would be fitted on.
    fs, fc : float
        Sample rate and low-pass cut-off [Hz].

    Returns
    -------
    list of tuple of int
        The sets of ``sets`` whose angle sum moves one way only.

    """
    out = []
    for js in sets:
        if not _travels(q, js):
            continue
        up = lowpass(v[:, list(js)].sum(axis=1), fs, fc)[rows] > 0
        if not up.size or min(float(np.mean(up)), 1.0 - float(np.mean(up))) < ONE_WAY:
            out.append(js)
    return out


def regressor_groups(q, v, a, fs, fc, i, ripple_s, bearing=None, skip=()):
    """
    Return the candidate regressor groups of axis i: name -> low-passed columns (N, k).

    Gravity sets only over the runs ``bearing`` of :func:`gravity_bearing` (all when None),
    none of the sets ``skip`` (those :func:`one_way_sets` finds).
    """
    n = q.shape[1]
    g: dict[str, np.ndarray] = {
        'gravity_torque': np.ones((q.shape[0], 1)),
        'coulomb_friction': np.sign(lowpass(v[:, i], fs, fc))[:, None],
        'viscous_friction': v[:, i:i + 1],
        'motor_inertia': a[:, i:i + 1]}
    if ripple_s:
        g['torque_ripple'] = np.column_stack([np.sin(ripple_s * q[:, i]),
                                              np.cos(ripple_s * q[:, i])])
    sets = [js for js in (gravity_sets(n, i) if bearing is None else link_sets(bearing, i))
            if _travels(q, js) and js not in skip]
    # one gravity group per single set and per pair of sets: a coupled arm's axis carries the
    # weight of its own link and of the links beyond (G1 sin(q2) + G2 sin(q2 + q3)), which a
    # single set approximates with the wrong joints when the motion correlates them
    combos = [(js,) for js in sets] + [(a, b) for k, a in enumerate(sets) for b in sets[k + 1:]]
    for combo in combos:
        cols = []
        for js in combo:
            arg = q[:, list(js)].sum(axis=1)
            cols += [np.sin(arg), np.cos(arg)]
        g['gravity:' + '|'.join(','.join(map(str, js)) for js in combo)] = np.column_stack(cols)
    return {k: lowpass(x, fs, fc) for k, x in g.items()}


def moving(v: np.ndarray, v_raw: np.ndarray, fs: float, fc: float) -> np.ndarray:
    """
    Return where each axis moves: its torque is set by the motion, not held by static friction.

    At rest the joint sticks and its torque is whatever static friction holds (anything
    within the breakaway band, set by the history of the motion), which no friction law of
    the model predicts. An axis moves where its low-passed speed exceeds REST_NOISE times the
    velocity noise (measured as the sample-to-sample scatter of the raw velocity) and
    REST_SHARE of its 95th-percentile speed (below that the Stribeck region begins and the
    sign of the velocity is set by noise); the filter's edge around every velocity reversal
    is left out too.

    Parameters
    ----------
    v : ndarray, shape (N, n)
        Velocities (between samples).
    v_raw : ndarray, shape (M, n)
        The recorded velocities (for the noise level).
    fs, fc : float
        Sample rate and low-pass cut-off [Hz].

    Returns
    -------
    ndarray of bool, shape (N, n)

    """
    vl = lowpass(v, fs, fc)
    vnoise = np.std(np.diff(v_raw, axis=0), axis=0) / math.sqrt(2)
    speed = np.abs(vl)
    out = speed > np.maximum(REST_NOISE * vnoise, REST_SHARE * np.percentile(speed, 95, axis=0))
    guard = int(0.5 * fs / fc)
    for i in range(v.shape[1]):
        for c in np.flatnonzero(np.diff(np.sign(vl[:, i])) != 0):
            out[max(c - guard, 0):c + guard + 1, i] = False
    return out


def axis_masks(rec, f, move, i, fit_m, val_m, fc):
    """
    Return the residual, masks and effective sample count of axis i.

    (low-passed residual, fit mask, held-out mask, effective samples) of axis i: samples at
    rest (:func:`moving`) are left out of fit and validation alike.
    """
    fs = rec.fs
    ff = lowpass(f[:, i], fs, fc)
    fit_i, val_i = fit_m & move[:, i], val_m & move[:, i]
    return ff, fit_i, val_i, effective_samples(int(fit_i.sum()), fs, fc)


def gravity_bearing(q, v, a, fs, fc, prep, skips=None) -> list[list[int]]:
    """
    Return the runs of axes that carry a configuration-dependent (gravity) load.

    An axis carries a configuration-dependent load when G sin(sum of a contiguous joint set
    containing the axis + phi) passes the F test (p < ALPHA) on top of offset, friction and
    inertia and removes at least BEARING_SHARE of what they leave. Only these axes' angles may
    enter gravity arguments (:func:`link_sets`): a joint whose axis carries no gravity (a
    vertical axis) does not tilt the links beyond it. Two neighbouring bearing axes i, i + 1
    belong to one run (parallel joints: q_i tilts the link of axis i + 1) when axis i + 1's
    residual is explained better by a set containing joint i than by any set without it.

    Parameters
    ----------
    q, v, a : ndarray, shape (N, n)
        Positions, velocities, accelerations between samples.
    fs, fc : float
        Sample rate and low-pass cut-off [Hz].
    prep : list
        Per axis (residual, fit mask, held-out mask, effective samples).
    skips : list of list of tuple of int, optional
        Per axis the joint sets that are no candidates (:func:`one_way_sets`); none if omitted.

    Returns
    -------
    list of list of int
        The runs, each a list of consecutive axes.

    """
    bearing: list[int] = []
    share: dict[tuple[int, tuple[int, ...]], float] = {}
    n = q.shape[1]
    for i, (ff, fit_i, val_i, n_eff) in enumerate(prep):
        g = regressor_groups(q, v, a, fs, fc, i, 0.0, None, skips[i] if skips else ())
        base = [g[k][fit_i] for k in ('gravity_torque', 'coulomb_friction', 'viscous_friction',
                                      'motor_inertia')]
        _, rss0 = lstsq(base, ff[fit_i])
        for js in gravity_sets(n, i):
            key = 'gravity:' + ','.join(map(str, js))
            if key not in g:
                continue
            _, rss1 = lstsq(base + [g[key][fit_i]], ff[fit_i])
            share[i, js] = (rss0 - rss1) / max(rss0, 1e-300)
            # significant and large: a slow residual of friction the model lacks (a
            # degressive law) passes the F test against a sinusoid over a short travel, but a
            # link's weight dominates the residual of the axis that carries it
            if (f_test(rss0, rss1, 2, 6, n_eff) < math.log(ALPHA)
                    and share[i, js] >= BEARING_SHARE and i not in bearing):
                bearing.append(i)
    runs: list[list[int]] = []
    for i in bearing:
        if runs and runs[-1][-1] == i - 1:
            with_prev = max((v for (k, js), v in share.items() if k == i and i - 1 in js),
                            default=0.0)
            without = max((v for (k, js), v in share.items() if k == i and i - 1 not in js),
                          default=0.0)
            if with_prev > without:
                runs[-1].append(i)
                continue
        runs.append([i])
    return runs
