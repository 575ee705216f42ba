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
Whether the time-series diagnosis can judge a record at all (length, efforts, motion).

Refused with one line: a record shorter than the blocks the fit and the held-out check need,
an axis whose effort never changes (a wrong column), a record in which no axis moves above its
velocity noise.
"""
from __future__ import annotations

import math

from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError
import numpy as np

from ..residual import lowpass
from ..selection import block_samples
from ..thresholds import BLOCK_S, FC_HZ, HOLD_EVERY, STILL_NOISE

__all__ = ['check_diagnosable']


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
    need = HOLD_EVERY * block_samples(rec.fs)
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
