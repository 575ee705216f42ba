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
Prepare a time-series record for the per-axis stages: residual, blocks, masks, load runs.

:func:`prepare` checks that the record can be diagnosed, bridges its gaps, takes the nominal
model's inverse-dynamics residual, splits fit and held-out blocks and finds the joints whose
angle carries a configuration-dependent load; :class:`Prepared` holds it for the stages.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
import numpy as np

from .diagnosable import check_diagnosable
from ..common import bridge_gaps
from ..regressors import (axis_masks, gravity_bearing, gravity_sets, model_residual, moving,
                          one_way_sets)
from ..selection import split_blocks

__all__ = ['prepare', 'Prepared']


@dataclass
class Prepared:
    """The record's residual, masks and gravity structure, shared by the per-axis stages."""

    rec: Recording          # gap-bridged
    fc: float
    f: np.ndarray           # residual of the nominal model, (N-1, n)
    qh: np.ndarray
    vh: np.ndarray
    ah: np.ndarray
    fit_m: np.ndarray       # fit rows (blocks), (N-1,)
    val_m: np.ndarray       # held-out rows
    prep: list              # per axis :func:`..regressors.axis_masks`
    skips: list             # per axis the joint sets that move one way only
    bearing: list           # runs of joints whose angle carries a load
    #: the URDF's inertia and Coriolis torque, and its gravity, at the record's motion (each
    #: (N-1, n)); None without a URDF
    urdf_torque: tuple[np.ndarray, np.ndarray] | None = None


def prepare(rec: Recording, robot: RobotParams, fc: float, say: Callable[[str], None], *,
            all_rows: bool = False) -> Prepared:
    """
    Check the record, bridge its gaps, take the residual, the blocks and the load runs.

    ``all_rows``: fit on every row no gap bridged, the held-out blocks and the ends too (the
    held-out rows stay the blocks', their metrics then in sample).
    """
    check_diagnosable(rec, robot.joint_names)
    rec, lost = bridge_gaps(rec)
    fs = rec.fs
    N = rec.t.size
    f, qh, vh, ah = model_residual(rec, robot)
    fit_m, val_m = split_blocks(N - 1, fs, fc)
    # rows bridged over gaps of the record take part in neither fit nor validation
    kept = ~(lost[1:] | lost[:-1])
    fit_m, val_m = (kept if all_rows else fit_m & kept), val_m & kept
    names = robot.joint_names
    move = moving(vh, rec.velocity, fs, fc)
    check_diagnosable(rec, names, move & fit_m[:, None], move & val_m[:, None])
    prep = [axis_masks(rec, f, move, i, fit_m, val_m, fc) for i in range(robot.n_axes)]
    skips = [one_way_sets(qh, vh, gravity_sets(robot.n_axes, i), prep[i][1], fs, fc)
             for i in range(robot.n_axes)]
    bearing = gravity_bearing(qh, vh, ah, fs, fc, prep, skips)
    say(f'axes whose own angle carries a configuration-dependent load (runs of parallel '
        f'joints): {[[names[i] for i in run] for run in bearing] or "none"}')
    urdf = None if robot.urdf is None else (robot.urdf.inertia(qh, vh, ah),
                                            robot.urdf.gravity(qh))
    return Prepared(rec, fc, f, qh, vh, ah, fit_m, val_m, prep, skips, bearing, urdf)
