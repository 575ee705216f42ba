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
rule with weights, and the effect is kept only where the combined z exceeds HELD_OUT_GAIN_Z.
An effect shows in some terms, a torque ripple in the torque and velocity, not in the FRFs,
whose lines then only add noise to an equal-weight sum (weighting by precision instead favours
the terms a model change leaves alone, whose paired differences have no spread). Each term is
weighted by the z it would show were the effect true (:attr:`HeldOutGain.weights`): with the
model with the effect the truth, the paired difference per piece is s0^2 + 2 n s0 (s0 the
error of the model without it, n the noise), whose mean s0^2 is the misfit of the model
without the effect against the simulation with it, computed from the two simulations alone.
The weights do not depend on the noise of the part judged, so the weighted sum over its
standard deviation stays a standard normal under noise alone, and for that alternative it is
the most powerful combination. The same prediction combined gives the test's power
(:attr:`HeldOutGain.power`): a held-out part whose power is below HELD_OUT_GAIN_Z cannot
show the effect even were it true, and the held-out check does not judge it there.

Two things the plain rule got wrong, measured (docs/diagnosis/experiments.md, "Held-out gain
over noise"):

- Torque and velocity share their samples: in the closed loop their errors are one noise
  seen twice, and their paired differences per block correlate (0.8 on the nominal sensor
  scenes), so the sum of the four z had a variance of about 4 + 2 x 0.8, not 4. The sum is
  divided by the root of its variance under noise, sum(w^2) + 2 rho w_effort w_velocity
  (n + 2 rho with equal weights), with rho the correlation of the two terms' block
  differences measured on the record (negative estimates taken as 0).
- A term on which the model with the effect stays above UNEXPLAINED_RATIO noise floors held
  out is not at its noise: its residual is an error neither model explains (the UR5e scene's
  held-out chirp on a joint its dry friction holds: the true model at 84 floors), and the
  paired differences of such a residual measure how the effect shifts that error, with a
  sign of its own, not what the effect buys. Such a term may speak for the effect but not
  against it: its z counts only where positive. Where every term is at its floor (the
  nominal scenes the false-alarm rate is measured on) the rule is the plain one.

For an effect that buys nothing (every term's true gain <= 0) each term's z is at most a
standard normal by the central limit over its pieces, and so is the combination: the
probability of passing is at most the normal tail of HELD_OUT_GAIN_Z (0.13 % for 3). The
spread over blocks also holds how the gain of a real effect varies along the record, so a
real effect is judged conservatively; too conservatively where its gain sits in a few pieces.
A stiffening gear engages where the torque is high: pair scene 5828 of
benchmarks/diagnosis_uncertainty.py held out 2.85e5 noise floors without its gear and 2145
with it, and the spread of that gain over the blocks made it 2.9 standard errors, dropped.

So the gain is also judged against the largest standard error any noise could give it with
the misfits observed (:attr:`HeldOutGain.bound_z`). Per piece the paired difference of the
squared errors is (s0 + n)^2 - (s1 + n)^2 = s0^2 - s1^2 + 2 n (s0 - s1): the noise n enters
only through the cross term. With noise of variance v per piece (in floors, whatever v is)
and M0, M1 the terms' misfits (M = mean s^2 + v), its variance is at most 4 v mean (s0 -
s1)^2 <= 8 v (M0 + M1 - 2 v), which is largest at v = (M0 + M1) / 4: the standard error of
the mean over N pieces is at most (M0 + M1) / sqrt(N) (a complex FRF line's is half of it;
noise correlated within a time block but not across blocks keeps the bound). The bound's z,
(M0 - M1) sqrt(N) / (M0 + M1) per term, combined as the plain one, can only exceed 3 where
one model's misfit is several times the other's over many pieces (2.3x over 60 lines, 5x over
20 blocks); for two models at their noise it is about 0. The effect passes where either z
exceeds HELD_OUT_GAIN_Z: the false-alarm rate stays at the plain rule's (Monte Carlo in
test/core/diagnosis/test_noise_gain.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Any

from frf_ident.core.model.params import RobotParams
import numpy as np

from .evaluator import Evaluator, frf_estimates, replace_segments
from ..common import diag_ratio, rms_about_mean
from ..thresholds import (HELD_OUT_GAIN_BLOCK_S, HELD_OUT_GAIN_LAGS, HELD_OUT_GAIN_Z,
                          UNEXPLAINED_RATIO)

__all__ = ['correlation', 'held_out_gain', 'HeldOutGain', 'paired']


@dataclass(frozen=True)
class HeldOutGain:
    """An effect's held-out gain on its axis, per loss term, and its noise."""

    #: per loss term ('multisine', 'chirp', 'effort', 'velocity'): the gain [noise floors]
    #: and its standard error under noise alone
    terms: dict[str, tuple[float, float]]
    #: the pieces (FRF lines and time blocks) the terms were averaged over
    pieces: int
    #: the terms on which the model with the effect stays above UNEXPLAINED_RATIO noise floors
    #: held out: not at their noise, they count only for the effect
    unexplained: frozenset[str] = frozenset()
    #: correlation of the paired differences of terms that share their pieces (the torque
    #: and velocity blocks), by pair of terms; negative estimates are kept as 0
    correlation: dict[tuple[str, str], float] = field(default_factory=dict)
    #: per loss term: the misfit without and with the effect [noise floors] and the number of
    #: pieces, for :attr:`bound_z` (none: the bound is not judged)
    misfits: dict[str, tuple[float, float, int]] = field(default_factory=dict)
    #: judged on the held-out part (False: on the fit part, where the record has no held-out
    #: part or the acceptance rule asked for it)
    held_out: bool = True
    #: per loss term: the gain the part would show were the model with the effect the truth
    #: [noise floors]: the misfit of the model without it against the simulation with it
    #: (:attr:`power`; none: not computed)
    predicted: dict[str, float] = field(default_factory=dict)

    @property
    def gain(self) -> float:
        """Return the equal-weight mean over the terms: the held-out misfit difference."""
        return float(np.mean([g for g, _ in self.terms.values()]))

    @property
    def term_z(self) -> dict[str, float]:
        """Return per loss term its gain in its standard errors (terms without a spread: none)."""
        return {k: g / se for k, (g, se) in self.terms.items() if se > 0}

    @property
    def weights(self) -> dict[str, float]:
        """
        Return per loss term its weight in the combination: the z it would show, were it true.

        The predicted gain over the term's standard error (:attr:`predicted`); equal weights
        where nothing was predicted or every prediction is 0.
        """
        w = self._predicted_z()
        return w if any(x > 0 for x in w.values()) else {k: 1.0 for k in self.terms}

    def _predicted_z(self) -> dict[str, float]:
        """Return per loss term with a spread its predicted gain in its standard errors."""
        return {k: g / self.terms[k][1] for k, g in self.predicted.items()
                if self.terms.get(k, (0.0, 0.0))[1] > 0}

    @property
    def z(self) -> float:
        """
        Return the terms' z combined: their weighted sum over its standard deviation under noise.

        Stouffer's rule with weights and correlated terms: sum(w z) has the variance sum(w^2)
        + 2 sum(rho w_a w_b) under noise alone; an unexplained term's z counts only where
        positive. The weights (:attr:`weights`) are the z each term would show were the
        effect true, the most powerful combination for that alternative: a term the effect
        leaves alone adds its noise with weight 0.
        """
        return self._combined(self.term_z)

    @property
    def bound_z(self) -> float:
        """
        Return the gain over the largest standard error any noise gives it, terms combined.

        Per term (M0 - M1) sqrt(N) / (M0 + M1) (module docstring), combined as :attr:`z`;
        -inf without the terms' misfits.
        """
        return self._combined({k: (m0 - m1) * math.sqrt(n) / (m0 + m1)
                               for k, (m0, m1, n) in self.misfits.items() if m0 + m1 > 0})

    def _combined(self, term_z: dict[str, float]) -> float:
        """Return the weighted Stouffer combination of per-term z (unexplained: only for)."""
        zs = {k: max(z, 0.0) if k in self.unexplained else z for k, z in term_z.items()}
        w = self.weights
        var = sum(w.get(k, 0.0) ** 2 for k in zs) + 2.0 * sum(
            max(r, 0.0) * w.get(a, 0.0) * w.get(b, 0.0)
            for (a, b), r in self.correlation.items() if a in zs and b in zs)
        if var <= 0:
            return -math.inf
        return float(sum(w.get(k, 0.0) * z for k, z in zs.items()) / math.sqrt(var))

    @property
    def beyond_noise(self) -> bool:
        """Return whether the gain exceeds HELD_OUT_GAIN_Z standard errors by either z."""
        return max(self.z, self.bound_z) > HELD_OUT_GAIN_Z

    @property
    def power(self) -> float:
        """
        Return the z this part would give the effect were the model with it the truth.

        Per term the predicted gain (:attr:`predicted`: with the effect true, the paired
        difference per piece is s0^2 + 2 n s0, whose mean is the misfit s0^2 of the model
        without it against the simulation with it) over the term's standard error measured
        on the part, combined as :attr:`z`. Below HELD_OUT_GAIN_Z the part cannot show the
        effect (:attr:`can_show`); 0 where every prediction is 0 (the two models simulate
        alike), -inf where nothing was predicted.
        """
        if not self.predicted:
            return -math.inf
        z = self._predicted_z()
        return self._combined(z) if any(x > 0 for x in z.values()) else 0.0

    @property
    def can_show(self) -> bool:
        """Return whether the part could show the effect beyond noise, were it true."""
        return self.power > HELD_OUT_GAIN_Z

    @property
    def against(self) -> bool:
        """Return whether the part speaks against the effect: a z below -HELD_OUT_GAIN_Z."""
        return min([self.z] + ([self.bound_z] if self.misfits else [])) < -HELD_OUT_GAIN_Z

    def describe(self) -> str:
        """Return the numbers people read."""
        part = 'held-out' if self.held_out else 'fit-part'
        w = self.weights
        return (f'{part} gain {self.gain:.3g} noise floors, {self.z:.1f} standard errors of '
                f'noise alone over its terms (' + ', '.join(
                    f'{k} {z:.1f}' + (f' of {w.get(k, 0.0):.1f}' if self.predicted else '')
                    + (' unexplained: only for it' if k in self.unexplained else '')
                    for k, z in self.term_z.items())
                + ''.join(f'; {a}/{b} correlated {r:.2f}'
                          for (a, b), r in self.correlation.items())
                + (f'; {self.bound_z:.1f} of the most any noise gives these misfits'
                   if self.misfits else '')
                + (f'; {self.power:.1f} were it true, each term weighted by what it would '
                   'show' if self.predicted else '')
                + f'; kept above {HELD_OUT_GAIN_Z:g})')


def held_out_gain(ev: Evaluator, with_model: RobotParams, without_model: RobotParams,
                  axis: int, *, held_out: bool = True) -> HeldOutGain:
    """
    Return the held-out gain of ``with_model`` over ``without_model`` on ``axis``.

    ``held_out`` False: the same paired test on the fit part (the acceptance rule's second
    route for a drop smaller than the misfit's own spread, :func:`.acceptance.passes`).

    Parameters
    ----------
    ev : Evaluator
        The record's evaluator (its held-out part, noise floors and simulations).
    with_model, without_model : RobotParams
        The model with the effect and the model without it.
    axis : int
        The effect's axis.
    held_out : bool
        Judge the held-out part (where the record has one) or the fit part.

    Returns
    -------
    HeldOutGain
        Its mean is the difference of the two models' misfits on the axis and part
        (:meth:`Evaluator.misfit`).

    """
    sims = [ev.simulate(m) for m in (without_model, with_model)]
    held = held_out and bool(ev.meas_val)
    meas = ev.meas_val if held else ev.meas_fit
    floors = ev.floors_held if held else ev.floors
    terms: dict[str, tuple[float, float]] = {}
    misfits: dict[str, tuple[float, float, int]] = {}
    predicted: dict[str, float] = {}
    pieces = 0
    ests = [frf_estimates(replace_segments(sim, ev.val)) if held else ev.fit_estimates(m, sim)
            for m, sim in zip((without_model, with_model), sims)]
    for k, pm in meas.items():
        sq = [np.abs(np.log(diag_ratio(pm, est[k])[axis])) ** 2 / floors[k][axis]
              for est in ests]
        d = sq[0] - sq[1]
        terms[k] = paired(d)
        misfits[k] = (float(sq[0].mean()), float(sq[1].mean()), int(d.size))
        predicted[k] = float(np.mean(np.abs(np.log(diag_ratio(ests[1][k], ests[0][k])[axis]))
                                     ** 2 / floors[k][axis]))
        pieces += d.size
    mask = ev.val_mask if held and ev.val_mask.any() else ev.fit_mask
    block = max(int(round(HELD_OUT_GAIN_BLOCK_S * ev.rec.fs)), 1)
    blocks = {}
    for key in ('effort', 'velocity'):
        a = getattr(ev.rec, key)[:, axis]
        # in the units of the evaluator's terms: NRMSE^2 on the fit part's scale
        den2 = max(float(rms_about_mean(a[ev.fit_mask])) ** 2, 1e-300)
        e = [(a[mask] - getattr(sim, key)[:, axis][mask]) ** 2 / den2 / floors[key][axis]
             for sim in sims]
        d = e[0] - e[1]
        blocks[key] = np.array([x.mean() for x in np.array_split(d, max(d.size // block, 2))])
        terms[key] = (float(d.mean()), paired(blocks[key])[1])
        misfits[key] = (float(e[0].mean()), float(e[1].mean()), int(blocks[key].size))
        predicted[key] = float(np.mean((getattr(sims[0], key)[:, axis][mask]
                                        - getattr(sims[1], key)[:, axis][mask]) ** 2
                                       / den2 / floors[key][axis]))
        pieces += blocks[key].size
    with_terms = ev.terms(with_model, sims[1], held_out=held)
    unexplained = frozenset(k for k in terms if with_terms[k][axis] / own_floor(
        floors[k][axis], meas.get(k), axis) > UNEXPLAINED_RATIO)
    return HeldOutGain(terms, pieces, unexplained,
                       {('effort', 'velocity'): correlation(blocks['effort'],
                                                            blocks['velocity'])}, misfits,
                       held, predicted)


def paired(d: np.ndarray, lags: int = HELD_OUT_GAIN_LAGS) -> tuple[float, float]:
    """
    Return the mean of a series of paired differences and its standard error.

    The pieces in their order (FRF lines by frequency, time blocks by time) may correlate
    with their neighbours (a chirp's overlapping excerpts; closed-loop blocks whose means the
    integrator pulls back): their autocovariances up to ``lags`` enter with Bartlett's weights
    (Newey and West's estimate, never negative), divided by n - 1 - lags pieces where the
    plain spread divides by n - 1 (the demeaned autocovariances of independent pieces are
    each about -1/n of their variance: the same correction as ddof=1). ``lags`` 0 is the
    plain spread. The standard error is 0 for fewer than two pieces.

    >>> paired(np.array([1.0, 3.0]), lags=0)
    (2.0, 1.0)
    """
    if d.size < 2:
        return float(np.mean(d)) if d.size else 0.0, 0.0
    x = d - d.mean()
    n = x.size
    lags = min(lags, n - 2)
    var = float(x @ x) / n
    for k in range(1, lags + 1):
        var += 2.0 * (1.0 - k / (lags + 1.0)) * float(x[k:] @ x[:-k]) / n
    return float(np.mean(d)), math.sqrt(max(var, 0.0) / (n - 1 - lags))


def correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Return the correlation of two series of paired differences (0 without a spread)."""
    if a.size < 3 or np.std(a) == 0 or np.std(b) == 0:
        return 0.0
    return float(np.corrcoef(a, b)[0, 1])


def own_floor(floor: float, est: Any, axis: int) -> float:
    """
    Return the noise floor of a loss term on the part judged: the estimate's own, if it has one.

    The evaluator's FRF floor is the fit part's multisine noise, averaged over its
    realisations; the held-out realisation has its own (on the nominal sensor scenes the true
    model sits at 2.4 of the fit part's floors there, up to 7.5). An FRF estimate with a noise
    variance (a multisine of two periods or more) gives its own relative noise on the axis;
    a chirp has none, nor have the time signals (their floors are the record's noise): those
    keep ``floor``.
    """
    nv = getattr(est, 'noise_variance', None)
    if nv is None:
        return floor
    power = np.maximum(np.abs(est.response[axis, axis]) ** 2, 1e-300)
    own = float(np.mean(nv[axis, axis] / power))
    return own if np.isfinite(own) and own > 0 else floor
