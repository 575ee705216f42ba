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
The controller check on a measured FRF: margins of L = C P-hat with their uncertainty.

Per axis, python-control's ``stability_margins`` on the FRD data of L_i = C_i P_ii gives the
gain, phase and modulus margins and the crossover; the same on draws of the FRF from its
variance (:func:`frf_ident.core.loop.check.draw_responses`) gives their standard deviations.
For several axes, the peak of the largest singular value of S = (I + P C)^-1 adds what the
coupling does. :func:`propose_gains` reads PI gains off the FRF for a target phase margin and
bandwidth; :func:`loop_check` then checks them on the measured FRF itself.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import json
from pathlib import Path
import warnings

from frf_ident.app.frf_source import axis_channels, read_source
from frf_ident.app.loop_document import check_dict
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.jsonable import jsonable
from frf_ident.core.loop.check import (AxisMargins, draw_responses, DRAWS, edge_gain_db,
                                       loop_response, LoopCheck, Margin, pi_response,
                                       sensitivity_peak)
from frf_ident.core.loop.design import check_targets, PIProposal, propose_pi, TargetCheck
from frf_ident.core.loop.notch import sections_response
from frf_ident.core.progress import Progress, sink
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.model_file import load_model
from frf_ident.report.fit_figures import loop_figure
from frf_ident.report.html import fit_sections, proposal_section, write_fit_report
import numpy as np

__all__ = ['LoopData', 'LoopOutcome', 'OUTPUT_FILES', 'check_dict', 'loop_check', 'loop_data',
           'margins', 'propose_gains', 'proposal_targets', 'run_loop']


