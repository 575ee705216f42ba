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
What an encoder's quantisation error, repeating with the multisine's period, adds to the floors.

:func:`add_quantisation_floor` measures it by simulating the nominal model with and without
the encoder in the loop and raises an :class:`.evaluator.Evaluator`'s FRF floors by it.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

from frf_ident.core.model.params import RobotParams
import numpy as np

from .evaluator import frf_estimates, replace_segments
from .floors import period_noise
from ..common import simulate_like

__all__ = ['add_quantisation_floor']


def add_quantisation_floor(ev: Any, robot: RobotParams) -> dict[str, np.ndarray] | None:
    """
    Raise an evaluator's FRF floors by what the record's encoder quantisation puts on them.

    The floors come from the spread between the multisine's periods, and an encoder's
    quantisation error repeats with the period where the motion does (to within what the
    noise dithers): no noise to that floor, yet no simulation reproduces it (scene 13191138
    of the sensor sweep: the true model's multisine term at 3.80 floors on an axis with
    9.2e-6 rad steps, 0.45 with 1e-9). Its share is measured, not modelled: ``robot``
    simulated with the record's velocity noise (the periods' spread, :func:`period_noise`,
    which dithers the encoder as in the record), with and without its
    ``encoder_resolution`` in the loop, the same noise in both; each against the record, the
    quantised one's terms exceed the other's by the quantisation's share (clipped at 0). The
    FRF terms only: their estimates average the periods, where the repeating part survives;
    the torque and velocity terms are sample by sample, where the period spread already holds
    the quantisation (13191138's true model: 1.00 / 0.88 / 1.06 floors on both, its
    multisine term 2.77 / 3.80 / 1.88, with this 1.31 / 1.75 / 0.95). Our plant only.

    Parameters
    ----------
    ev : Evaluator
        The evaluator; its ``floors`` and ``floors_held`` are raised in place.
    robot : RobotParams
        The nominal model with the sensor the record shows (``encoder_resolution``).

    Returns
    -------
    dict or None
        Per FRF term the added floor (fit part); None where nothing was added (another
        simulator, or no axis with an encoder grid).

    """
    if ev.simulator is not simulate_like or not any(a.encoder_resolution for a in robot.axes):
        return None
    nv = np.sqrt(np.nan_to_num(period_noise(ev.rec, ~ev.missing)[0]))
    noisy = replace(robot, axes=[replace(a, velocity_noise=float(s))
                                 for a, s in zip(robot.axes, nv)])
    sims = [simulate_like(ev.rec, noisy, ev.ctrl, reference=ev.drive, keep=keep)
            for keep in (('velocity_noise',), ('velocity_noise', 'encoder_resolution'))]
    ev.n_sims += 2
    added = {}
    for held, floors in ((False, ev.floors), (True, ev.floors_held)):
        if held and not ev.val.segments:
            continue
        part = ev.val if held else ev.fit
        base, extra = (ev.terms_of(x, frf_estimates(replace_segments(x, part)), held)
                       for x in sims)
        for k in ev.meas_fit:
            if k in floors and k in extra:
                d = np.maximum(extra[k] - base[k], 0.0)
                floors[k] = floors[k] + d
                if not held:
                    added[k] = d
    return added
