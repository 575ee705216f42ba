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
Loop shaping of one axis on its measured FRFs: PI gains and filters, worst case over poses.

The controller is C = PI(z) F(z): the discrete PI kp + ki dt z / (z - 1) the simulation runs
and the product F of the biquads on the measured velocity (:mod:`frf_ident.core.loop.notch`).
Candidates (:func:`filter_sets` x a gain grid):

- filters: none; per resonance band a notch of each width in NOTCH_WIDTHS (every
  combination over the bands, or, beyond MAX_COMBINATIONS, the same width for all bands and
  each notch alone); each of these again with a low-pass below the lowest band at each of
  LOWPASS_RATIOS (a resonance that moves too far for a notch to follow is lowered by both);
- gains: kp = 1 / |P_0| at KP_POINTS crossovers log-spaced over the measured band (a P
  controller without filters crossing there on the nominal pose: filters lower the crossover,
  they never buy a gain the plant alone would not take), ki = kp r 2 pi f_c for every r in
  KI_RATIOS; once a first choice is made, a finer grid around it (REFINE_KP x REFINE_KI)
  with its filters.

Every candidate's loop L_0 = C P_0 is checked on the measured lines of the nominal pose
(:func:`frf_ident.core.loop.frd_margins.frd_margins`) and, with a weight, for robust
stability max |W T_0| < 1; those that meet every target there (no other can meet them at
every pose), or the best ones when none does, go on to the other poses, L_k = C P_k, the
farthest from the nominal first, dropping at each the candidates that miss a target as long
as others meet them all (:mod:`frf_ident.core.loop.candidates`). A target's slack is
margin / target (gain margin in dB, 1 / max |W T_0| for the robust test, 1 or 0 for
Nyquist's stability on a band that holds the crossover); a candidate
is feasible when its smallest slack over targets and poses is >= 1. Chosen: with a crossover
target the feasible candidate whose worst-pose bandwidth (its lowest gain crossing) is
nearest to it (in log), else the feasible one with the highest worst-pose bandwidth; among
those within CROSSOVER_TOLERANCE of that bandwidth the most integral action ki / kp wins,
then the larger slack. An ``accept`` callback (the margins as reported) may reject a choice:
the next is taken. Without a feasible candidate the best achievable is the one whose margins
and stability come nearest to their targets (then the robust test), and :class:`Limit` names
the target that binds, where and by how much.
"""
from __future__ import annotations

from dataclasses import dataclass
import itertools
from typing import Callable

from frf_ident.core.loop.candidates import (Candidates, CROSSOVER_TOLERANCE, Evaluation,
                                            ROBUST, TARGET_NAMES)
from frf_ident.core.loop.check import pi_response
from frf_ident.core.loop.frd_margins import FrdMargins
from frf_ident.core.loop.modes import ResonanceBand
from frf_ident.core.loop.notch import (Biquad, design_lowpass, design_notch, MAX_CENTRE_SHARE,
                                       NOTCH_WIDTHS)
from frf_ident.core.loop.targets import TuneTargets
import numpy as np

__all__ = ['AxisSetting', 'KI_RATIOS', 'KP_POINTS', 'LOWPASS_RATIOS', 'Limit',
           'MAX_ACCEPT_TRIES', 'MAX_COMBINATIONS', 'REFINE_KI', 'REFINE_KP', 'ShapingResult',
           'filter_sets', 'shape_axis']

#: crossovers the proportional gain grid places over the measured band
KP_POINTS = 24
#: integral corners w_i / w_c of the PI candidates (0.5 costs 27 deg at w_c; no P-only
#: controller: the integral holds gravity and friction)
KI_RATIOS = (0.05, 0.1, 0.2, 0.35, 0.5)
#: low-pass candidates: corner = the lowest resonance band's low edge / ratio
LOWPASS_RATIOS = (1.5, 3.0)
#: most notch combinations over the bands before one common depth is used for all
MAX_COMBINATIONS = 64
#: the finer grid around the first choice: kp factors and factors of its ki / kp
REFINE_KP = tuple(np.geomspace(0.8, 1.25, 11))
REFINE_KI = (0.5, 0.7, 1.0, 1.4, 2.0)
#: feasible choices an ``accept`` callback may reject before the last one is kept
MAX_ACCEPT_TRIES = 25


@dataclass(frozen=True)
class AxisSetting:
    """
    One axis's controller: the PI and the filters on its measured velocity.

    Attributes
    ----------
    axis : str
        The joint.
    kp, ki : float
        PI gains [N m s/rad], [N m/rad].
    filters : tuple of Biquad
        Sections in the order they run.

    """

    axis: str
    kp: float
    ki: float
    filters: tuple[Biquad, ...] = ()

    def filter_response(self, freq_hz: np.ndarray) -> np.ndarray:
        """Return the product of the discrete filters' responses (1 without filters)."""
        out = np.ones(np.shape(freq_hz), dtype=complex)
        for b in self.filters:
            out = out * b.response(freq_hz)
        return out

    def response(self, freq_hz: np.ndarray, dt: float) -> np.ndarray:
        """Return C = PI(z) F(z) at ``freq_hz`` for the sample time ``dt``."""
        return pi_response(freq_hz, self.kp, self.ki, dt) * self.filter_response(freq_hz)

    def sos(self) -> np.ndarray:
        """Return the filters as an (n_sections, 6) array (0 rows without filters)."""
        return np.array([b.sos for b in self.filters]).reshape(-1, 6)

    def summary(self) -> str:
        """Return one line for people."""
        f = '; '.join(b.summary() for b in self.filters) or 'no filter'
        return f'{self.axis}: kp {self.kp:.4g} N m s/rad, ki {self.ki:.4g} N m/rad, {f}'


@dataclass(frozen=True)
class Limit:
    """
    The target that binds a setting: which, at which pose and line, and by how much.

    Attributes
    ----------
    target : str
        One of TARGET_NAMES, ``'crossover_hz'``, ``'band'``: the crossover lies outside the
        measured band (``value`` -20 log10 |L| at the highest line [dB]), or ``'judge'``: the
        ``accept`` callback rejected the MAX_ACCEPT_TRIES best choices (``value`` their
        number).
    pose : int
        Index of the pose where it binds.
    value, wanted : float
        The margin reached and the target.
    frequency_hz : float
        Where it binds: the gain crossover (phase margin), the phase crossover (gain margin),
        the sensitivity peak (modulus margin, robust test, stability) or the crossover asked.
    because : Limit or None
        For the crossover: what the best setting reaching it misses (None: no candidate
        reaches it).

    """

    target: str
    pose: int
    value: float
    wanted: float
    frequency_hz: float
    because: 'Limit | None' = None


@dataclass(frozen=True)
class ShapingResult:
    """
    The chosen setting of one axis and how it does at every pose.

    Attributes
    ----------
    setting : AxisSetting
        The chosen PI and filters.
    feasible : bool
        Every margin target met at every pose (on the measured lines).
    margins : FrdMargins
        Its margins, one entry per pose.
    robust_peak : float
        max |W T_0| on the lines (NaN without a weight).
    limit : Limit or None
        What binds: the missed target when not feasible; the target that keeps the crossover
        below the one asked for; None when everything asked for is met.
    searched : int
        Candidates checked.

    """

    setting: AxisSetting
    feasible: bool
    margins: FrdMargins
    robust_peak: float
    limit: Limit | None
    searched: int

    @property
    def worst_bandwidth_hz(self) -> float:
        """Return the lowest bandwidth (first crossing) over the poses [Hz]."""
        bw = self.margins.bandwidth_hz
        return float(np.nanmin(bw)) if np.isfinite(bw).any() else float('nan')


def filter_sets(bands: list[ResonanceBand], sample_rate: float) -> list[tuple[Biquad, ...]]:
    """
    Return the filter candidates for the resonance bands (module doc).

    Parameters
    ----------
    bands : list of ResonanceBand
        The resonances to filter.
    sample_rate : float
        Controller rate [Hz]; bands at or above MAX_CENTRE_SHARE of it get no filter.

    Returns
    -------
    list of tuple of Biquad
        The first is the empty set (no filter).

    """
    ok = [b for b in bands if b.high_hz < MAX_CENTRE_SHARE * sample_rate]
    notches = []
    for b in ok:
        widths = []
        for z in NOTCH_WIDTHS:
            try:
                widths.append(design_notch(b.low_hz, b.high_hz, b.damping, z, sample_rate))
            except ValueError:        # too shallow for this band: not worth its phase
                continue
        notches.append(widths)
    notches = [n for n in notches if n]
    sets: list[tuple[Biquad, ...]] = [()]
    if np.prod([len(n) + 1 for n in notches]) <= MAX_COMBINATIONS:
        for combo in itertools.product(*[[None] + n for n in notches]):
            if any(c is not None for c in combo):
                sets.append(tuple(c for c in combo if c is not None))
    else:
        common = min(len(n) for n in notches)
        sets += [tuple(n[-common + j] for n in notches) for j in range(common)]
        sets += [(x,) for n in notches for x in n]
    if ok:
        low = min(b.low_hz for b in ok)
        lows = [design_lowpass(low / r, sample_rate) for r in LOWPASS_RATIOS]
        sets += [s + (lp,) for lp in lows for s in sets]
    return sets


def _gain_grid(freq_hz: np.ndarray, nominal: np.ndarray, target: float | None
               ) -> tuple[np.ndarray, np.ndarray]:
    """Return kp and ki of the candidates, both (n_kp, n_ratio)."""
    f = freq_hz
    lo, hi = f[0] * 1.05, f[-1] / 1.05
    fc = np.geomspace(lo, hi, KP_POINTS)
    if target is not None and lo < target < hi:
        fc = np.unique(np.r_[fc, target * np.geomspace(0.8, 1.25, 9)])
    # from the plant alone: a filter that attenuates at fc does not buy a larger gain
    mag = np.exp(np.interp(np.log(fc), np.log(f), np.log(np.abs(nominal))))
    kp = (1.0 / mag)[:, None]
    ki = kp * np.asarray(KI_RATIOS)[None, :] * 2 * np.pi * fc[:, None]
    return np.broadcast_to(kp, ki.shape), ki


def _limit(m: FrdMargins, slack: np.ndarray, robust: float, targets: TuneTargets,
           nominal: int) -> Limit:
    """Return the binding target of one candidate (m per pose, slack (n_poses, 5))."""
    pose, col = np.unravel_index(int(np.argmin(slack)), slack.shape)
    stab = TARGET_NAMES.index('stability')
    if slack[:, stab].min() <= slack[pose, col]:       # an unjudged loop's margins mean nothing
        pose, col = int(np.argmin(slack[:, stab])), stab
    name = TARGET_NAMES[col]
    if name == 'stability' and not m.in_band[pose]:
        return Limit('band', int(pose), float(m.top_db[pose]), 0.0, float('nan'))
    if name == 'robust':
        return Limit(name, nominal, float(robust), 1.0, float(m.peak_frequency_hz[nominal]))
    if name == 'stability':
        return Limit(name, int(pose), float(m.encirclements[pose]), 0.0,
                     float(m.peak_frequency_hz[pose]))
    top = bool(m.top_db[pose] < m.gain_margin_db[pose])
    value = {'phase_margin_deg': m.phase_margin_deg, 'modulus_margin': m.modulus_margin,
             'gain_margin_db': m.top_db if top else m.gain_margin_db}[name][pose]
    where = {'phase_margin_deg': m.crossover_hz, 'modulus_margin': m.peak_frequency_hz,
             'gain_margin_db': np.full(m.top_db.shape, np.inf) if top
             else m.phase_crossover_hz}[name][pose]
    return Limit(name, int(pose), float(value), float(getattr(targets, name)), float(where))


def shape_axis(axis: str, freq_hz: np.ndarray, responses: np.ndarray, nominal: int,
               bands: list[ResonanceBand], dt: float, targets: TuneTargets,
               weight: np.ndarray | None = None,
               sets: list[tuple[Biquad, ...]] | None = None,
               accept: Callable[[AxisSetting], bool] | None = None) -> ShapingResult:
    """
    Choose the PI and filters of one axis on its measured FRFs (module doc).

    Parameters
    ----------
    axis : str
        The joint.
    freq_hz : ndarray, shape (n_freq,)
        The lines [Hz].
    responses : ndarray of complex, shape (n_poses, n_freq)
        P_ii of the axis at every pose.
    nominal : int
        Index of the nominal pose (the gain grid and the robust test use it).
    bands : list of ResonanceBand
        The resonances to filter.
    dt : float
        Controller sample time [s].
    targets : TuneTargets
        What to meet.
    weight : ndarray, shape (n_freq,), optional
        |W| at the lines (the robust test; None: skipped, NaN peak).
    sets : list of tuple of Biquad, optional
        Filter candidates; default :func:`filter_sets` of ``bands``.
    accept : callable, optional
        The final judge of a feasible choice, e.g. the reported margins (python-control
        interpolates between the lines, which this search does not): a choice it rejects is
        dropped and the next one taken, at most MAX_ACCEPT_TRIES times.

    Returns
    -------
    ShapingResult
        The chosen setting (or the best achievable), its margins per pose and what binds.

    """
    f = np.asarray(freq_hz, dtype=float)
    p = np.asarray(responses, dtype=complex)
    sets = filter_sets(bands, 1.0 / dt) if sets is None else sets
    weight = None if weight is None else np.asarray(weight, dtype=float)
    z = np.exp(2j * np.pi * f * dt)
    integ = dt * z / (z - 1)
    filts = [AxisSetting(axis, 0.0, 0.0, fs).filter_response(f) for fs in sets]
    lows = [min([b.frequency_hz for b in fs], default=np.inf) for fs in sets]
    js, kps, kis = [], [], []
    for j in range(len(sets)):
        kp, ki = _gain_grid(f, p[nominal], targets.crossover_hz)
        js.append(np.full(kp.size, j))
        kps.append(kp.ravel())
        kis.append(ki.ravel())
    js, kps, kis = np.concatenate(js), np.concatenate(kps), np.concatenate(kis)
    ev = Evaluation(f, p, nominal, integ, filts, np.array(lows), weight, targets)
    cand = ev.candidates(js, kps, kis, screened=True)
    searched = kps.size
    q, feasible, _ = _choose(cand, targets, nominal, np.zeros(cand.kp.size, dtype=bool))
    # refine around the choice: its filters, a finer grid of gains
    rj, rkp, rki = _refinement(cand.sets[q], cand.kp[q], cand.ki[q])
    cand = cand.join(ev.candidates(rj, rkp, rki, screened=False))
    searched += rkp.size
    rejected = np.zeros(cand.kp.size, dtype=bool)
    for tries in range(MAX_ACCEPT_TRIES):
        q, feasible, limit = _choose(cand, targets, nominal, rejected)
        setting = AxisSetting(axis, float(cand.kp[q]), float(cand.ki[q]),
                              tuple(sets[cand.sets[q]]))
        if not feasible or accept is None or accept(setting):
            break
        rejected[q] = True
    else:       # every feasible choice tried was rejected: keep the last, say so
        feasible = False
        limit = Limit('judge', nominal, float(MAX_ACCEPT_TRIES), 0.0, float('nan'))
    return ShapingResult(setting, feasible, cand.at(q), float(cand.robust[q]), limit,
                         int(searched))


def _refinement(j: int, kp: float, ki: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the finer grid of gains around one candidate: REFINE_KP x REFINE_KI."""
    g = kp * np.asarray(REFINE_KP)[:, None] * np.ones(len(REFINE_KI))
    r = ki / kp * np.asarray(REFINE_KI)[None, :] * np.ones((len(REFINE_KP), 1))
    return np.full(g.size, j), g.ravel(), (g * r).ravel()


def _choose(cand: Candidates, targets: TuneTargets, nominal: int, rejected: np.ndarray
            ) -> tuple[int, bool, Limit | None]:
    """Return the candidate of the module doc, its feasibility and what binds."""
    least = np.where(rejected, -np.inf, cand.slack.min(axis=(1, 2)))
    bw = cand.margins.bandwidth_hz
    worst = np.where(np.isfinite(bw).all(axis=1), np.min(np.where(np.isfinite(bw), bw, np.inf),
                                                         axis=1), 0.0)
    feasible = (least >= 1.0) & (worst > 0)
    t = targets.crossover_hz
    if not feasible.any():
        # best achievable: the margins and stability first (met counts as met), then the
        # robust test, so a hopeless robust target does not give up the margins
        margin = np.minimum(np.delete(cand.slack, ROBUST, axis=2).min(axis=(1, 2)), 1.0)
        margin = np.where(rejected, -np.inf, margin)
        q = int(np.lexsort((least, margin))[-1])
        return q, False, _limit(cand.at(q), cand.slack[q], float(cand.robust[q]), targets,
                                nominal)
    with np.errstate(divide='ignore'):
        score = -np.abs(np.log(worst / t)) if t is not None else np.log(worst)
    score = np.where(feasible, score, -np.inf)
    top = np.flatnonzero(score >= score.max() - np.log1p(CROSSOVER_TOLERANCE))
    ratio = cand.ki[top] / cand.kp[top]
    top = top[ratio >= ratio.max() * (1 - 1e-9)]          # most integral action, then slack
    q = int(top[np.argmax(least[top])])
    limit = None
    if t is not None and worst[q] < (1 - CROSSOVER_TOLERANCE) * t:
        reach = np.flatnonzero(worst >= (1 - CROSSOVER_TOLERANCE) * t)
        because = None
        if reach.size:
            r = int(reach[np.argmax(least[reach])])
            because = _limit(cand.at(r), cand.slack[r], float(cand.robust[r]), targets, nominal)
        limit = Limit('crossover_hz', int(np.argmin(cand.margins.bandwidth_hz[q])),
                      float(worst[q]), float(t), float(t), because)
    return q, True, limit
