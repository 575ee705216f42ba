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
  each notch alone); a low-pass below the lowest band at each of LOWPASS_RATIOS;
- gains: kp = 1 / |P_0 F| at KP_POINTS crossovers log-spaced over the measured band (a P
  controller crossing there on the nominal pose), ki = kp r 2 pi f_c for every r in KI_RATIOS.

Every candidate's loop L_k = C P_k is checked on the measured lines of every pose k
(:func:`frf_ident.core.loop.frd_margins.frd_margins`) and, with a weight, for robust
stability max |W T_0| < 1 on the nominal pose. A target's slack is margin / target (gain
margin in dB, 1 / max |W T_0| for the robust test); a candidate is feasible when its smallest
slack over targets and poses is >= 1. Chosen: with a crossover target the feasible candidate
whose worst-pose bandwidth (its lowest gain crossing) is nearest to it (in log), else the
feasible one with the highest worst-pose bandwidth; ties go to the most integral action
ki / kp, then to the larger slack. Without a feasible candidate the one with
the largest smallest slack is the best achievable, and :class:`Limit` names the target that
binds, where and by how much.
"""
from __future__ import annotations

from dataclasses import dataclass
import itertools

from frf_ident.core.loop.check import pi_response
from frf_ident.core.loop.frd_margins import frd_margins, FrdMargins
from frf_ident.core.loop.modes import ResonanceBand
from frf_ident.core.loop.notch import (Biquad, design_lowpass, design_notch, MAX_CENTRE_SHARE,
                                       NOTCH_WIDTHS)
from frf_ident.core.loop.targets import TuneTargets
import numpy as np

__all__ = ['AxisSetting', 'KI_RATIOS', 'KP_POINTS', 'LOWPASS_RATIOS', 'Limit',
           'MAX_COMBINATIONS', 'ShapingResult', 'TARGET_NAMES', 'filter_sets', 'shape_axis']

#: crossovers the proportional gain grid places over the measured band
KP_POINTS = 32
#: integral corners w_i / w_c of the PI candidates (0.5 costs 27 deg at w_c; no P-only
#: controller: the integral holds gravity and friction)
KI_RATIOS = (0.05, 0.1, 0.2, 0.35, 0.5)
#: low-pass candidates: corner = the lowest resonance band's low edge / ratio
LOWPASS_RATIOS = (1.5, 3.0)
#: most notch combinations over the bands before one common depth is used for all
MAX_COMBINATIONS = 64
#: the targets in the order of the slack columns
TARGET_NAMES = ('phase_margin_deg', 'gain_margin_db', 'modulus_margin', 'robust', 'stability')
#: the fields of FrdMargins, in order
_FIELDS = ('gain_margin_db', 'phase_margin_deg', 'crossover_hz', 'modulus_margin',
           'peak_frequency_hz', 'bandwidth_hz', 'encirclements', 'stable', 'in_band')
#: a crossover within this share of the target counts as reaching it
CROSSOVER_TOLERANCE = 0.05


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
        One of TARGET_NAMES, or ``'crossover_hz'``.
    pose : int
        Index of the pose where it binds.
    value, wanted : float
        The margin reached and the target.
    frequency_hz : float
        Where it binds: the crossover (phase margin, crossover), the sensitivity peak (modulus
        margin, robust test) or the nominal crossover (gain margin).

    """

    target: str
    pose: int
    value: float
    wanted: float
    frequency_hz: float


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
        sets += [(design_lowpass(low / r, sample_rate),) for r in LOWPASS_RATIOS]
    return sets


def _gain_grid(freq_hz: np.ndarray, nominal: np.ndarray, filt: np.ndarray,
               target: float | None) -> tuple[np.ndarray, np.ndarray]:
    """kp (n_kp, 1) and ki (n_kp, n_ratio) of the candidates."""
    f = freq_hz
    lo, hi = f[0] * 1.05, f[-1] / 1.05
    fc = np.geomspace(lo, hi, KP_POINTS)
    if target is not None and lo < target < hi:
        fc = np.unique(np.r_[fc, target * np.geomspace(0.8, 1.25, 9)])
    mag = np.exp(np.interp(np.log(fc), np.log(f), np.log(np.abs(nominal * filt))))
    kp = (1.0 / mag)[:, None]
    ki = kp * np.asarray(KI_RATIOS)[None, :] * 2 * np.pi * fc[:, None]
    return np.broadcast_to(kp, ki.shape), ki


def _slack(m: FrdMargins, robust: np.ndarray, targets: TuneTargets) -> np.ndarray:
    """
    Slack of every target, shape (..., n_poses, 5): margin / target, >= 1 when met.

    The robust column (1 / max |W T_0|) repeats per pose; the stability column is 1 for a
    loop Nyquist's criterion finds stable on a band that holds its crossover, else 0 (a
    margin of an unstable loop, or of one that crosses outside the band, means nothing).
    """
    pm = np.where(np.isfinite(m.phase_margin_deg), m.phase_margin_deg, -np.inf)
    with np.errstate(divide='ignore'):
        rob = (1.0 / robust)[..., None] if targets.robust else np.full(robust.shape + (1,),
                                                                         np.inf)
    cols = [pm / targets.phase_margin_deg, m.gain_margin_db / targets.gain_margin_db,
            m.modulus_margin / targets.modulus_margin, np.broadcast_to(rob, pm.shape),
            (m.stable & m.in_band).astype(float)]
    return np.stack(cols, axis=-1)


