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

:func:`search_left_modes` therefore tries, on every axis still UNEXPLAINED_RATIO floors above
its noise once the other effects are named and that holds no mode, a mode fitted by
simulation: its link-held frequency on a grid (MODE_SEARCH_STEP apart, from the axis' first
resonance to the highest measured line; MODE_SEARCH_DAMPING, MODE_SEARCH_SHARE of the link on
the spring), then Nelder-Mead on the log of frequency, damping ratio and inertia from the best
grid point (MODE_SEARCH_EVALUATIONS). The fit is offered as a ``second_mode`` only where it
explains its axis (the misfit left below UNEXPLAINED_RATIO floors: a mode posing for a missed
friction or ripple does not), and is judged as every candidate (:func:`.acceptance.accept`);
the held-out check judges it again. Its standard errors are those of the frequency-domain fit
of the multisine ratio started at its frequency where that fit lands within MODE_FREQUENCY_SE of
it, else not given.
"""
from __future__ import annotations

import math

from frf_ident.core.fit.link_mode import fit_second_mode
from frf_ident.core.model.params import RobotParams
from frf_ident.errors import ModelFileError
import numpy as np

from .acceptance import accept, passes, share_of_misfit
from .refit import rebuild
from .search import Search
from .simplex import nelder_mead
from ..common import Effect
from ..thresholds import (MODE_DAMPING_RANGE, MODE_FREQUENCY_SE, MODE_SEARCH_DAMPING,
                          MODE_SEARCH_EVALUATIONS, MODE_SEARCH_SHARE, MODE_SEARCH_STEP,
                          MODE_SEARCH_SIMPLEX, UNEXPLAINED_RATIO)

__all__ = ['search_left_modes']

KEYS = ('frequency_hz', 'damping_ratio', 'inertia')


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
        if (s.cur[i] <= UNEXPLAINED_RATIO * floor[i]
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


def _fit_by_simulation(s: Search, i: int, base: list[Effect]) -> Effect | None:
    """Return the mode that explains axis i by simulation on top of ``base`` (None: none)."""
    ev, name = s.ev, s.robot.axes[i].name
    limit = 0.95 * s.ext.axes[i].link_inertia

    def model(x: np.ndarray) -> RobotParams | None:
        m = mode_of(x, limit)
        trial = Effect('second_mode', name, 0.0, {'second_mode': m}, '', i)
        try:
            return rebuild(s.robot, base + [trial])
        except ModelFileError:
            return None

    def loss(x: np.ndarray) -> float:
        m = model(x)
        return math.inf if m is None else ev.loss(m, i)

    link = s.ext.axes[i].link_inertia
    grid = [np.log([f, MODE_SEARCH_DAMPING[0], share * link / f ** 2])
            for f in search_grid(s, i) for share in MODE_SEARCH_SHARE]
    ev.prefetch([m for m in (model(x) for x in grid) if m is not None])
    x0 = grid[int(np.argmin([loss(x) for x in grid]))]

    # within the grid's band and MODE_DAMPING_RANGE (a fit past them has found no mode)
    f = search_grid(s, i)
    bounds = [(math.log(f[0]), math.log(f[-1] * MODE_SEARCH_STEP)),
              tuple(math.log(z) for z in MODE_DAMPING_RANGE), (x0[2] - 5.0, x0[2] + 5.0)]

    def fit(x: np.ndarray) -> np.ndarray:
        simplex = np.vstack([x, x + np.diag(MODE_SEARCH_SIMPLEX)])
        ev.prefetch([m for m in (model(y) for y in simplex) if m is not None])
        return nelder_mead(loss, simplex, bounds=bounds, xatol=0.005, fatol=1e-3,
                           maxfev=MODE_SEARCH_EVALUATIONS,
                           prefetch=lambda xs: ev.prefetch([m for m in (model(y) for y in xs)
                                                            if m is not None]))
    # a light mode's narrow valley and a heavy one's broad one: one start in each
    ends = [fit(np.array([x0[0], math.log(z), x0[2]])) for z in MODE_SEARCH_DAMPING[1:]]
    best = min(ends, key=loss)
    left = loss(best)
    m = mode_of(best, limit)
    text = ', '.join(f'{k} {m[k]:.4g}' for k in KEYS)
    floor = ev.floor_seen(s.cur)[i]
    starts = ' and '.join(f'{z:g}' for z in MODE_SEARCH_DAMPING[1:])
    s.say(f'  {name}: second mode by simulation (grid best {math.exp(x0[0]):.3g} Hz, damping '
          f'ratio from {starts}): {text}, misfit {s.cur[i]:.4g} -> {left:.4g} (floor {floor:.3g})')
    lo, hi = MODE_DAMPING_RANGE
    if not left <= UNEXPLAINED_RATIO * floor or not lo <= m['damping_ratio'] <= hi:
        s.say(f'  {name}: not offered: it does not explain the axis')
        return None
    return Effect('second_mode', name, 0.0, {'second_mode': m},
                  f'{name} stays at {s.cur[i]:.3g} x its noise floor with the other effects '
                  f'named, and the multisine lines show no band a mode explains there: a '
                  f'link-side mode fitted by simulation of the records, {text} (misfit '
                  f'{s.cur[i]:.3g} -> {left:.3g} noise floors)', i,
                  standard_error={'second_mode': _frequency_domain_errors(s, i, m)})


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
