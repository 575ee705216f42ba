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
The loop shaping's candidates: their margins at every pose, their slack, which survive.

A candidate is PI gains with a filter set (:mod:`frf_ident.core.loop.shaping`). Its slack
per target is margin / target (>= 1: met); :class:`Evaluation` computes the margins of many
candidates at the nominal pose, screens them (:func:`screen`) and follows the survivors over
the other poses (:meth:`Evaluation.eliminate`); :class:`Candidates` holds the result.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.loop.frd_margins import frd_margins, FrdMargins
from frf_ident.core.loop.targets import TuneTargets
import numpy as np

__all__ = ['CROSSOVER_TOLERANCE', 'Candidates', 'Evaluation', 'FIELDS', 'FILTER_CLEARANCE',
           'ROBUST', 'SCREEN_KEEP', 'TARGET_NAMES', 'screen', 'slack']

#: the targets in the order of the slack columns
TARGET_NAMES = ('phase_margin_deg', 'gain_margin_db', 'modulus_margin', 'robust', 'stability')

#: column of the robust test in the slack
ROBUST = TARGET_NAMES.index('robust')

#: the fields of FrdMargins, in order
FIELDS = ('gain_margin_db', 'phase_margin_deg', 'crossover_hz', 'modulus_margin',
          'peak_frequency_hz', 'bandwidth_hz', 'phase_crossover_hz', 'encirclements', 'stable',
          'in_band', 'top_db')

#: a filter sits at least this factor above the loop's bandwidth: below it a notch or a
#: low-pass turns the loop conditionally stable (stable only while its gain stays high: it
#: loses stability when the torque saturates), the pathology of a search for the highest
#: crossover that puts a low-pass under it
FILTER_CLEARANCE = 2.0

#: candidates checked at every pose when none meets the targets at the nominal pose
SCREEN_KEEP = 256

#: a crossover within this share of the target counts as reaching it
CROSSOVER_TOLERANCE = 0.05


def slack(m: FrdMargins, robust: np.ndarray, targets: TuneTargets, lowest: np.ndarray
          ) -> np.ndarray:
    """
    Slack of every target, shape (..., n_poses, 5): margin / target, >= 1 when met.

    The gain margin counts no more than the loop's attenuation at the highest line (beyond
    the band its phase is unknown). The robust column (1 / max |W T_0|) repeats per pose; the
    stability column is 1 for a
    loop Nyquist's criterion finds stable on a band that holds its crossover, with its lowest
    filter (``lowest`` [Hz], per candidate) FILTER_CLEARANCE times above its bandwidth, else 0
    (a margin of an unstable loop, or of one that crosses outside the band, means nothing).
    """
    pm = np.where(np.isfinite(m.phase_margin_deg), m.phase_margin_deg, 0.0)   # no crossing
    with np.errstate(divide='ignore'):
        rob = (1.0 / robust)[..., None] if targets.robust else \
            np.full(robust.shape + (1,), np.inf)
    gm = np.minimum(m.gain_margin_db, m.top_db)       # the phase beyond the band is unknown
    cols = [pm / targets.phase_margin_deg, gm / targets.gain_margin_db,
            m.modulus_margin / targets.modulus_margin, np.broadcast_to(rob, pm.shape),
            (m.stable & m.in_band & (lowest[:, None] >= FILTER_CLEARANCE
                                     * np.nan_to_num(m.bandwidth_hz, nan=np.inf))
             ).astype(float)]
    return np.stack(cols, axis=-1)


@dataclass
class Candidates:
    """Every evaluated candidate, flattened: filter set, gains, margins per pose, slack."""

    sets: list[int]
    kp: np.ndarray
    ki: np.ndarray
    margins: FrdMargins          # fields shaped (n, n_poses)
    robust: np.ndarray           # (n,)
    slack: np.ndarray            # (n, n_poses, 5)

    def at(self, q: int) -> FrdMargins:
        """Return candidate q's margins per pose."""
        return FrdMargins(*(getattr(self.margins, a)[q] for a in FIELDS))

    def join(self, other: 'Candidates') -> 'Candidates':
        """Return both sets of candidates in one."""
        return Candidates(self.sets + other.sets, np.r_[self.kp, other.kp],
                          np.r_[self.ki, other.ki],
                          FrdMargins(*(np.concatenate([getattr(self.margins, a),
                                                       getattr(other.margins, a)])
                                       for a in FIELDS)),
                          np.r_[self.robust, other.robust],
                          np.concatenate([self.slack, other.slack]))


