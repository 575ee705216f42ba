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
Write an axis' misfit as a sum of squares: the residual vector the simulation fits minimise.

:meth:`.evaluator.Evaluator.loss` of an axis is the mean over its loss terms of term / noise
floor: the log ratio of measured to simulated FRF on each line of the multisine and the chirp
estimate, the torque and velocity output errors on the samples of the fit part. Weighted by
their term's floor and count, these are one vector r with |r|^2 = the misfit
(:func:`axis_residual`). Its :class:`Layout` says which block and which experiment each entry
belongs to, for the block-robust standard errors of :mod:`.standard_errors`.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from frf_ident.core.model.params import RobotParams
import numpy as np

from .evaluator import Evaluator
from ..common import rms_about_mean, segment_mask
from ..selection import block_samples, correlation_time
from ..thresholds import SE_BLOCK_TAUS

__all__ = ['axis_residual', 'Layout', 'layout']

#: the time signals compared (evaluator terms besides the FRF estimates)
SIGNALS = ('effort', 'velocity')


@dataclass(frozen=True)
class Layout:
    """Which block and which experiment each entry of an axis' residual belongs to."""

    #: block of each entry: samples of one time block, or lines of one band of an estimate
    blocks: np.ndarray
    #: experiment of each entry: 'multisine' or 'chirp' (the estimate, or the segment of a
    #: sample)
    experiment: np.ndarray


def axis_residual(ev: Evaluator, robot: RobotParams, axis: int) -> np.ndarray:
    """
    Return the weighted residual of one axis of a model on the fit part.

    Parameters
    ----------
    ev : Evaluator
        The recording's evaluator.
    robot : RobotParams
        The model (simulated through the evaluator, so a prefetched simulation is used).
    axis : int
        The axis.

    Returns
    -------
    ndarray
        Real and imaginary part of ln(P_measured / P_model) of the axis' diagonal element on
        each line of each estimate, then measured minus simulated torque and velocity on the
        fit samples; each part weighted so that the sum of squares is :meth:`Evaluator.loss`.

    """
    sim = ev.simulate(robot)
    est = ev.fit_estimates(robot, sim)
    n_terms = len(ev.floors)
    parts = []
    for k, pm in ev.meas_fit.items():
        z = np.log(pm.response[axis, axis] / est[k].response[axis, axis])
        w = 1.0 / math.sqrt(n_terms * ev.floors[k][axis] * z.size)
        parts.append(w * np.column_stack([z.real, z.imag]).ravel())
    m = ev.fit_mask
    for k in SIGNALS:
        meas = getattr(ev.rec, k)[m, axis]
        w = 1.0 / math.sqrt(n_terms * ev.floors[k][axis] * meas.size)
        parts.append(w * (meas - getattr(sim, k)[m, axis]) / max(rms_about_mean(meas), 1e-300))
    return np.concatenate(parts)


def layout(ev: Evaluator, residual: np.ndarray) -> Layout:
    """
    Return the blocks and experiments of the entries of :func:`axis_residual`.

    A time block is BLOCK_S long, or SE_BLOCK_TAUS integrated correlation times of the
    residual where that is longer (as the time-series route's standard errors,
    :func:`..selection.block_standard_errors`); a band of an estimate is SE_BLOCK_TAUS
    correlation lengths of its residual over the lines. Both at most a third of their part,
    so that a misfit which drifts slowly over time or frequency is not taken for noise.

    Parameters
    ----------
    ev : Evaluator
        The recording's evaluator.
    residual : ndarray
        :func:`axis_residual` of the model the standard errors are taken at.

    Returns
    -------
    Layout

    """
    blocks, exps = [], []
    at, next_id = 0, 0
    for k, pm in ev.meas_fit.items():
        n = pm.freq_hz.size
        re = residual[at:at + 2 * n:2]
        at += 2 * n
        width = _block(re, np.ones(n, bool), 1, n)
        blocks.append(np.repeat(next_id + np.arange(n) // width, 2))
        exps.append(np.full(2 * n, k))
        next_id = int(blocks[-1].max()) + 1
    m = ev.fit_mask
    idx = np.flatnonzero(m)
    in_ms = segment_mask(ev.fit, ('multisine',))[m]
    width = block_samples(ev.rec.fs)
    for _ in SIGNALS:
        # the fit samples one after the other (the few lags across a gap between segments
        # do not move the correlation time): a transform of their length, not the record's
        width = max(width, _block(residual[at:at + idx.size], np.ones(idx.size, bool),
                                  block_samples(ev.rec.fs), idx.size))
        at += idx.size
    for _ in SIGNALS:
        blocks.append(next_id + idx // width)
        exps.append(np.where(in_ms, 'multisine', 'chirp'))
    return Layout(np.concatenate(blocks), np.concatenate(exps))


def _block(e: np.ndarray, rows: np.ndarray, least: int, n: int) -> int:
    """Return a block length: SE_BLOCK_TAUS correlation lengths, ``least`` to ``n`` / 3."""
    tau = correlation_time(e, rows)
    return int(max(least, min(math.ceil(SE_BLOCK_TAUS * tau), max(n // 3, 1))))
