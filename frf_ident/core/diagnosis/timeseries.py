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
Diagnose plain time series by regression of the inverse-dynamics residual.

Diagnosis of plain time series (recorded trajectories, imported CSV/MAT): no identification
experiments, so the evidence is the motor-side inverse-dynamics residual of the nominal model
(:mod:`.residual`), regressed per axis on the signatures of the candidate effects:

=====================  =====================================================================
group                  regressors (low-passed like the residual)
=====================  =====================================================================
coulomb_friction       sgn(dq)                                           (eq. 1)
viscous_friction       dq
parameter_mismatch     ddq (inertia)
torque_ripple          sin / cos (s q) at the spatial frequency of the position scan
gravity                1 (constant load) and sin / cos (sum of q over a contiguous set of
                       joints containing the axis): G sin(q_i + phi) of a link about its own
                       joint, or sums over the joints it depends on for a coupled arm
=====================  =====================================================================

Groups enter by forward selection with an F test at the data's own noise (residual variance,
effective sample count of the filtered signals, false-alarm probability ``ALPHA``), all selected
groups are refitted jointly, and a group is dropped when removing it does not worsen the
held-out error. Held out: every third block of 0.5 s (:func:`split_blocks`).

``time_nrmse`` is the error of the torque the model predicts from the measured motion
(inverse dynamics) over the RMS of the measured torque, both low-pass filtered; the model is
the model file itself (nominal or extended), so the same number can be computed on any other
record (``--validate``). ``frf_error_db`` compares the measured u -> dq FRF (Welch H1) with the
one of the predicted torque, on the lines with coherence > 0.5.
"""
from __future__ import annotations

from dataclasses import replace
import math
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.progress import Progress, sink
from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError
import numpy as np
from scipy import signal, stats

from .common import bridge_gaps, Effect
from .residual import (coulomb_and_ripple, effective_samples, FC_HZ, find_ripple,
                       inverse_dynamics_residual, is_rigid, lowpass)

__all__ = ['ALPHA', 'FC_HZ', 'block_standard_errors', 'diagnose_timeseries', 'f_test',
           'model_residual', 'noise_level', 'predict_metrics']

ALPHA = 1e-3          # false-alarm probability of the F test that admits a regressor group
EDGE = 0.02           # share of the record left out at each end of fit and held-out parts
BLOCK_S = 0.5         # fit / held-out blocks [s]
HOLD_EVERY = 3        # every third block is held out
UNEXPLAINED_RATIO = 4.0   # held-out misfit energy above this many noise floors is unexplained
MIN_SHARE = 0.10          # ... when it is also at least this share of the nominal misfit
BEARING_SHARE = 0.5       # a link's weight dominates what friction and inertia leave of its axis
REST_NOISE = 0.3          # an axis is at rest below this many velocity-noise levels ...
REST_SHARE = 0.05         # ... or below this share of its 95th-percentile speed
#: an axis whose 95th-percentile speed is below this many velocity-noise levels does not move
#: at all (a record of a robot at rest)
STILL_NOISE = 3.0
ONE_WAY = 0.05            # an axis with fewer moving samples in one direction moves one way
MIN_TRAVEL = 1e-3         # [rad] a joint set whose angle sum spans less is no gravity candidate


#: evidence sentence of each one-coefficient regressor group (c: fitted coefficient)
_SCALAR_EVIDENCE = {
    'coulomb_friction': ('inverse-dynamics residual steps by {step:.3g} (torque units) at each '
                         'velocity reversal (F test p = {p:.2g}; removing it raises the held-out '
                         'residual energy by {gain:.0f} %)'),
    'viscous_friction': ('residual proportional to velocity: {c:+.4g} per unit velocity '
                         '(p = {p:.2g})'),
    'motor_inertia': ('residual proportional to acceleration: inertia {old:.4g} -> {new:.4g} '
                      '(p = {p:.2g})'),
    'gravity_torque': ('constant torque residual {c:+.3g} (a load or friction asymmetry the model '
                       'lacks; p = {p:.2g})'),
}
#: evidence of the constant fitted without a test on an axis that moves one way only
_ONE_WAY_EVIDENCE = ('constant torque residual {c:+.3g} while the axis moves one way only: '
                     'Coulomb friction and a constant load (gravity at the operating point) in '
                     'one parameter, always fitted (not tested)')


def model_residual(rec: Recording, robot: RobotParams) -> tuple[np.ndarray, ...]:
    """
    Return u - (torque the model needs for the measured motion), between samples.

    Linear part from :func:`.residual.inverse_dynamics_residual`, plus the model's own Coulomb
    friction, torque ripple and gravity (link positions taken as the motor positions: the
    deflection is far below the gravity terms' angular scale).

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
    return f - coulomb_and_ripple(robot, qh, vh) - grav, qh, vh, ah


def _gravity_sets(n: int, i: int) -> list[tuple[int, ...]]:
    """Return the contiguous joint sets containing axis i (the coupled-arm sums)."""
    return [tuple(range(a, b + 1)) for a in range(0, i + 1) for b in range(i, n)]


def _link_sets(runs: list[list[int]], i: int) -> list[tuple[int, ...]]:
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


def _groups(q, v, a, fs, fc, i, ripple_s, bearing=None, skip=()):
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
    sets = [js for js in (_gravity_sets(n, i) if bearing is None else _link_sets(bearing, i))
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


def _by_group(coef: np.ndarray, groups: dict[str, np.ndarray], chosen: list[str]
              ) -> dict[str, np.ndarray]:
    """Return the joint fit's coefficients ``coef`` split into the groups ``chosen``."""
    out, k0 = {}, 0
    for k in chosen:
        w = groups[k].shape[1]
        out[k] = coef[k0:k0 + w]
        k0 += w
    return out


def _lstsq(cols: list[np.ndarray], y: np.ndarray) -> tuple[np.ndarray, float]:
    if not cols:
        return np.zeros(0), float(y @ y)
    X = np.column_stack(cols)
    c, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ c
    return c, float(r @ r)


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


def _axis_masks(rec, f, move, i, fit_m, val_m, fc):
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
    enter gravity arguments (:func:`_link_sets`): a joint whose axis carries no gravity (a
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
        g = _groups(q, v, a, fs, fc, i, 0.0, None, skips[i] if skips else ())
        base = [g[k][fit_i] for k in ('gravity_torque', 'coulomb_friction', 'viscous_friction',
                                      'motor_inertia')]
        _, rss0 = _lstsq(base, ff[fit_i])
        for js in _gravity_sets(n, i):
            key = 'gravity:' + ','.join(map(str, js))
            if key not in g:
                continue
            _, rss1 = _lstsq(base + [g[key][fit_i]], ff[fit_i])
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


def f_test(rss0: float, rss1: float, q: int, p: int, n_eff: float) -> float:
    """
    Return the log p-value of the F test that q added regressors reduce rss0 to rss1.

    The residual is low-passed: its N samples hold only ``n_eff`` independent ones
    (:func:`.residual.effective_samples`), and a regressor as slow as the residual picks up
    N / n_eff times a sample's noise variance per coefficient. ``rss1 / (n_eff - p)`` is that
    variance, so the plain F ratio has the F(q, n_eff - p) distribution under the null
    (test/core/diagnosis/test_diagnosis.py checks the false-alarm rate by Monte Carlo).

    Parameters
    ----------
    rss0, rss1 : float
        Residual sums of squares without and with the q regressors (all N samples).
    q : int
        Number of added regressors.
    p : int
        Number of regressors of the larger model.
    n_eff : float
        Effective number of independent samples.

    Returns
    -------
    float
        log p (0 when the regressors do not reduce the residual).

    """
    dof = max(n_eff - p, 1.0)
    F = ((rss0 - rss1) / q) / max(rss1 / dof, 1e-300)
    return float(stats.f.logsf(F, q, dof)) if F > 0 else 0.0


def select_groups(groups: dict[str, np.ndarray], y: np.ndarray, fit: np.ndarray,
                  val: np.ndarray, n_eff: float, forced: list[str] | tuple[str, ...] = ()
                  ) -> tuple[list[str], dict[str, dict]]:
    """
    Select regressor groups by F test and held-out error.

    Forward selection by F test (p < ALPHA at ``n_eff`` effective samples) on top of the
    ``forced`` groups, then removal of every other group whose absence does not worsen the
    held-out residual, repeated without the removed groups until none is removed (stepwise
    regression: a group that only stood in for another one no longer keeps it out). Returns
    the selected names and per candidate {'p', 'share', 'held_out_gain'} for the report.
    """
    chosen: list[str] = list(forced)
    info: dict[str, dict] = {k: {'p': 0.0, 'share': 0.0, 'forced': True} for k in forced}
    yf = y[fit]
    tot = float((yf - yf.mean()) @ (yf - yf.mean())) or 1e-300
    dropped: set[str] = set()
    while True:
        _forward(groups, yf, fit, n_eff, chosen, dropped, info, tot)
        removed = _backward(groups, y, fit, val, chosen, forced, info)
        # stepwise: a group dropped on held-out data may have kept out another that the
        # forward pass now admits (a one-off sinusoid standing in for the friction)
        if not removed:
            return chosen, info
        dropped |= set(removed)


def _forward(groups, yf, fit, n_eff, chosen, dropped, info, tot):
    """Add to ``chosen`` the groups (not in ``dropped``) that pass the F test, best first."""
    while True:
        _, rss0 = _lstsq([groups[k][fit] for k in chosen], yf)
        # ranked by log p, then (where log p underflows too, a link's weight against a
        # friction-free model) by the Bayesian information criterion on effective samples
        best, bp = None, (math.log(ALPHA), math.inf)
        for k, x in groups.items():
            if k in chosen or k in dropped or (k.startswith('gravity:') and any(
                    c.startswith('gravity:') for c in chosen)):
                continue
            cols = [groups[c][fit] for c in chosen] + [x[fit]]
            _, rss1 = _lstsq(cols, yf)
            q = x.shape[1]
            p_tot = sum(groups[c].shape[1] for c in chosen) + q
            lp = f_test(rss0, rss1, q, p_tot, n_eff)
            info.setdefault(k, {})
            info[k].update(p=math.exp(lp), share=(rss0 - rss1) / tot)
            key = (lp, n_eff * math.log(max(rss1, 1e-300)) + p_tot * math.log(n_eff))
            if key < bp:
                best, bp = k, key
        if best is None:
            return
        chosen.append(best)


def _backward(groups, y, fit, val, chosen, forced, info) -> list[str]:
    """
    Remove from ``chosen`` every group whose absence does not worsen the held-out error.

    One at a time, the one whose absence helps most first; returns the removed names.
    """
    yf = y[fit]

    def held(names):
        """Return the held-out residual energy of the groups ``names`` refitted jointly."""
        c, _ = _lstsq([groups[k][fit] for k in names], yf)
        if not names:
            r = y[val]
        else:
            r = y[val] - np.column_stack([groups[k][val] for k in names]) @ c
        return float(r @ r)
    removed = []
    while True:
        # the group whose absence helps the held-out data most goes first, then the rest are
        # judged again without it (two collinear groups each look useless next to the other)
        with_k = held(chosen)
        for k in chosen:
            without = held([c for c in chosen if c != k])
            info[k]['held_out_gain'] = (without - with_k) / max(without, 1e-300)
        worst = min((k for k in chosen if k not in forced),
                    key=lambda k: info[k]['held_out_gain'], default=None)
        if worst is None or info[worst]['held_out_gain'] > 0:
            return removed
        chosen.remove(worst)
        removed.append(worst)


def _block_length(fs: float) -> int:
    """Return the length of a fit / held-out block [samples]: BLOCK_S, at least 8."""
    # rounded: a rate taken from float timestamps (249.99999999999977 Hz for 4 ms) must not
    # cut a sample off every block, and the two halves of one record then differ in blocks
    return max(int(round(BLOCK_S * fs)), 8)


def check_diagnosable(rec: Recording, names: list[str], fit: np.ndarray | None = None,
                      held: np.ndarray | None = None) -> None:
    """
    Refuse a record the time-series diagnosis cannot judge.

    It needs HOLD_EVERY blocks of BLOCK_S (fit and held-out data), an effort that varies on
    every axis (an all-zero effort is a wrong column, not a robot) and, given ``fit`` and
    ``held``, an axis that moves in both the fit and the held-out blocks and moves at all:
    its 95th-percentile low-passed speed above STILL_NOISE velocity-noise levels (the rest
    masks of :func:`moving` are relative, so a robot at rest shows its noise as motion).

    Parameters
    ----------
    rec : Recording
        The record.
    names : list of str
        The model's joint names (recording column order).
    fit, held : ndarray of bool, shape (N - 1, n), optional
        Where each axis moves (:func:`moving`) in the fit and in the held-out blocks
        (:func:`split_blocks`); not checked when omitted.

    Raises
    ------
    EstimationError
        The record is too short, an axis' effort is constant, or no axis moves.

    """
    need = HOLD_EVERY * _block_length(rec.fs)
    if rec.t.size < need:
        raise EstimationError(f'the record holds {rec.t.size} samples ({rec.t.size / rec.fs:.3g} '
                              f's): the diagnosis needs at least {need} ({need / rec.fs:.3g} s: '
                              f'{HOLD_EVERY} blocks of {BLOCK_S} s, one of them held out)')
    for i, name in enumerate(names):
        e = rec.effort[:, i]
        e = e[np.isfinite(e)]
        if e.size and np.ptp(e) == 0.0:
            raise EstimationError(f'the effort of {name} is {e[0]:g} N m at every sample: no '
                                  "measured torque (check the map's effort column)")
    if fit is not None and held is not None:
        v = np.nan_to_num(rec.velocity)
        vnoise = np.std(np.diff(v, axis=0), axis=0) / math.sqrt(2)
        speed = np.percentile(np.abs(lowpass(v, rec.fs, FC_HZ)), 95, axis=0)
        if not np.any(fit.any(axis=0) & held.any(axis=0) & (speed > STILL_NOISE * vnoise)):
            raise EstimationError('no axis moves in this record (each axis rests or creeps '
                                  'below its velocity noise): the diagnosis compares torques '
                                  'along a motion')


def split_blocks(n: int, fs: float, fc: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the fit and held-out masks of interleaved blocks.

    Fit and held-out masks: the record cut into blocks of BLOCK_S, every HOLD_EVERY-th
    held out (interleaved, so held-out data cover the same configurations as the fit instead
    of extrapolating to the end of a short trajectory), a guard of half a filter period
    dropped at every block boundary and EDGE of the record at both ends.
    """
    blk = _block_length(fs)
    k = np.arange(n)
    held = (k // blk) % HOLD_EVERY == HOLD_EVERY - 1
    guard = int(0.5 * fs / fc)
    near = np.zeros(n, bool)
    for b in range(blk, n, blk):
        near[max(b - guard, 0):b + guard] = True
    e = int(EDGE * n)
    near[:e] = near[n - e:] = True
    return ~held & ~near, held & ~near


def block_standard_errors(groups: dict[str, np.ndarray], chosen: list[str], y: np.ndarray,
                          fit: np.ndarray, fs: float) -> dict[str, np.ndarray]:
    """
    Return block-robust (CR2) standard errors of the jointly fitted groups.

    The covariance of the joint least-squares fit of the groups ``chosen`` is the sandwich
    (X'X)^-1 (sum_b X_b' A_b e_b e_b' A_b X_b) (X'X)^-1 over the blocks b of the fit rows
    (as long as the held-out blocks of :func:`split_blocks`), e_b the block's residuals and
    A_b = (I - H_bb)^-1/2 with H_bb the block's part of the hat matrix: the bias-reduced
    cluster-robust estimator CR2 (Bell & McCaffrey 2002), unbiased for independent
    homoscedastic noise however few the blocks. A block is far longer than the low-passed
    residual's correlation time, so the sandwich takes the residual as it is: coloured, and
    with whatever misfit the model still has within a block, where a formula for white noise
    would not (README_diagnosis.md, "Standard errors"). The error of the amplitude
    hypot(a_sin, a_cos) of a sin / cos pair is its spread under the pair's normal distribution.

    Parameters
    ----------
    groups : dict of str to ndarray, shape (N, k)
        The regressor groups (low-passed columns).
    chosen : list of str
        The groups fitted jointly.
    y : ndarray, shape (N,)
        The low-passed residual.
    fit : ndarray of bool, shape (N,)
        The rows fitted on.
    fs : float
        Sample rate [Hz] (the blocks are BLOCK_S long).

    Returns
    -------
    dict of str to ndarray
        Per group the standard error of each quantity it reports: its coefficient (one
        column) or the amplitude of each sin / cos pair; NaN for all when fewer than 3 blocks
        hold fit rows.

    """
    ids = (np.arange(y.size) // _block_length(fs))[fit]
    used = np.unique(ids)
    if used.size < 3 or not chosen:
        return {k: np.full(max(groups[k].shape[1] // 2, 1), math.nan) for k in chosen}
    X = np.column_stack([groups[k][fit] for k in chosen])
    bread = np.linalg.pinv(X.T @ X)
    coef = bread @ (X.T @ y[fit])
    e = y[fit] - X @ coef
    # H_bb = A A' with A = X_b (X'X)^-1/2: its nonzero eigenvalues are the squared singular
    # values of A (at most one per column), so (I - H_bb)^-1/2 e_b costs O(n_b p^2)
    lam, vec = np.linalg.eigh(bread)
    half = (vec * np.sqrt(np.maximum(lam, 0.0))) @ vec.T
    meat = np.zeros_like(bread)
    for b in used:
        xb, eb = X[ids == b], e[ids == b]
        u, sv, _ = np.linalg.svd(xb @ half, full_matrices=False)
        # an eigenvalue of I - H_bb near 0 is a block the fit rests on alone
        gain = 1.0 / np.sqrt(np.maximum(1.0 - sv ** 2, 1e-12)) - 1.0
        score = xb.T @ (eb + u @ (gain * (u.T @ eb)))
        meat += np.outer(score, score)
    cov = bread @ meat @ bread
    out = {}
    for k, ix in _by_group(np.arange(coef.size), groups, chosen).items():
        if ix.size == 1:
            out[k] = np.sqrt(np.maximum(cov[ix, ix], 0.0))
        else:
            # amplitudes: the spread of hypot(a_sin, a_cos) over draws from the pair's normal
            # distribution (not the delta method, which misses an ill-determined phase)
            out[k] = np.array([np.std(np.hypot(*_normal_draws(coef[p], cov[np.ix_(p, p)])))
                               for p in ix.reshape(-1, 2)])
    return out


def _normal_draws(mean: np.ndarray, cov: np.ndarray, n: int = 4000) -> np.ndarray:
    """Return ``n`` fixed draws (2, n) of the normal distribution (mean, cov) of a pair."""
    w, u = np.linalg.eigh(cov)
    z = np.random.default_rng(0).standard_normal((2, n))
    return mean[:, None] + u @ (np.sqrt(np.maximum(w, 0.0))[:, None] * z)


def diagnose_timeseries(rec: Recording, robot: RobotParams, *, fc: float = FC_HZ,
                        progress: Progress | None = None
                        ) -> dict[str, Any]:
    """
    Diagnose a time-series recording against the nominal ``robot``.

    Per axis: residual regression on the fit blocks of :func:`split_blocks`, effects
    selected by F test and held-out error, the extended model, metrics on the held-out blocks.

    Parameters
    ----------
    rec
        The recording (positions, velocities, efforts of the model's axes).
    robot
        The nominal model.
    fc
        Low-pass cut-off of residual and regressors [Hz].
    progress
        Callback for progress lines.

    Returns
    -------
    dict with 'effects' (ranked), 'extended' (RobotParams), 'metrics' (docs/CONTRACT.md §7),
    'unexplained', 'rejected' (candidates with their numbers), 'residual' (for the plots).

    """
    say = sink(progress)
    check_diagnosable(rec, robot.joint_names)
    rec, lost = bridge_gaps(rec)
    fs = rec.fs
    N = rec.t.size
    f, qh, vh, ah = model_residual(rec, robot)
    fit_m, val_m = split_blocks(N - 1, fs, fc)
    # rows bridged over gaps of the record take part in neither fit nor validation
    kept = ~(lost[1:] | lost[:-1])
    fit_m, val_m = fit_m & kept, val_m & kept
    effects: list[Effect] = []
    rejected: list[dict[str, Any]] = []
    ext_axes = list(robot.axes)
    names = robot.joint_names
    move = moving(vh, rec.velocity, fs, fc)
    check_diagnosable(rec, names, move & fit_m[:, None], move & val_m[:, None])
    prep = [_axis_masks(rec, f, move, i, fit_m, val_m, fc) for i in range(robot.n_axes)]
    skips = [one_way_sets(qh, vh, _gravity_sets(robot.n_axes, i), prep[i][1], fs, fc)
             for i in range(robot.n_axes)]
    bearing = gravity_bearing(qh, vh, ah, fs, fc, prep, skips)
    say(f'axes whose own angle carries a configuration-dependent load (runs of parallel '
        f'joints): {[[names[i] for i in run] for run in bearing] or "none"}')
    for i, ax in enumerate(robot.axes):
        ff, fit_i, val_i, n_eff = prep[i]
        skip = skips[i]
        g0 = _groups(qh, vh, ah, fs, fc, i, 0.0, bearing, skip)
        if skip:
            rejected.append({'name': 'gravity', 'axis': ax.name, 'reason': (
                'not testable in this record: ' + ', '.join(
                    ' + '.join('q_' + names[j] for j in js) for js in skip)
                + ' moves one way only where the axis moves, so a sinusoid of it fits any '
                  'torque that changes along the path (friction, inertia)')})
        # the scan's base also takes a slow trend in the axis' own position (a cable
        # carrier's spring, a load of a non-bearing axis): over the 1.5 cycles at the low
        # end of the scan it poses as a ripple, which repeats along the travel and a trend
        # does not
        qc = qh[:, i] - qh[fit_i, i].mean() if fit_i.any() else qh[:, i]
        trend = np.column_stack([qc, qc ** 2])
        X0 = np.column_stack(list(g0.values()) + [lowpass(trend, fs, fc)])
        c0, *_ = np.linalg.lstsq(X0[fit_i], ff[fit_i], rcond=None)
        wide = lowpass(f[:, i], fs, 0.45 * fs) - np.column_stack(
            list(_groups(qh, vh, ah, fs, 0.45 * fs, i, 0.0, bearing, skip).values())
            + [lowpass(trend, fs, 0.45 * fs)]) @ c0
        s, peak, thr = find_ripple(wide, qh[:, i], fit_i)
        groups = _groups(qh, vh, ah, fs, fc, i, s if peak >= thr else 0.0, bearing, skip)
        up = float(np.mean(vh[fit_i, i] > 0)) if fit_i.any() else 0.0
        if min(up, 1.0 - up) < ONE_WAY:
            # one direction only: sgn(v) is the constant column, Coulomb friction a load
            # (always fitted: the robot has friction, no other term may take its torque)
            del groups['coulomb_friction']
            forced = ['gravity_torque']
            rejected.append({'name': 'coulomb_friction', 'axis': ax.name,
                             'forward_share': round(up, 3),
                             'reason': f'the axis moves one way only in this record '
                                       f'({100 * up:.0f} % of its moving samples forward): '
                                       f'Coulomb friction and a constant load are one '
                                       f'parameter here'})
        else:
            forced = []
        chosen, info = select_groups(groups, ff, fit_i, val_i, n_eff, forced=forced)
        unphysical: dict[str, dict] = {}
        while True:
            coef, _ = _lstsq([groups[k][fit_i] for k in chosen], ff[fit_i])
            cf = _by_group(coef, groups, chosen)
            # a fit that leaves the physical range (negative friction or inertia) is no
            # evidence of that effect: drop the group and select again without it, since it
            # may have kept out the group that carries that torque (KUKA A, joint_3: an
            # inertia of -3.27 stood in for a constant load, which now enters)
            bad = [k for k, base in (('coulomb_friction', ax.coulomb_friction),
                                     ('viscous_friction', ax.viscous_friction),
                                     ('motor_inertia', ax.motor_inertia))
                   if k in cf and base + float(cf[k][0]) <= 0]
            if not bad:
                break
            unphysical.update({k: {**info[k], 'unphysical': getattr(ax, k) + float(cf[k][0])}
                               for k in bad})
            groups = {k: x for k, x in groups.items() if k not in unphysical}
            chosen, info = select_groups(groups, ff, fit_i, val_i, n_eff, forced=forced)
        info = {**unphysical, **info}
        say(f'{ax.name}: selected {chosen} (ripple scan peak {peak:.1f}, threshold {thr:.1f}); '
            + ', '.join(f'{k} p={v.get("p", 1):.2g} share={v.get("share", 0):.3f}'
                        for k, v in info.items()))
        ch: dict[str, Any] = {}
        for k, v in info.items():
            if k not in chosen:
                rejected.append({'name': k.split(':')[0], 'axis': ax.name,
                                 'p_value': float(f'{v.get("p", 1.0):.3g}'),
                                 'residual_share': round(float(v.get('share', 0.0)), 4),
                                 'held_out_gain': round(float(v.get('held_out_gain', 0.0)), 4)})
                if 'unphysical' in v:
                    rejected[-1].update(fitted_value=round(v['unphysical'], 4), reason=(
                        f'the joint fit gives {k} = {v["unphysical"]:.3g}, outside the '
                        f'physical range: another term the model lacks'))
        score = {k: float(np.clip(info[k].get('held_out_gain', 0.0), 0, 1)) for k in chosen}
        se = block_standard_errors(groups, chosen, ff, fit_i, fs)
        for k in ('coulomb_friction', 'viscous_friction', 'motor_inertia', 'torque_ripple',
                  'gravity_torque'):
            if k not in cf:
                continue
            if k == 'torque_ripple':
                a_s, a_c = (float(x) for x in cf[k])
                amp = math.hypot(a_s, a_c)
                rip = {'amplitude': amp, 'spatial_frequency': s,
                       'phase': math.atan2(-a_c, -a_s)}
                ch[k] = list(ax.torque_ripple) + [rip]
                err = {k: [None] * len(ax.torque_ripple) + [{'amplitude': _se(se[k][0])}]}
                text = (f'residual periodic in position: amplitude {amp:.3g}{_pm(se[k][0])} at '
                        f'{s:.4g} /rad (scan peak {peak:.0f}x the local noise level, '
                        f'false-alarm level {thr:.0f})')
            else:
                # f = u - model: the coefficient adds to the model's value
                c = float(cf[k][0])
                ch[k] = getattr(ax, k) + c
                form = _ONE_WAY_EVIDENCE if info[k].get('forced') else _SCALAR_EVIDENCE[k]
                text = form.format(
                    c=c, step=2 * c, old=getattr(ax, k), new=ch[k], p=info[k]['p'],
                    gain=100 * info[k].get('held_out_gain', 0.0))
                if math.isfinite(se[k][0]):
                    text += f'; {k} = {ch[k]:.4g}{_pm(se[k][0])}'
                err = {k: _se(se[k][0])}
            name = 'parameter_mismatch' if k in ('motor_inertia', 'gravity_torque') else k
            effects.append(Effect(name, ax.name, score[k], {k: ch[k]}, text, i,
                                  standard_error=err))
        gk = [k for k in chosen if k.startswith('gravity:')]
        if gk:
            terms = list(ax.gravity)
            errs: list[dict[str, float | None] | None] = [None] * len(terms)
            parts = []
            for k in gk:
                for t_i, set_text in enumerate(k.split(':')[1].split('|')):
                    js = [int(x) for x in set_text.split(',')]
                    a_s, a_c = (float(x) for x in cf[k][2 * t_i:2 * t_i + 2])
                    # residual = +G sin(arg + phi) = G cos(phi) sin(arg) + G sin(phi) cos(arg)
                    term = {'amplitude': math.hypot(a_s, a_c), 'phase': math.atan2(a_c, a_s),
                            'joints': [names[j] for j in js]}
                    terms.append(term)
                    errs.append({'amplitude': _se(se[k][t_i])})
                    parts.append(f'{term["amplitude"]:.3g}{_pm(se[k][t_i])} sin('
                                 f'{" + ".join("q_" + names[j] for j in js)} '
                                 f'{term["phase"]:+.2f})')
            ch['gravity'] = terms
            effects.append(Effect(
                'gravity', ax.name, max(score[k] for k in gk), {'gravity': terms},
                f'residual follows the configuration: {", ".join(parts)} (torque units; '
                f'held-out gain {100 * max(score[k] for k in gk):.0f} %)', i,
                standard_error={'gravity': errs}))
        ext_axes[i] = replace(ax, **ch)
    effects.sort(key=lambda x: -x.score)
    ext = replace(robot, axes=ext_axes)
    metrics: dict[str, Any] = {}
    val = {}
    for key, model in (('baseline', robot), ('extended', ext)):
        val[key] = predict_metrics(rec, model, fc=fc, mask=val_m)
        metrics[key] = {k: val[key][k] for k in ('frf_error_db', 'time_nrmse', 'per_axis')}
    metrics['validation'] = (f'held out (not used for fitting): every {HOLD_EVERY}rd block of '
                             f'{BLOCK_S:g} s ({val_m.sum() / fs:.2f} s of {N / fs:.2f} s); '
                             f'time_nrmse = error of the '
                             f'inverse-dynamics torque of the model file over the RMS of the '
                             f'measured torque ({fc:g} Hz low-pass)')
    unexplained = []
    # over the rows the held-out NRMSE is taken over (a long rest lowers the torque variance)
    floor = noise_floor(rec, f, fc, val['extended']['rows'])
    for i, ax in enumerate(robot.axes):
        b = val['baseline']['per_axis'][ax.name]['time_nrmse'] ** 2
        x = val['extended']['per_axis'][ax.name]['time_nrmse'] ** 2
        share = float(np.clip((x - floor[i]) / max(b - floor[i], 1e-300), 0, 1))
        if x > UNEXPLAINED_RATIO * floor[i] and share >= MIN_SHARE:
            unexplained.append({'axis': ax.name, 'misfit_share': round(share, 3),
                                'signature': signature(val['extended']['residual'][:, i],
                                                       qh[:, i], vh[:, i], ah[:, i],
                                                       rec.t[:-1], val_m, fs, fc)})
    return {'effects': effects, 'extended': ext, 'metrics': metrics, 'unexplained': unexplained,
            'rejected': rejected, 'noise_floor_nrmse2': floor.tolist(),
            'residual': {'t': rec.t[:-1], 'f': f, 'q': qh, 'v': vh,
                         'pred_baseline': lowpass(f, fs, fc) - val['baseline']['residual'],
                         'pred_extended': lowpass(f, fs, fc) - val['extended']['residual'],
                         'val_mask': val_m}}


def _se(x: float) -> float | None:
    """Return a standard error for the report: None when there were too few blocks."""
    return None if not math.isfinite(x) else float(x)


def _pm(x: float) -> str:
    """Return ' +- se' for the evidence text ('' without a standard error)."""
    return f' \u00b1 {x:.2g}' if math.isfinite(x) else ''


def noise_floor(rec: Recording, f: np.ndarray, fc: float, use: np.ndarray | None = None
                ) -> np.ndarray:
    """
    Return per axis the NRMSE^2 that torque noise alone leaves.

    Per axis NRMSE^2 that torque noise alone leaves after the fc low-pass: the white level
    of the residual (:func:`noise_level`) times the bandwidth fc, over the variance of the
    low-passed torque on the rows the NRMSE is taken over.

    Parameters
    ----------
    rec : Recording
        The recording.
    f : ndarray, shape (N-1, n)
        The model's torque residual (:func:`model_residual`).
    fc : float
        Low-pass cut-off of the metric [Hz].
    use : ndarray of bool, shape (N-1, n), optional
        Per axis the rows the NRMSE is taken over (``rows`` of :func:`predict_metrics`); all
        rows if omitted.

    Returns
    -------
    ndarray, shape (n,)
        The floor per axis.

    """
    fs = rec.fs
    level = noise_level(f, fs)
    uf = lowpass(rec.effort[:-1], fs, fc)
    var_u = np.array([np.var(uf[use[:, i], i]) if use is not None and use[:, i].sum() > 1
                      else np.var(uf[:, i]) for i in range(uf.shape[1])])
    return level * min(fc, fs / 2) / np.maximum(var_u, 1e-300)


def noise_level(f: np.ndarray, fs: float) -> np.ndarray:
    """
    Return per axis the white torque-noise level of a residual [torque^2 / Hz].

    The median one-sided power spectral density (Welch) between 0.6 and 0.95 of the Nyquist
    frequency, where the motion leaves little; a white noise of standard deviation sigma has
    the level 2 sigma^2 / fs.

    Parameters
    ----------
    f : ndarray, shape (N, n)
        A torque residual (:func:`model_residual`).
    fs : float
        Sample rate [Hz].

    Returns
    -------
    ndarray, shape (n,)
        The level per axis (zeros when the record is too short to have that band).

    """
    nper = int(min(2 ** int(math.log2(max(f.shape[0] // 8, 64))), 4096))
    fr, p = signal.welch(f, fs=fs, nperseg=nper, axis=0)
    sel = (fr > 0.6 * fs / 2) & (fr < 0.95 * fs / 2)
    return np.median(p[sel], axis=0) if sel.any() else np.zeros(f.shape[1])


def signature(res: np.ndarray, q, v, a, t, mask, fs, fc) -> dict[str, Any]:
    """
    Return where a held-out residual lives (band and correlated signal).

    Where a held-out residual lives: the band [f1, f2] Hz holding the middle half of its
    power (quartiles below fc) and the signal it correlates with most (|r| >= 0.3).
    """
    out: dict[str, Any] = {}
    r = res[mask]
    if r.size >= 64:
        nper = int(min(2 ** int(math.log2(r.size // 4)), 4096))
        fr, p = signal.welch(r, fs=fs, nperseg=nper)
        sel = (fr > 0) & (fr <= fc)
        if sel.any() and p[sel].sum() > 0:
            c = np.cumsum(p[sel]) / p[sel].sum()
            fsel = fr[sel]
            df = float(fr[1] - fr[0])      # a spectral line stands for its bin's width
            out['band_hz'] = [round(max(float(fsel[np.searchsorted(c, 0.25)]) - df, 0.0), 2),
                              round(float(fsel[min(np.searchsorted(c, 0.75), fsel.size - 1)])
                                    + df, 2)]
    best, rb = None, 0.3
    rr = r - r.mean()
    for name, x in (('position', q), ('velocity', v), ('acceleration', a), ('time', t)):
        xm = x[mask] - x[mask].mean()
        den = math.sqrt(float(xm @ xm) * float(rr @ rr))
        c = abs(float(xm @ rr)) / den if den > 0 else 0.0
        if c >= rb:
            best, rb = name, c
    if best:
        out['correlates_with'] = best
    return out


def predict_metrics(rec: Recording, robot: RobotParams, *, fc: float = FC_HZ,
                    mask: np.ndarray | None = None) -> dict[str, Any]:
    """
    Return held-out metrics of a model file on a recording.

    Held-out metrics of a model file on a recording: the torque the model predicts from
    the measured motion against the measured torque (both low-passed at fc), on ``mask``
    (between samples, N-1; default all but the ends), never on rows bridged over a gap
    (:func:`.common.bridge_gaps`).

    Parameters
    ----------
    rec : Recording
        The record (any record of the robot, not necessarily the one fitted).
    robot : RobotParams
        The model file's robot (nominal or extended).
    fc : float
        Low-pass cut-off of torques and residual [Hz].
    mask : ndarray of bool, shape (N-1,), optional
        The samples (between samples) the metrics are computed on.

    Returns
    -------
    dict
        'frf_error_db', 'time_nrmse', 'per_axis' {name: {...}}, 'residual' (N-1, n)
        (measured minus predicted torque, low-passed) and 'rows' (N-1, n) (per axis the rows
        the metrics were taken over: in ``mask``, not bridged, moving).

    """
    rec, lost = bridge_gaps(rec)
    fs = rec.fs
    f, _, vh, _ = model_residual(rec, robot)
    N = rec.t.size
    if mask is None:
        mask = np.zeros(N - 1, bool)
        mask[int(EDGE * N):N - 1 - int(EDGE * N)] = True
    # per axis: only where it moves (at rest static friction holds any torque)
    use = (mask & ~(lost[1:] | lost[:-1]))[:, None] & moving(vh, rec.velocity, fs, fc)
    uf = lowpass(rec.effort[:-1], fs, fc)
    ff = lowpass(f, fs, fc)
    u_model = uf - ff
    per = {}
    err2, var2 = 0.0, 0.0
    for i, name in enumerate(robot.joint_names):
        m = use[:, i]
        e = ff[m, i]
        du = uf[m, i] - uf[m, i].mean() if m.any() else np.zeros(0)
        err2, var2 = err2 + float(e @ e), var2 + float(du @ du)
        per[name] = {'frf_error_db': round(_frf_error(rec.velocity[:-1][m][:, [i]],
                                                      uf[m][:, [i]], u_model[m][:, [i]],
                                                      fs), 4),
                     'time_nrmse': round(math.sqrt(float(e @ e) / max(float(du @ du), 1e-300)),
                                         5),
                     'moving_share': round(float(m.sum()) / max(int(mask.sum()), 1), 3)}
    rows = use.any(axis=1)
    return {'frf_error_db': round(_frf_error(rec.velocity[:-1][rows], uf[rows], u_model[rows],
                                             fs), 4),
            'time_nrmse': round(math.sqrt(err2 / max(var2, 1e-300)), 5),
            'per_axis': per, 'residual': ff, 'rows': use}


def _frf_error(v: np.ndarray, u_meas: np.ndarray, u_model: np.ndarray, fs: float) -> float:
    """Return the RMS dB difference of the Welch H1 estimates u_meas -> v and u_model -> v."""
    out = []
    nper = int(min(2 ** int(math.log2(max(v.shape[0] // 4, 64))), 4096))
    for i in range(v.shape[1]):
        fr, pm = signal.csd(u_meas[:, i], v[:, i], fs=fs, nperseg=nper)
        _, uu = signal.welch(u_meas[:, i], fs=fs, nperseg=nper)
        _, pmod = signal.csd(u_model[:, i], v[:, i], fs=fs, nperseg=nper)
        _, mm = signal.welch(u_model[:, i], fs=fs, nperseg=nper)
        _, coh = signal.coherence(u_meas[:, i], v[:, i], fs=fs, nperseg=nper)
        sel = (coh > 0.5) & (fr > 0) & (fr < 20)
        if sel.any():
            out.append(20 * np.log10(np.abs((pm[sel] / uu[sel]) / (pmod[sel] / mm[sel]))))
    v_ = np.concatenate(out) if out else np.array([np.nan])
    return float(np.sqrt(np.mean(v_ ** 2)))