@dataclass
class Evaluation:
    """What every candidate's loops need: the lines, plants, filters and targets."""

    f: np.ndarray
    p: np.ndarray
    nominal: int
    integ: np.ndarray
    filts: list[np.ndarray]
    lows: np.ndarray
    weight: np.ndarray | None
    targets: TuneTargets

    def candidates(self, js: np.ndarray, kps: np.ndarray, kis: np.ndarray, screened: bool
                   ) -> 'Candidates':
        """Return the candidates' margins at every pose (screened at the nominal first)."""
        c = (kps[:, None] + kis[:, None] * self.integ) * np.stack([self.filts[j] for j in js])
        lowest = self.lows[js]
        w = np.zeros(self.f.size) if self.weight is None else self.weight
        l0 = c * self.p[self.nominal]
        m0 = frd_margins(l0, self.f)
        robust = np.max(np.abs(w * l0 / (1 + l0)), axis=-1)
        rob = robust if self.weight is not None else np.zeros_like(robust)
        keep = np.arange(kps.size)
        if screened:
            slack0 = slack(FrdMargins(*(getattr(m0, a)[:, None] for a in FIELDS)), rob,
                           self.targets, lowest)
            keep = screen(slack0, m0.bandwidth_hz, self.targets.crossover_hz)
            keep = self.eliminate(c, keep, rob, lowest, slack0)
        if self.p.shape[0] == 1:
            m = FrdMargins(*(getattr(m0, a)[keep, None] for a in FIELDS))
        else:
            m = frd_margins(c[keep][:, None, :] * self.p[None], self.f)
        return Candidates(js[keep].tolist(), kps[keep], kis[keep], m,
                          robust[keep] if self.weight is not None else
                          np.full(keep.size, np.nan),
                          slack(m, rob[keep], self.targets, lowest[keep]))

    def eliminate(self, c: np.ndarray, keep: np.ndarray, rob: np.ndarray, lowest: np.ndarray,
                  slack0: np.ndarray) -> np.ndarray:
        """
        Return the candidates left after checking the other poses one by one.

        Farthest poses from the nominal first; after each, the candidates that missed a target
        there are dropped while some meet every target so far (only those can be chosen).
        When none does, the SCREEN_KEEP best so far stay (the best achievable is among them)
        and are checked at the rest. Those reaching an asked crossover stay throughout (what
        binds there is reported).
        """
        k0 = self.nominal
        others = [k for k in np.argsort(-np.median(np.abs(self.p - self.p[k0])
                                                   / np.abs(self.p[k0]), axis=-1))
                  if k != k0]
        least = slack0.min(axis=(1, 2))
        protect = np.zeros(c.shape[0], dtype=bool)
        if self.targets.crossover_hz is not None:
            reach = np.flatnonzero(
                np.nan_to_num(frd_margins(c[keep] * self.p[k0], self.f).bandwidth_hz)
                >= (1 - CROSSOVER_TOLERANCE) * self.targets.crossover_hz)
            protect[keep[reach[:SCREEN_KEEP]]] = True
        alive, pruning = keep, True
        for k in others:
            m = frd_margins(c[alive] * self.p[k], self.f)
            s = slack(FrdMargins(*(getattr(m, a)[:, None] for a in FIELDS)), rob[alive],
                      self.targets, lowest[alive]).min(axis=(1, 2))
            least[alive] = np.minimum(least[alive], s)
            if not pruning:
                continue
            ok = (s >= 1.0) & (least[alive] >= 1.0)
            if ok.any():
                alive = alive[ok | protect[alive]]
            else:
                alive = alive[np.argsort(-least[alive])[:SCREEN_KEEP]]
                pruning = False
        return np.unique(np.r_[alive, keep[protect[keep]]])


def screen(slack0: np.ndarray, bandwidth0: np.ndarray, crossover: float | None
           ) -> np.ndarray:
    """
    Return the indices of the candidates worth checking at every pose.

    Those that meet every target at the nominal pose (no other can be feasible); the
    SCREEN_KEEP best there in the order of the best achievable (margins and stability first,
    then the robust test) when none does; and with a crossover asked, the SCREEN_KEEP best of
    those that reach it (what binds there is reported).
    """
    least = slack0.min(axis=(1, 2))
    margin = np.minimum(np.delete(slack0, ROBUST, axis=2).min(axis=(1, 2)), 1.0)
    order = np.lexsort((least, margin))[::-1]
    ok = np.flatnonzero(least >= 1.0)
    keep = [ok if ok.size else order[:SCREEN_KEEP]]
    if crossover is not None:
        reach = (1 - CROSSOVER_TOLERANCE) * crossover <= np.nan_to_num(bandwidth0)
        keep.append(order[reach[order]][:SCREEN_KEEP])
    return np.unique(np.concatenate(keep))
