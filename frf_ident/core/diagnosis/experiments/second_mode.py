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
A second link-side mode where the frequency-domain fit's residual shows missing structure.

A share of a link's inertia on a spring behind it (a tool, a cable carrier, a second gear
stage; docs/model_file.md ``second_mode``) adds a resonance the two-mass joint lacks. Fitted
as a change of the linear parameters alone, it is sold as a heavier link: right at low
frequency, wrong where a notch or a bandwidth is chosen. Where stage 0's residual
(:mod:`.structure`) has bands, the axes are tried strongest band first: the mode and every
axis' linear scales are fitted to the ratio of the record's multisine FRF to the nominal
simulation's (:func:`~frf_ident.core.fit.link_mode.fit_second_mode`, started in the band).
A fit that explains its band (MODE_COST_SHARE of the linear fit's cost above its degrees of freedom
removed, no band left on its axis beyond MODE_LEFT_SHARE of the one that asked for it, the
frequency determined within MODE_FREQUENCY_SE and such that the mode acts in the band
(MODE_BAND_SPAN), the damping ratio in MODE_DAMPING_RANGE, at least MODE_MIN_INERTIA_SHARE of the
link's inertia on the spring, the mode in the measured band) is a candidate ``second_mode``, with
the Cramer-Rao standard errors of its frequency, damping ratio and inertia, and any linear
parameter of its axis the same fit moves as stage 0 would name it (MISMATCH_MIN_LOG and
FD_MISMATCH_Z). The candidates are judged by simulation one after the other
(:func:`take_second_mode`); the first taken ends the search. Once the other effects are in the
model, :func:`refine_modes` refits each named mode's frequency, damping ratio and inertia by
simulation: the multisine lines may lie a few half-power widths off a light mode, whose damping
then only the chirp's passage through it shows. :func:`mode_band` is the band of a named mode the
held-out check reports.
"""
from __future__ import annotations

from dataclasses import replace
import math
from typing import Callable, Iterator

from frf_ident.core.fit.link_mode import fit_second_mode, LINEAR, ModeFit
from frf_ident.core.fit.residual_whiteness import residual_test, ResidualBand
from frf_ident.core.model.params import RobotParams
from frf_ident.core.simulation.analytic import robot_frf
from frf_ident.errors import ModelFileError
import numpy as np

from .acceptance import accept
from .refit import rebuild, searched
from .rigid_axes import rigid_in_band
from .search import Search
from .simplex import nelder_mead
from .structure import structural, StructureReading
from ..common import apply_effect, Effect
from ..mode_thresholds import (MODE_BAND_DB, MODE_BAND_SPAN, MODE_BANDS_TRIED, MODE_COST_SHARE,
                               MODE_DAMPING_RANGE, MODE_FREQUENCY_SE, MODE_LEFT_SHARE,
                               MODE_MIN_INERTIA_SHARE, MODE_REFINE_EVALUATIONS, MODE_REFINE_STEP)
from ..thresholds import FD_MISMATCH_Z, MISMATCH_MIN_LOG

__all__ = ['mode_band', 'refine_modes', 'second_mode_candidates', 'take_second_mode']


def second_mode_candidates(reading: StructureReading, robot: RobotParams,
                           say: Callable[[str], None]) -> Iterator[Effect]:
    """
    Yield the second modes that explain a band of stage 0's residual, strongest band first.

    Each axis' MODE_BANDS_TRIED strongest bands, in the order of their statistics (not on an axis
    the model holds rigid in the band: a resonance there is the joint's missing spring, which
    stage 0b reads, :mod:`.rigid_axes`; the iiwa 14 of ``demo --plant mujoco`` against its rigid
    MJCF had its joint springs read as second modes, and left unexplained): a mode is fitted
    there (:func:`~frf_ident.core.fit.link_mode.fit_second_mode`) and yielded when it explains the
    band (:func:`_why_not`); an axis' weaker bands are tried only while none of its stronger ones
    gave a candidate. A mode moves its axis' first resonance and antiresonance too, so its own band
    need not be the strongest (scene link_mode 6587472 of ``python -m benchmarks.second_mode 10
    6587468``: a 35.3 Hz mode on joint_2, its band 35.5-42.6 Hz at 7.0 x the noise, the shifted
    first resonance 11.4-17.3 Hz at 6.45 x; the fit there explains 47 % of the cost, the mode was
    reported unexplained). The caller judges each by simulation and stops at the first it takes: a
    mode behind one link shows on the coupled axes too, and a fit on a coupled axis may explain its
    band with a mode the simulation then rejects (scene link_mode_beside 3 of
    benchmarks/second_mode.py: Coulomb friction on joint_1, the mode on joint_3 at 39 Hz; joint_2's
    band at its resonance, the mode's coupling, was the strongest).

    Parameters
    ----------
    reading : StructureReading
        Stage 0's linear fit and its residual tests.
    robot : RobotParams
        The nominal model.
    say : callable
        Trace lines (every fit and why it was or was not offered).

    Yields
    ------
    Effect
        ``second_mode`` candidates, one per axis at most.

    """
    # a joint the model holds rigid has no first resonance for a mode to sit behind: what its
    # FRFs show in the band is the joint's own spring, read by stage 0b (.rigid_axes)
    rigid = [i for i in range(robot.n_axes) if rigid_in_band(robot, i)]
    for i in rigid:
        say(f'  {robot.axes[i].name}: rigid in the model: a resonance in its band is read as '
            f'the joint spring it lacks (stage 0b), not as a second mode')
    order = sorted(((b.statistic, i, k, b) for i in range(robot.n_axes) if i not in rigid
                    for k, b in enumerate(reading.bands(i)[:MODE_BANDS_TRIED])),
                   key=lambda t: t[:3], reverse=True)
    done: set[int] = set()
    for _, i, _, band in order:
        if i in done:
            continue
        fit = fit_second_mode(robot, reading.data, i, band.centre_hz, reading.linear)
        if fit is None:
            say(f'  {robot.axes[i].name}: no second mode converged in {band.text()}')
            continue
        why = _why_not(fit, reading, band, robot.axes[i].link_inertia)
        say(f'  {robot.axes[i].name}: second mode in {band.text()}: {_fit_text(fit)}'
            + (f': not offered ({why})' if why else ': offered'))
        if not why:
            done.add(i)
            left = structural(residual_test(reading.data.freq_hz, fit.residual[i]))
            yield _effect(fit, reading, robot, band.text(),
                          f'leaves {left[0].text()}' if left else 'leaves no band')


def _fit_text(fit: ModeFit) -> str:
    """Return the fitted mode with its standard errors, for the trace and the evidence."""
    return (f'{fit.frequency_hz:.4g} +- {fit.frequency_std:.2g} Hz, damping ratio '
            f'{fit.damping_ratio:.3g} +- {fit.damping_std:.2g}, inertia {fit.inertia:.4g} +- '
            f'{fit.inertia_std:.2g} kg m^2 (cost {fit.cost:.4g} for {fit.dof} degrees of freedom)')


def _why_not(fit: ModeFit, reading: StructureReading, asked: ResidualBand, link_inertia: float
             ) -> str:
    """Return why a fitted mode does not explain the band that ``asked`` for it ('' if it does)."""
    lin = reading.linear
    removed = (fit.linear_cost - fit.cost) / max(fit.linear_cost - lin.dof, 1e-12)
    f = reading.data.freq_hz
    left = structural(residual_test(f, fit.residual[fit.axis]))
    if removed < MODE_COST_SHARE:
        return f"it removes {100 * removed:.0f} % of the linear fit's cost above the noise"
    if left and left[0].statistic > MODE_LEFT_SHARE * asked.statistic:
        return f'it leaves {left[0].text()}'
    lo, hi = asked.lo_hz / MODE_BAND_SPAN[1], asked.hi_hz / MODE_BAND_SPAN[0]
    if not lo <= fit.frequency_hz <= hi:
        return (f'a mode at {fit.frequency_hz:.4g} Hz acts outside the band '
                f'(it would lie in {lo:.3g}-{hi:.3g} Hz)')
    if not fit.frequency_std < MODE_FREQUENCY_SE * fit.frequency_hz:
        return 'its frequency is not determined'
    lo, hi = MODE_DAMPING_RANGE
    if not lo <= fit.damping_ratio <= hi:
        return f'damping ratio {fit.damping_ratio:.3g} outside [{lo:g}, {hi:g}]'
    share = fit.inertia / (link_inertia * math.exp(fit.log_scale[1]))
    if share < MODE_MIN_INERTIA_SHARE:
        return f"it carries {100 * share:.2g} % of the link's inertia"
    if not f.min() <= fit.frequency_hz <= f.max():
        return 'outside the measured band'
    return ''


def _effect(fit: ModeFit, reading: StructureReading, robot: RobotParams, band: str, left: str
            ) -> Effect:
    """Return the candidate effect of a fitted mode (and the linear changes of its axis)."""
    a = robot.axes[fit.axis]
    params: dict = {'second_mode': fit.second_mode()}
    se: dict = {'second_mode': fit.second_mode_std()}
    moved = []
    for k, x, sd in zip(LINEAR, fit.log_scale, fit.log_scale_std):
        if abs(x) > MISMATCH_MIN_LOG and abs(x) > FD_MISMATCH_Z * sd:
            params[k] = getattr(a, k) * math.exp(x)
            se[k] = params[k] * sd
            moved.append(f'{k} x{math.exp(x):.3f} +- {sd:.3f}')
    lin = reading.linear
    return Effect('second_mode', a.name, 0.0, params,
                  f'the frequency-domain fit of the multisine FRF (against the nominal '
                  f'simulation) leaves {band} on {a.name}: no linear parameter change explains '
                  f'it (cost {lin.cost:.4g} for {lin.dof} degrees of freedom); a link-side mode '
                  f'there, {_fit_text(fit)}, {left} on its axis'
                  + (f'; with it {", ".join(moved)}' if moved else ''),
                  fit.axis, standard_error=se)


def mode_band(model: RobotParams, effect: Effect, freq_hz: np.ndarray) -> list[float]:
    """
    Return the band [f1, f2] Hz of a named mode: where it changes its axis' FRF.

    The lines around the largest change of the axis' analytic FRF by the mode (the model with
    it against without it) between MODE_BAND_SPAN times its frequency (the resonance it adds
    lies above its link-held frequency; far below it the mode's inertia moves with the link
    and only shifts a sharp antiresonance a little) while the change stays at least
    MODE_BAND_DB, plus one line each side.

    Parameters
    ----------
    model : RobotParams
        The extended model (with the mode).
    effect : Effect
        The ``second_mode`` effect.
    freq_hz : ndarray
        The lines the band is read on (ascending).

    Returns
    -------
    list of float
        [f1, f2] in Hz.

    """
    i = effect.axis_index
    f = np.asarray(freq_hz, dtype=float)
    without = apply_effect(model, Effect('second_mode', effect.axis, 0.0, {'second_mode': None},
                                         '', i))
    d = 20 * np.abs(np.log10(np.abs(robot_frf(model, f)[i, i] / robot_frf(without, f)[i, i])))
    fe = float(effect.parameters['second_mode']['frequency_hz'])
    near = (f >= MODE_BAND_SPAN[0] * fe) & (f <= MODE_BAND_SPAN[1] * fe)
    k = int(np.argmax(np.where(near, d, -1.0))) if near.any() else int(np.argmin(np.abs(f - fe)))
    lo = hi = k
    while lo > 0 and d[lo - 1] >= MODE_BAND_DB:
        lo -= 1
    while hi < f.size - 1 and d[hi + 1] >= MODE_BAND_DB:
        hi += 1
    return [round(float(f[max(lo - 1, 0)]), 2), round(float(f[min(hi + 1, f.size - 1)]), 2)]


def take_second_mode(s: Search) -> None:
    """
    Offer stage 0's second-mode candidates one after the other; stop at the first taken.

    Each is judged by simulation (:func:`.acceptance.accept`) against the model so far; every
    one offered is a candidate of the report (its ``rejected`` entry when not taken).
    """
    if s.structure is None:
        return
    for c in second_mode_candidates(s.structure, s.robot, s.say):
        try:
            apply_effect(s.robot, c)
        except ModelFileError as err:
            # a mode heavier than the link coupling leaves room for (an MJCF arm's coupled
            # links): no model holds it, it is reported, not simulated
            c.reason = f'no model holds it: {err}'
            s.cands.append(c)
            continue
        s.ext, s.cur = accept(s.ev, s.robot, s.kept, [c], s.cur, s.say)
        s.stage0.append(c)
        s.cands.append(c)
        if c in s.kept:
            return


def refine_modes(s: Search) -> None:
    """
    Refit every named mode's frequency, damping ratio and inertia by simulation.

    Where its axis is still above its noise floor: Nelder-Mead on their log scale factors
    (MODE_REFINE_STEP the first simplex) with the axis' misfit on the fit part, every other effect
    in the model, at most MODE_REFINE_EVALUATIONS simulations; kept when the axis' misfit drops.
    The standard errors stay those of the frequency-domain fit (the evidence says so). The lines of
    a multisine a few half-power widths off a light mode leave its damping to the time signals:
    scene link_mode 4 of benchmarks/second_mode.py (44.3 Hz, damping ratio 0.0063 on joint_3, lines
    2.6 Hz apart there) was fitted at 0.0039 (the misfit of the axis 1.13 floors, the truth's
    0.40).
    """
    for c in [k for k in s.kept if k.name == 'second_mode']:
        i = c.axis_index
        if s.cur[i] <= s.ev.floor_seen(s.cur)[i]:
            continue                     # explained to the noise: nothing to refine
        start = dict(c.parameters['second_mode'])
        keys = ('frequency_hz', 'damping_ratio', 'inertia')
        limit = s.ext.axes[i].link_inertia

        def params(x, c=c, start=start):
            p = dict(c.parameters)
            p['second_mode'] = {k: start[k] * float(np.exp(v)) for k, v in zip(keys, x)}
            p['second_mode']['inertia'] = min(p['second_mode']['inertia'], 0.95 * limit)
            return p

        def mk(x, c=c):
            return rebuild(s.robot, [replace(k, parameters=params(x)) if k is c else k
                                     for k in s.kept])
        simplex = np.vstack([np.zeros(3), np.diag(MODE_REFINE_STEP)])
        loss, prefetch = searched(s.ev, mk, i)
        prefetch(list(simplex))
        best = nelder_mead(loss, simplex, xatol=0.005, fatol=1e-3,
                           maxfev=MODE_REFINE_EVALUATIONS, prefetch=prefetch)
        ext = mk(best)
        new = s.ev.misfit(s.ev.terms(ext))
        if new[i] >= s.cur[i]:
            continue
        c.parameters = params(best)
        m = c.parameters['second_mode']
        s.say(f'  {c.axis} second_mode refined by simulation: misfit {s.cur[i]:.4g} -> '
              f'{new[i]:.4g}: ' + ', '.join(f'{k} {m[k]:.4g}' for k in keys))
        c.evidence += (f'; refined by simulation to {m["frequency_hz"]:.4g} Hz, damping ratio '
                       f'{m["damping_ratio"]:.3g}, inertia {m["inertia"]:.4g} kg m^2 (misfit '
                       f'{s.cur[i]:.3g} -> {new[i]:.3g} noise floors; standard errors of the '
                       f'frequency-domain fit)')
        s.ext, s.cur = ext, new
