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
Test whether an effect's held-out gain exceeds what the noise alone gives (issue 55 item 2).

The held-out check (:func:`.held_out.held_out_check`) compares an axis' held-out misfit with
and without an effect: the misfit is a mean over the loss terms of the axis (held-out
multisine and chirp FRF misfit, torque and velocity NRMSE^2, each over its noise floor), and
each term is itself a mean over pieces the noise makes independent: the lines of an FRF
estimate, blocks of HELD_OUT_GAIN_BLOCK_S of the time signals. The two models are judged on
the same measured data, so each term's gain is a paired difference: per piece the difference
of the two squared errors, whose spread over the pieces gives the term's standard error
under noise alone. The terms' gains in their standard errors are combined by Stouffer's
rule (their sum over the root of their number: an effect shows in some terms, a torque ripple
in the torque and velocity, not in the FRFs, whose lines then only add noise to an
equal-weight mean; weighting by precision instead favours the terms a model change leaves
alone, whose paired differences have no spread), and the effect is kept only where the
combined z exceeds HELD_OUT_GAIN_Z. For an effect that buys nothing (every term's true gain
<= 0) each term's z is at most a standard normal by the central limit over its pieces, and
so is the combination: the probability of passing is at most the normal tail of
HELD_OUT_GAIN_Z (0.13 % for 3) where the terms are independent. The spread over blocks also
holds how the gain of a real effect varies along the record, so a real effect is judged
conservatively. The rate measured on nominal scenes with realistic sensors is in
docs/diagnosis/experiments.md ("Held-out gain over noise").
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from frf_ident.core.model.params import RobotParams
import numpy as np

from .evaluator import Evaluator, frf_estimates, replace_segments
from ..common import diag_ratio, rms_about_mean
from ..thresholds import HELD_OUT_GAIN_BLOCK_S, HELD_OUT_GAIN_Z

__all__ = ['held_out_gain', 'HeldOutGain', 'paired']


@dataclass(frozen=True)
class HeldOutGain:
    """An effect's held-out gain on its axis, per loss term, and its noise."""

    #: per loss term ('multisine', 'chirp', 'effort', 'velocity'): the gain [noise floors]
    #: and its standard error under noise alone
    terms: dict[str, tuple[float, float]]
    #: the pieces (FRF lines and time blocks) the terms were averaged over
    pieces: int

    @property
    def gain(self) -> float:
        """Return the equal-weight mean over the terms: the held-out misfit difference."""
        return float(np.mean([g for g, _ in self.terms.values()]))

    @property
    def term_z(self) -> dict[str, float]:
        """Return per loss term its gain in its standard errors (terms without a spread: none)."""
        return {k: g / se for k, (g, se) in self.terms.items() if se > 0}

    @property
    def z(self) -> float:
        """Return the terms' z combined (Stouffer: their sum over the root of their count)."""
        zs = list(self.term_z.values())
        return float(sum(zs) / math.sqrt(len(zs))) if zs else -math.inf

    @property
    def beyond_noise(self) -> bool:
        """Return whether the weighted gain exceeds HELD_OUT_GAIN_Z standard errors."""
        return self.z > HELD_OUT_GAIN_Z

    def describe(self) -> str:
        """Return the numbers people read."""
        return (f'held-out gain {self.gain:.3g} noise floors, {self.z:.1f} standard errors of '
                f'noise alone over its terms (' + ', '.join(
                    f'{k} {z:.1f}' for k, z in self.term_z.items())
                + f'; kept above {HELD_OUT_GAIN_Z:g})')


def held_out_gain(ev: Evaluator, with_model: RobotParams, without_model: RobotParams,
                  axis: int) -> HeldOutGain:
    """
    Return the held-out gain of ``with_model`` over ``without_model`` on ``axis``.

    Parameters
    ----------
    ev : Evaluator
        The record's evaluator (its held-out part, noise floors and simulations).
    with_model, without_model : RobotParams
        The model with the effect and the model without it.
    axis : int
        The effect's axis.

    Returns
    -------
    HeldOutGain
        Its mean is the difference of the two models' held-out misfits on the axis
        (:meth:`Evaluator.misfit`).

    """
    sims = [ev.simulate(m) for m in (without_model, with_model)]
    held = bool(ev.meas_val)
    meas = ev.meas_val if held else ev.meas_fit
    terms: dict[str, tuple[float, float]] = {}
    pieces = 0
    for k, pm in meas.items():
        sq = []
        for m, sim in zip((without_model, with_model), sims):
            est = (frf_estimates(replace_segments(sim, ev.val)) if held
                   else ev.fit_estimates(m, sim))
            sq.append(np.abs(np.log(diag_ratio(pm, est[k])[axis])) ** 2)
        d = (sq[0] - sq[1]) / ev.floors[k][axis]
        terms[k] = paired(d)
        pieces += d.size
    mask = ev.val_mask if held and ev.val_mask.any() else ev.fit_mask
    block = max(int(round(HELD_OUT_GAIN_BLOCK_S * ev.rec.fs)), 1)
    for key in ('effort', 'velocity'):
        a = getattr(ev.rec, key)[:, axis][mask]
        den2 = max(float(rms_about_mean(a)) ** 2, 1e-300)
        e = [(a - getattr(sim, key)[:, axis][mask]) ** 2 for sim in sims]
        d = (e[0] - e[1]) / den2 / ev.floors[key][axis]
        b = np.array([x.mean() for x in np.array_split(d, max(d.size // block, 2))])
        terms[key] = (float(d.mean()), paired(b)[1])
        pieces += b.size
    return HeldOutGain(terms, pieces)


def paired(d: np.ndarray) -> tuple[float, float]:
    """Return the mean of paired differences and its standard error (0 for one piece)."""
    if d.size < 2:
        return float(np.mean(d)) if d.size else 0.0, 0.0
    return float(np.mean(d)), float(np.std(d, ddof=1)) / math.sqrt(d.size)
