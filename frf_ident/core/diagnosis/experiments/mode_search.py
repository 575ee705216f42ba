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
A second link-side mode the multisine lines do not show, fitted by simulation of the records.

Stage 0 (:mod:`.second_mode`) fits a mode where the multisine FRF's residual has a band. A
mode well above its axis' first resonance, behind a link that the spring already decouples
from the motor there, changes the motor-side FRF most at the axis' antiresonance, a few per
cent, which a rescale of the link's inertia and stiffness absorbs, and near its own frequency
by less than the lines' noise; a light one also falls between the lines. The linear fit's
residual is then white and no band asks for a mode (a 35.6 Hz mode of damping ratio 0.0057 and
18 % of joint_1's link: the lines see it at most 1.6 x their noise; scenes link_mode_beside
6588469, 6588470 and 6588475 of ``python -m benchmarks.second_mode 10 6587468``, every axis a
mode on joint_1 at 31-37 Hz). The closed-loop records see it: the chirp passes through its
resonance and the axis stays far above its noise floor with every other effect named (joint_1
of 6588470: 15.1 floors with the true time delay on joint_2, 0.88 with the true mode too).

:func:`search_left_modes` therefore tries, on every axis still UNEXPLAINED_RATIO floors above its
noise once the other effects are named and that holds no mode, a mode fitted by simulation against
the other axes' effects (what the axis took while the mode was missing may stand in for it, and is
offered again on top of the mode): its link-held frequency on a grid (MODE_SEARCH_STEP apart, from
the axis' first resonance to the highest measured line) times shares of the link on the spring
(MODE_SEARCH_SHARE), the band again MODE_SCAN_STEP apart at a light damping ratio (a light mode's
valley is as narrow as its half-power width), then Nelder-Mead on the log of frequency, damping
ratio and inertia over frequency squared from the scan's best point and from the grid's at a heavy
damping ratio (MODE_SEARCH_DAMPING). The fit is offered as a ``second_mode`` only where it explains
its axis (the misfit left below UNEXPLAINED_RATIO floors: a mode posing for a missed friction or
ripple does not) and where its frequency is determined: the mode refitted MODE_FREQUENCY_SE off
on either side loses to it by more than the noise gives (the paired test of :mod:`.noise_gain`
on the fit part, at the z of a profile likelihood ratio test at MODE_PROFILE_ALPHA,
PROFILE_Z); else the axis stays unexplained. Its damping ratio, which a light mode far above
the first resonance may leave free, is labelled not determined where the same test does not
exclude it moved by MODE_DAMPING_PROFILE either way. It
is judged as every candidate (:func:`.acceptance.passes`); the held-out check judges it again. Its
standard errors are those of the frequency-domain fit of the multisine ratio started at its
frequency where that fit lands within MODE_FREQUENCY_SE of it (wider than the records' fit: the
lines hardly see the mode), else not given.
"""
from __future__ import annotations

import math

from frf_ident.core.fit.link_mode import fit_second_mode
from frf_ident.core.model.params import RobotParams
from frf_ident.errors import ModelFileError
import numpy as np
from scipy import stats

from .acceptance import accept, passes, share_of_misfit
from .noise_gain import held_out_gain, HeldOutGain
from .refit import rebuild
from .rigid_axes import rigid_in_band
from .search import Search
from .simplex import nelder_mead
from ..common import Effect
from ..determination import not_determined
from ..mode_thresholds import (MODE_DAMPING_PROFILE, MODE_DAMPING_RANGE, MODE_FREQUENCY_SE,
                               MODE_PROFILE_ALPHA, MODE_SCAN_STEP, MODE_SEARCH_DAMPING,
                               MODE_SEARCH_EVALUATIONS, MODE_SEARCH_SHARE, MODE_SEARCH_SIMPLEX,
                               MODE_SEARCH_STEP)
from ..records import NotDetermined
from ..thresholds import UNEXPLAINED_RATIO

__all__ = ['search_left_modes']

KEYS = ('frequency_hz', 'damping_ratio', 'inertia')
#: the paired z a determined frequency wins by: a profile likelihood ratio of 4 z^2 beyond
#: chi-square(1) at MODE_PROFILE_ALPHA (mode_thresholds.py says why)
PROFILE_Z = math.sqrt(stats.chi2.isf(MODE_PROFILE_ALPHA, 1) / 4.0)


def first_resonance_hz(robot: RobotParams, i: int) -> float:
    """Return axis i's first (two-mass) resonance [Hz]: motor and link on the joint spring."""
    a = robot.axes[i]
    return math.sqrt(a.stiffness * (1 / a.motor_inertia + 1 / a.link_inertia)) / (2 * math.pi)


def search_grid(s: Search, i: int) -> np.ndarray:
    """Return the link-held frequencies [Hz] the search starts from on axis i."""
    top = max(float(np.max(e.freq_hz)) for e in s.ev.meas_fit.values())
    lo = first_resonance_hz(s.robot, i)
    n = max(int(math.floor(math.log(top / lo) / math.log(MODE_SEARCH_STEP))) + 1, 1)
    return lo * MODE_SEARCH_STEP ** np.arange(n)


def search_left_modes(s: Search) -> None:
    """
    Offer a mode fitted by simulation on every axis left clearly unexplained without one.

    The mode is fitted against the other axes' effects only: what the axis took while the mode
    was missing may stand in for it (joint_1 of scene 6588470 took a viscous friction of 15.9
    for the nominal 20 N m s/rad, and on top of it the fit ended at a damping ratio of 0.40, 1.55
    floors, the true mode 2.5). Taken in their place (:func:`.acceptance.passes`), the axis'
    own effects are offered again on top of it (:func:`.acceptance.accept`).
    """
    ev = s.ev
    floor = ev.floor_seen(s.cur)
    for i in range(s.robot.n_axes):
        # an axis the model holds rigid lacks its spring, not a mode (stage 0b, .rigid_axes)
        if (s.cur[i] <= UNEXPLAINED_RATIO * floor[i] or rigid_in_band(s.robot, i)
                or any(k.name == 'second_mode' and k.axis_index == i for k in s.kept)):
            continue
        others = [k for k in s.kept if k.axis_index != i]
        own = [k for k in s.kept if k.axis_index == i]
        c = _fit_by_simulation(s, i, others)
        if c is None:
            continue
        s.cands.append(c)
        ext = rebuild(s.robot, others + [c])
        cur = ev.misfit(ev.terms(ext))
        gain, c.gain = share_of_misfit(ev, s.cur, cur, i)
        s.say(f'  {c.axis} second_mode in place of its '
              f'{", ".join(k.name for k in own) or "nothing"}: misfit {s.cur[i]:.4g} -> '
              f'{cur[i]:.4g} (share {c.gain:.3f})')
        if not passes(ev, gain, c.gain):
            continue
        for k in own:
            k.gain = 0.0
        s.kept[:] = others + [c]
        s.ext, s.cur = ext, cur
        if own:
            s.ext, s.cur = accept(ev, s.robot, s.kept, own, s.cur, s.say)


class _Fit:
    """The simulation fit of a mode on axis ``i`` on top of ``base``: its models and losses."""

    def __init__(self, s: Search, i: int, base: list[Effect]) -> None:
        self.s, self.i, self.base = s, i, base
        self.limit = 0.95 * s.ext.axes[i].link_inertia
        self.bounds: list[tuple[float, float]] = []

    def model(self, x: np.ndarray) -> RobotParams | None:
        """Return the model with the mode of ``x`` (None: no model holds it)."""
        trial = Effect('second_mode', self.s.robot.axes[self.i].name, 0.0,
                       {'second_mode': mode_of(x, self.limit)}, '', self.i)
        try:
            return rebuild(self.s.robot, self.base + [trial])
        except ModelFileError:
            return None

    def prefetch(self, xs: list[np.ndarray]) -> None:
        """Simulate the models of ``xs`` at once in the evaluator's workers."""
        self.s.ev.prefetch([m for m in (self.model(x) for x in xs) if m is not None])

    def loss(self, x: np.ndarray) -> float:
        """Return the axis' misfit with the mode of ``x`` (noise floors)."""
        m = self.model(x)
        return math.inf if m is None else self.s.ev.loss(m, self.i)

    def fit(self, x: np.ndarray, free: tuple[int, ...] = (0, 1, 2)) -> np.ndarray:
        """Return the Nelder-Mead fit from ``x`` of the coordinates ``free`` (the rest held)."""
        idx = list(free)

        def full(y: np.ndarray) -> np.ndarray:
            z = np.array(x, dtype=float)
            z[idx] = y
            return z
        y0 = np.asarray(x, dtype=float)[idx]
        simplex = np.vstack([y0, y0 + np.diag(np.asarray(MODE_SEARCH_SIMPLEX)[idx])])
        self.prefetch([full(y) for y in simplex])
        y = nelder_mead(lambda y: self.loss(full(y)), simplex,
                        bounds=[self.bounds[k] for k in idx], xatol=0.005, fatol=1e-3,
                        maxfev=MODE_SEARCH_EVALUATIONS,
                        prefetch=lambda ys: self.prefetch([full(v) for v in ys]))
        return full(y)


def _fit_by_simulation(s: Search, i: int, base: list[Effect]) -> Effect | None:
    """Return the mode that explains axis i by simulation on top of ``base`` (None: none)."""
    ev, name, fit = s.ev, s.robot.axes[i].name, _Fit(s, i, base)
    link = s.ext.axes[i].link_inertia
    f = search_grid(s, i)
    grid = [np.log([g, MODE_SEARCH_DAMPING[0], share * link / g ** 2])
            for g in f for share in MODE_SEARCH_SHARE]
    fit.prefetch(grid)
    x0 = grid[int(np.argmin([fit.loss(x) for x in grid]))]
    # within the grid's band and MODE_DAMPING_RANGE (a fit past them has found no mode)
    fit.bounds = [(math.log(f[0]), math.log(f[-1] * MODE_SEARCH_STEP)),
                  (math.log(MODE_DAMPING_RANGE[0]), math.log(MODE_DAMPING_RANGE[1])),
                  (x0[2] - 5.0, x0[2] + 5.0)]
    # a light mode's valley is as narrow as its half-power width: scanned at MODE_SCAN_STEP with
    # the grid's inertia / frequency^2; a heavy one's broad valley from the grid's best point
    hi = f[-1] * MODE_SEARCH_STEP
    scan = [np.array([math.log(g), math.log(MODE_SEARCH_DAMPING[1]), x0[2]])
            for g in f[0] * MODE_SCAN_STEP ** np.arange(
                int(math.log(hi / f[0]) / math.log(MODE_SCAN_STEP)) + 1)]
    fit.prefetch(scan)
    x1 = scan[int(np.argmin([fit.loss(x) for x in scan]))]
    heavy = np.array([x0[0], math.log(MODE_SEARCH_DAMPING[2]), x0[2]])
    best = min((fit.fit(x1), fit.fit(heavy)), key=fit.loss)
    left = fit.loss(best)
    m = mode_of(best, fit.limit)
    text = ', '.join(f'{k} {m[k]:.4g}' for k in KEYS)
    floor = ev.floor_seen(s.cur)[i]
    s.say(f'  {name}: second mode by simulation (grid best {math.exp(x0[0]):.3g} Hz, scan best '
          f'{math.exp(x1[0]):.3g} Hz): {text}, misfit {s.cur[i]:.4g} -> {left:.4g} (floor '
          f'{floor:.3g})')
    if not left <= UNEXPLAINED_RATIO * floor:
        s.say(f'  {name}: not offered: it does not explain the axis')
        return None
    z, side = _frequency_profile(fit, best)
    seen = (f'refitted {100 * MODE_FREQUENCY_SE:g} % off, it wins by {z:.2f} standard errors, '
            f'needed {PROFILE_Z:.2f}: ' + (side.describe() if side else
                                           'no model holds it there'))
    if not z > PROFILE_Z:
        s.say(f'  {name}: not offered: its frequency is not determined ({seen})')
        return None
    s.say(f'  {name}: its frequency is determined ({seen})')
    labels = _damping_label(fit, best, m['damping_ratio'])
    if labels:
        s.say(f'  {name}: its damping ratio is not determined ({labels[0].reason})')
    return Effect('second_mode', name, 0.0, {'second_mode': m},
                  f'{name} stays at {s.cur[i]:.3g} x its noise floor with the other effects '
                  f'named, and the multisine lines show no band a mode explains there: a '
                  f'link-side mode fitted by simulation of the records, {text} (misfit '
                  f'{s.cur[i]:.3g} -> {left:.3g} noise floors; refitted '
                  f'{100 * MODE_FREQUENCY_SE:g} % off its frequency it loses by {z:.2f} '
                  f'standard errors of the noise, '
                  f'needed {PROFILE_Z:.2f}; standard errors of the multisine fit started there, '
                  f"wider than the records' fit)", i,
                  standard_error={'second_mode': _frequency_domain_errors(s, i, m)},
                  not_determined=labels)


def _frequency_profile(fit: _Fit, best: np.ndarray) -> tuple[float, HeldOutGain | None]:
    """
    Return what ``best`` wins by over its refit MODE_FREQUENCY_SE off, the closer side.

    With that side's paired gain (-inf and None: no model holds the mode on either side). The
    damping ratio and inertia are refitted at each side: a heavy mode's frequency trades
    with them along a valley the records may not close (scene link_mode_beside 6588469 of
    ``python -m benchmarks.second_mode 10 6587468``: its mode of 37.4 Hz, damping ratio 0.070
    and 20.5 kg m^2 on joint_1 and one of 48.3 Hz, 0.035 and 35.4 kg m^2 leave 0.55 floors
    both). The gain is judged against the noise by the paired test of :mod:`.noise_gain` on
    the fit part, the acceptance rule's: the misfit's own spread (:meth:`.Evaluator.misfit_sd`)
    takes its terms' samples as independent, and on scene link_mode 4173340 (41.0 Hz, damping
    ratio 0.047 on joint_1) a light mode at 51.6 Hz fitted 0.022 floors below the truth, 21 on
    that scale's chi-square, while the paired test put it 2.4 standard errors behind the truth
    and 0.1 behind its refit 5 % off (the larger of z and bound_z).
    """
    # the low-frequency change (inertia / frequency^2) kept at the first step; a side no
    # model holds tells nothing
    sides = [w for w in (_wins_over(fit, best, 0, 1.0 + sign * MODE_FREQUENCY_SE, (1, 2))
                         for sign in (-1.0, 1.0)) if w[1] is not None]
    return min(sides, key=lambda t: t[0], default=(-math.inf, None))


def _damping_label(fit: _Fit, best: np.ndarray, zeta: float) -> list[NotDetermined]:
    """
    Return the label of a damping ratio the records leave free (empty: it is determined).

    The damping ratio is moved by MODE_DAMPING_PROFILE each way, the frequency and the inertia
    refitted, and judged as :func:`_frequency_profile` judges the frequency (the larger of
    the paired test's z and its bound, PROFILE_Z). It is determined where both sides are
    excluded; else each side not excluded is moved on by the same factor until it is (or
    leaves MODE_DAMPING_RANGE), and the label's range runs between the first excluded values:
    the values the records do not exclude lie within it.
    """
    ends, said = [], []
    for factor in (1.0 / MODE_DAMPING_PROFILE, MODE_DAMPING_PROFILE):
        k, wins = 1, _wins_over(fit, best, 1, factor, (0, 2))[0]
        if wins > PROFILE_Z:
            ends.append(zeta * factor)
            continue
        said.append(f'{factor:g} x (wins by {wins:.2f})')
        while not wins > PROFILE_Z:
            k += 1
            if not MODE_DAMPING_RANGE[0] <= zeta * factor ** k <= MODE_DAMPING_RANGE[1]:
                break
            wins = _wins_over(fit, best, 1, factor ** k, (0, 2))[0]
        ends.append(min(max(zeta * factor ** k, MODE_DAMPING_RANGE[0]), MODE_DAMPING_RANGE[1]))
    if not said:
        return []
    return [not_determined(
        'second_mode damping_ratio', zeta, 0.0,
        'moved ' + ' and '.join(said) + f', frequency and inertia refitted, it fits the '
        f'records within {PROFILE_Z:.2f} standard errors of their paired test; they exclude '
        f'{ends[0]:.3g} and {ends[1]:.3g}', ends)]


def _wins_over(fit: _Fit, best: np.ndarray, coordinate: int, factor: float,
               free: tuple[int, ...]) -> tuple[float, HeldOutGain | None]:
    """
    Return what ``best`` wins by over itself with one coordinate times ``factor``.

    The coordinates ``free`` refitted; what it wins by is the larger of the paired test's z
    and its bound on the fit part (inf, with no gain, where no model holds the mode there).
    """
    x = np.array(best, dtype=float)
    x[coordinate] += math.log(factor)
    off = fit.model(fit.fit(x, free=free))
    if off is None:
        return math.inf, None
    g = held_out_gain(fit.s.ev, fit.model(best), off, fit.i, held_out=False)
    return max(g.z, g.bound_z), g


def mode_of(x: np.ndarray, limit: float) -> dict[str, float]:
    """
    Return the mode of ``x``: the log of its frequency, damping ratio and inertia / frequency^2.

    Below its frequency a mode changes the axis' FRF by about its inertia over its frequency
    squared (the spring's compliance times the inertia it carries): that term is searched, so
    that a step of the frequency leaves the low-frequency change alone. The inertia is capped at
    ``limit``.
    """
    f, z, compliance = (float(np.exp(v)) for v in x)
    m = {'frequency_hz': f, 'damping_ratio': z, 'inertia': min(compliance * f ** 2, limit)}
    return m


def _frequency_domain_errors(s: Search, i: int, m: dict[str, float]
                             ) -> dict[str, float] | None:
    """
    Return the multisine fit's standard errors of a mode near ``m`` (None: no such fit).

    The frequency-domain fit of stage 0's ratio started at the mode's frequency; its errors
    stand for the mode's only where it lands within MODE_FREQUENCY_SE of it.
    """
    st = s.structure
    if st is None:
        return None
    fit = fit_second_mode(s.robot, st.data, i, m['frequency_hz'], st.linear)
    if fit is None or abs(fit.frequency_hz / m['frequency_hz'] - 1) > MODE_FREQUENCY_SE:
        return None
    return fit.second_mode_std()