def _limit(m: FrdMargins, slack: np.ndarray, robust: float, targets: TuneTargets,
           nominal: int) -> Limit:
    """The binding target of one candidate (slack shape (n_poses, 4))."""
    pose, col = np.unravel_index(int(np.argmin(slack)), slack.shape)
    name = TARGET_NAMES[col]
    if name == 'robust':
        return Limit(name, nominal, float(robust), 1.0, float(m.peak_frequency_hz[nominal]))
    if name == 'stability':
        return Limit(name, int(pose), float(m.encirclements[pose]), 0.0,
                     float(m.peak_frequency_hz[pose]))
    value = {'phase_margin_deg': m.phase_margin_deg, 'gain_margin_db': m.gain_margin_db,
             'modulus_margin': m.modulus_margin}[name][pose]
    where = m.peak_frequency_hz[pose] if name == 'modulus_margin' else m.crossover_hz[pose]
    return Limit(name, int(pose), float(value), float(getattr(targets, name)), float(where))


def shape_axis(axis: str, freq_hz: np.ndarray, responses: np.ndarray, nominal: int,
               bands: list[ResonanceBand], dt: float, targets: TuneTargets,
               weight: np.ndarray | None = None,
               sets: list[tuple[Biquad, ...]] | None = None) -> ShapingResult:
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

    Returns
    -------
    ShapingResult
        The chosen setting (or the best achievable), its margins per pose and what binds.

    """
    f = np.asarray(freq_hz, dtype=float)
    p = np.asarray(responses, dtype=complex)
    sets = filter_sets(bands, 1.0 / dt) if sets is None else sets
    w = np.zeros(f.size) if weight is None else np.asarray(weight, dtype=float)
    z = np.exp(2j * np.pi * f * dt)
    integ = dt * z / (z - 1)
    rows = []
    for j, fs in enumerate(sets):
        filt = AxisSetting(axis, 0.0, 0.0, fs).filter_response(f)
        kp, ki = _gain_grid(f, p[nominal], filt, targets.crossover_hz)
        c = (kp[..., None] + ki[..., None] * integ) * filt           # (n_kp, n_r, F)
        loops = c[:, :, None, :] * p[None, None]                     # (n_kp, n_r, K, F)
        m = frd_margins(loops, f)
        l0 = loops[:, :, nominal]
        robust = np.max(np.abs(w * l0 / (1 + l0)), axis=-1) if weight is not None \
            else np.zeros(kp.shape)
        rows.append((j, kp.ravel(), ki.ravel(), m, robust.ravel(),
                     _slack(m, robust, targets).reshape(kp.size, p.shape[0], 5)))
    return _choose(axis, rows, sets, targets, nominal, weight is not None)


def _choose(axis, rows, sets, targets: TuneTargets, nominal: int, weighted: bool
            ) -> ShapingResult:
    """Pick the candidate of the module doc among all evaluated ones."""
    js = np.concatenate([np.full(r[1].size, r[0]) for r in rows])
    kp = np.concatenate([r[1] for r in rows])
    ki = np.concatenate([r[2] for r in rows])
    idx = np.concatenate([np.arange(r[1].size) for r in rows])
    slack = np.concatenate([r[5] for r in rows])                     # (N, K, 4)
    least = slack.min(axis=(1, 2))
    wc = np.concatenate([r[3].bandwidth_hz.reshape(r[1].size, -1) for r in rows])
    wc_worst = np.where(np.isfinite(wc).all(axis=1), np.nanmin(np.where(np.isfinite(wc), wc,
                                                                          np.inf), axis=1), 0.0)
    feasible = (least >= 1.0) & (wc_worst > 0)
    t = targets.crossover_hz
    if feasible.any():
        score = -np.abs(np.log(np.maximum(wc_worst, 1e-300) / t)) if t is not None \
            else np.log(np.maximum(wc_worst, 1e-300))
        score = np.where(feasible, score, -np.inf)
        top = np.flatnonzero(score >= score.max() - 1e-9)
        ratio = ki[top] / kp[top]
        top = top[ratio >= ratio.max() * (1 - 1e-9)]       # most integral action, then slack
        pick = int(top[np.argmax(least[top])])
    else:
        pick = int(np.argmax(least))
    j, k = int(js[pick]), int(idx[pick])
    m = rows[[r[0] for r in rows].index(j)][3]
    mp = FrdMargins(*(np.asarray(getattr(m, a)).reshape(-1, slack.shape[1])[k]
                      for a in _FIELDS))
    robust = float(np.concatenate([r[4] for r in rows])[pick]) if weighted else float('nan')
    limit = None
    if not feasible[pick]:
        limit = _limit(mp, slack[pick], robust, targets, nominal)
    elif t is not None and wc_worst[pick] < (1 - CROSSOVER_TOLERANCE) * t:
        reach = wc_worst >= (1 - CROSSOVER_TOLERANCE) * t
        if reach.any():
            q = int(np.flatnonzero(reach)[np.argmax(least[reach])])
            jq, kq = int(js[q]), int(idx[q])
            mq = rows[[r[0] for r in rows].index(jq)][3]
            mq = FrdMargins(*(np.asarray(getattr(mq, a)).reshape(-1, slack.shape[1])[kq]
                              for a in _FIELDS))
            limit = _limit(mq, slack[q], float(np.concatenate([r[4] for r in rows])[q]),
                           targets, nominal)
        else:
            limit = Limit('crossover_hz', nominal, float(wc_worst[pick]), float(t), float(t))
    setting = AxisSetting(axis, float(kp[pick]), float(ki[pick]), tuple(sets[j]))
    return ShapingResult(setting, bool(feasible[pick]), mp, robust, limit, int(kp.size))