def margins(loop: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """
    Return python-control's margins of SISO loop responses given as FRD data.

    Parameters
    ----------
    loop : ndarray of complex, shape (..., n_freq)
        L at ``omega``; leading axes are separate loops (e.g. draws).
    omega : ndarray, shape (n_freq,)
        Frequencies [rad/s].

    Returns
    -------
    ndarray, shape (..., 4)
        Gain margin [dB], phase margin [deg], gain crossover [Hz], modulus margin; NaN where
        python-control finds no crossover. The modulus margin is the least |1 + L| over the
        measured band: python-control's interior minima, or a measured line where |1 + L| is
        least at the band's edge (python-control reports none there: an infinite margin).

    """
    import control
    flat = loop.reshape(-1, loop.shape[-1])
    res = np.full((flat.shape[0], 4), np.nan)
    for k, lk in enumerate(flat):
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')
            gm, pm, sm, _, wgc, _ = control.stability_margins(
                control.frd(lk, omega, smooth=True), method='frd')
        res[k] = [20 * np.log10(gm) if gm and np.isfinite(gm) else np.inf, pm,
                  wgc / (2 * np.pi), min(sm, float(np.min(np.abs(1 + lk))))]
    return res.reshape(loop.shape[:-1] + (4,))


def _margin(nominal: float, draws: np.ndarray | None) -> Margin:
    if draws is None:
        return Margin(float(nominal), float('nan'))
    ok = draws[np.isfinite(draws)]
    return Margin(float(nominal), float(ok.std(ddof=1)) if ok.size > 2 else float('nan'))


@dataclass
class LoopData:
    """
    The loops a check looks at.

    Attributes
    ----------
    channels : list of tuple
        (axis, output index, input index) of every axis (:func:`axis_channels`).
    controller : ndarray of complex, shape (n_axes, n_freq)
        C_i of every axis.
    draws : ndarray of complex, shape (n_draws, n_out, n_in, n_freq), or None
        Draws of the FRF from its variance (None without variance).

    """

    channels: list[tuple[str, int, int]]
    controller: np.ndarray
    draws: np.ndarray | None

    def axis_loops(self, response: np.ndarray) -> np.ndarray:
        """Return L_i = C_i P_ii of every axis, shape (..., n_axes, n_freq)."""
        return np.stack([response[..., o, i, :] * self.controller[j]
                         for j, (_, o, i) in enumerate(self.channels)], axis=-2)


def loop_data(frf: FrequencyResponse, kp: np.ndarray, ki: np.ndarray, *,
              dt: float | None = None, draws: int = DRAWS, seed: int = 0,
              filters: np.ndarray | None = None) -> LoopData:
    """
    Return the controller responses and the FRF's draws for a check (args of loop_check).

    Parameters
    ----------
    frf : FrequencyResponse
        Torque -> velocity FRF.
    kp, ki : array_like, shape (n_axes,)
        PI gains per axis (in input order).
    dt : float, optional
        Sample time of the discrete PI; None: continuous PI.
    draws : int, optional
        Monte-Carlo draws of the FRF.
    seed : int, optional
        Seed of the draws.
    filters : ndarray of complex, shape (n_axes, n_freq), optional
        Response of each axis' filters on the measured velocity (issue #51; the model
        file's ``controller.filters``): C_i = PI_i F_i.

    Returns
    -------
    LoopData
        Channels, controller responses and draws.

    Raises
    ------
    FrfIdentInputError
        The number of gains is not the number of axes.

    """
    chans = axis_channels(frf)
    kp, ki = np.atleast_1d(np.asarray(kp, float)), np.atleast_1d(np.asarray(ki, float))
    if kp.size != len(chans) or ki.size != len(chans):
        raise FrfIdentInputError(f'controller gains: expected {len(chans)} kp and ki values '
                                 f'(one per FRF input {frf.inputs}), got {kp.size} and '
                                 f'{ki.size}')
    var = frf.variance()
    sample = None
    if var is not None and draws > 0:
        sample = draw_responses(frf.response, var, draws, np.random.default_rng(seed))
    c = np.stack([pi_response(frf.freq_hz, kp[j], ki[j], dt) for j in range(len(chans))])
    if filters is not None:
        c = c * np.asarray(filters).reshape(c.shape)
    return LoopData(chans, c, sample)


def loop_check(frf: FrequencyResponse, kp: np.ndarray, ki: np.ndarray, *,
               dt: float | None = None, draws: int = DRAWS, seed: int = 0,
               filters: np.ndarray | None = None) -> LoopCheck:
    """
    Check the velocity PI on the measured loop: margins with their uncertainty.

    Parameters
    ----------
    frf : FrequencyResponse
        Torque -> velocity FRF (square for the MIMO sensitivity peak); its total variance
        (else noise variance) gives the uncertainty.
    kp, ki : array_like, shape (n_axes,)
        PI gains per axis (in input order).
    dt : float, optional
        Sample time of the discrete PI as the simulation runs it; None: continuous PI.
    draws : int, optional
        Monte-Carlo draws of the FRF for the standard deviations.
    seed : int, optional
        Seed of the draws.
    filters : ndarray of complex, shape (n_axes, n_freq), optional
        Response of each axis' filters (:func:`loop_data`).

    Returns
    -------
    LoopCheck
        Per-axis margins, the MIMO sensitivity peak, and how many draws were used.

    Raises
    ------
    FrfIdentInputError
        The number of gains is not the number of axes.

    """
    data = loop_data(frf, kp, ki, dt=dt, draws=draws, seed=seed, filters=filters)
    loops = data.axis_loops(frf.response)
    nominal = margins(loops, frf.omega)
    edge = edge_gain_db(loops)
    band = (float(frf.freq_hz.min()), float(frf.freq_hz.max()))
    drawn = None if data.draws is None else margins(data.axis_loops(data.draws), frf.omega)
    axes = []
    for j, (name, _, _) in enumerate(data.channels):
        axes.append(AxisMargins(name, float(np.atleast_1d(kp)[j]), float(np.atleast_1d(ki)[j]),
                                *[_margin(nominal[j, q], None if drawn is None
                                          else drawn[:, j, q]) for q in range(4)],
                                band_hz=band, edge_gain_db=float(edge[j])))
    peak = None
    if len(data.channels) > 1 and frf.noutputs == frf.ninputs:
        peak = _margin(float(sensitivity_peak(loop_response(frf.response, data.controller))),
                       None if data.draws is None else
                       sensitivity_peak(loop_response(data.draws, data.controller)))
    return LoopCheck(axes, peak, 0 if data.draws is None else data.draws.shape[0], dt)


def propose_gains(frf: FrequencyResponse, bandwidth_hz: float, phase_margin_deg: float
                  ) -> list[PIProposal]:
    """
    Propose PI gains per axis from the measured FRF (see :mod:`frf_ident.core.loop.design`).

    Parameters
    ----------
    frf : FrequencyResponse
        Torque -> velocity FRF.
    bandwidth_hz : float
        Target crossover [Hz].
    phase_margin_deg : float
        Target phase margin [deg].

    Returns
    -------
    list of PIProposal
        One per axis, in input order.

    Raises
    ------
    FrfIdentInputError
        The bandwidth lies outside the measured band (the message names ``--propose`` and
        the band).

    """
    out = []
    for name, o, i in axis_channels(frf):
        try:
            out.append(propose_pi(frf.freq_hz, frf.response[o, i], bandwidth_hz,
                                  phase_margin_deg))
        except ValueError as err:
            raise FrfIdentInputError(
                f'--propose {bandwidth_hz:g} {phase_margin_deg:g}: axis {name}: {err}; give a '
                f'bandwidth inside it (the design reads the FRF at the bandwidth)') from err
    return out


def proposal_targets(proposals: list[PIProposal], check: LoopCheck) -> list[TargetCheck]:
    """
    Return per axis whether the measured loop with the proposed gains meets the targets.

    Parameters
    ----------
    proposals : list of PIProposal
        The proposed gains per axis.
    check : LoopCheck
        Those gains checked on the measured FRF (:func:`loop_check`).

    Returns
    -------
    list of TargetCheck
        One per axis (:func:`~frf_ident.core.loop.design.check_targets`).

    """
    return [check_targets(p, a.phase_margin_deg.value, a.crossover_hz.value, a.edge_gain_db,
                          a.band_hz) for p, a in zip(proposals, check.axes)]


#: the files :func:`run_loop` writes into its output directory
OUTPUT_FILES = ('loop.json', 'loop.png', 'loop.html')


@dataclass
class LoopOutcome:
    """
    What ``loop`` found and wrote.

    Attributes
    ----------
    check : LoopCheck or None
        The given controller on the measured FRF (None when only a proposal was asked).
    proposals : list of PIProposal
        PI gains proposed for the target (empty without ``propose``).
    proposal_check : LoopCheck or None
        The proposed gains checked on the measured FRF.
    files : list of Path
        Files written.
    targets : list of TargetCheck
        Per axis, whether the proposed gains meet the targets on the measured loop.

    """

    check: LoopCheck | None
    proposals: list[PIProposal]
    proposal_check: LoopCheck | None
    files: list[Path]
    targets: list[TargetCheck] = field(default_factory=list)


def run_loop(source: str | Path, out: Path, *, kp: list[float] | None = None,
             ki: list[float] | None = None, dt: float | None = None,
             model: str | Path | None = None,
             propose: tuple[float, float] | None = None, draws: int = DRAWS,
             page: bool = True, progress: Progress | None = None) -> LoopOutcome:
    """
    Check a velocity PI on a measured FRF (and/or propose one); write loop.json, loop.png.

    And loop.html, the report page of the margins (unless ``page`` is False: ``fit`` puts
    the same section into its fit.html).

    Parameters
    ----------
    source : str or Path
        Directory with frf.json, or an FRF file.
    out : Path
        Output directory (created if missing; the caller has checked it).
    kp, ki : list of float, optional
        Gains per axis; they take precedence over the model file's.
    dt : float, optional
        Sample time of a discrete PI for the given gains; with the model file's gains its
        sample time is used.
    model : str or Path, optional
        Model file whose ``controller`` (velocity PI, discrete at the model's sample rate) is
        checked.
    propose : tuple of float, optional
        (bandwidth [Hz], phase margin [deg]): propose PI gains and check them too.
    draws : int, optional
        Monte-Carlo draws of the FRF for the standard deviations.
    page : bool, optional
        Write loop.html.
    progress : callable, optional
        Called with one line of text per stage.

    Returns
    -------
    LoopOutcome
        The checks, proposals and files.

    Raises
    ------
    FrfIdentInputError
        No controller given and nothing to propose, gains of the wrong count, or a target
        bandwidth outside the measured band.

    """
    frf = read_source(source)
    filters = None
    if kp is None and model is not None:
        _, robot, ctrl = load_model(model)
        kp, ki, dt = ctrl.kp.tolist(), ctrl.ki.tolist(), robot.dt
        if ctrl.n_sections:          # the model's filters on the measured velocity (#51)
            filters = np.stack([sections_response(frf.freq_hz, ctrl.sos[j], robot.sample_rate)
                                for j in range(ctrl.n_axes)])
    if (kp is None) != (ki is None):
        raise FrfIdentInputError('--kp and --ki: give both (one value per axis)')
    if kp is None and propose is None:
        raise FrfIdentInputError('loop: nothing to check: give --model, --kp/--ki or --propose')
    out.mkdir(parents=True, exist_ok=True)
    progress = sink(progress)
    progress(f'loop: {frf.noutputs}x{frf.ninputs} FRF, {frf.freq_hz.size} lines '
             f'{frf.freq_hz.min():.3g}-{frf.freq_hz.max():.3g} Hz; PI '
             f'{"discrete, dt " + format(dt, "g") + " s" if dt else "continuous"}')
    check = None
    figure_gains = None
    if kp is not None:
        check = loop_check(frf, kp, ki, dt=dt, draws=draws, filters=filters)
        figure_gains = (kp, ki, dt, check)
        for line in check.summary():
            progress(f'  {line}')
    proposals, pcheck, targets = [], None, []
    if propose is not None:
        proposals = propose_gains(frf, *propose)
        pkp, pki = [p.kp for p in proposals], [p.ki for p in proposals]
        pcheck = loop_check(frf, pkp, pki, draws=draws)
        targets = proposal_targets(proposals, pcheck)
        progress(f'  proposed PI for {propose[1]:g} deg at {propose[0]:g} Hz, checked on the '
                 f'measured FRF:')
        for a, t in zip(pcheck.axes, targets):
            progress(f'    {a.summary()}')
            progress(f'    {a.axis}: {t.text()}')
        if figure_gains is None:
            figure_gains, filters = (pkp, pki, None, pcheck), None
    gkp, gki, gdt, gcheck = figure_gains
    data = loop_data(frf, gkp, gki, dt=gdt, draws=draws, filters=filters)
    files = [loop_figure(frf.freq_hz, data.axis_loops(frf.response),
                         None if data.draws is None else data.axis_loops(data.draws),
                         [c[0] for c in data.channels],
                         [a.modulus_margin.value for a in gcheck.axes], out / 'loop.png')]
    doc = {'source': str(source), 'check': None if check is None else check_dict(check),
           'proposal': None if propose is None else {
               'bandwidth_hz': propose[0], 'phase_margin_deg': propose[1],
               'gains': [{'axis': c[0], 'kp': p.kp, 'ki': p.ki, 'feasible': p.feasible,
                          'targets_met': t.met, 'missed': list(t.missed)}
                         for c, p, t in zip(axis_channels(frf), proposals, targets)],
               'check': check_dict(pcheck)}}
    (out / 'loop.json').write_text(json.dumps(jsonable(doc), indent=1))
    files.append(out / 'loop.json')
    if page:
        sections = fit_sections(check=gcheck, loop_png='loop.png')
        if pcheck is not None:
            sections.append(proposal_section(
                pcheck if check is not None else None, propose,
                [(a.axis, t.text(), t.met) for a, t in zip(pcheck.axes, targets)]))
        files.append(write_fit_report(out / 'loop.html', title=f'Loop check of {source}',
                                      sections=sections))
    progress(f'loop: wrote {", ".join(p.name for p in files)} to {out}')
    return LoopOutcome(check, proposals, pcheck, files, targets)
