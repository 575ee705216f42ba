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
The fit stages of `frf-ident fit`: the physical (per axis and coupled) and the rational fit.

Each stage fits, prints its lines (:mod:`frf_ident.app.fit` composes them) and writes its
model file (model.yaml through :mod:`frf_ident.app.fitted_model`, or model.mat); it returns a
:class:`FitStage`, what the figure, fit.json and the report page need.
"""
from __future__ import annotations

from dataclasses import dataclass
import logging
from pathlib import Path
from typing import Callable

from frf_ident.app.fitted_model import export_drive, hold_of, write_fitted_model
from frf_ident.app.frf_source import axis_channels
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.fit.cost import CostTest
from frf_ident.core.fit.coupled import CoupledFit, fit_coupled
from frf_ident.core.fit.physical import fit_two_mass, PhysicalFit
from frf_ident.core.fit.rational import OrderSelection, select_order
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.lti import write_lti_mat
import numpy as np

__all__ = ['FitStage', 'MAX_DISAGREEMENT_LINES', 'MAX_ORDER', 'physical_stage',
           'rational_stage', 'say_coupled', 'short_verdict']

_log = logging.getLogger(__name__)

#: highest order tried when no --order is given: 9 states (3 twists, 6 velocities) describe the
#: 3-axis robot's velocity FRF; 12 leaves room for a second mode per axis
MAX_ORDER = 12
#: per-axis/coupled disagreements printed on the console (all are in fit.json and the log)
MAX_DISAGREEMENT_LINES = 3


@dataclass
class FitStage:
    """What a fit stage gives the writers: the fits, the channels' data and figure labels."""

    physical: list[PhysicalFit] | None
    coupled: CoupledFit | None
    rational: OrderSelection | None
    measured: np.ndarray
    fitted: np.ndarray
    variance: np.ndarray | None
    names: list[str]
    verdicts: list[str]
    files: list[Path]


def physical_stage(frf: FrequencyResponse, var: np.ndarray | None, delay_s: float | None,
                   model: str | Path | None, out: Path, say: Callable[[str], None]) -> FitStage:
    """Fit per axis, and the coupled robot when the FRF is square with >= 2 axes."""
    chans = axis_channels(frf)
    outs, ins = [o for _, o, _ in chans], [i for _, _, i in chans]
    names = [n for n, _, _ in chans]
    hold = hold_of(model)
    nf = frf.freq_hz.size
    if len(chans) >= 2 and len(set(outs)) == len(outs) == frf.noutputs:
        sub = frf.response[np.ix_(outs, ins)]
        v = None if var is None else var[np.ix_(outs, ins)]
        coupled = fit_coupled(frf.freq_hz, sub, v, delay_s=delay_s, names=names)
        say_coupled(coupled, hold, say)
        phys, values = coupled.per_axis, {n: coupled.axis_parameters(k)
                                          for k, n in enumerate(names)}
        measured, fitted = sub.reshape(-1, nf), coupled.model.reshape(-1, nf)
        labels = [f'{a} -> {b}: coupled fit' for b in names for a in names]
        verdicts = [short_verdict(coupled.cost)] * len(labels)
    else:
        coupled = None
        v = None if var is None else np.stack([var[o, i] for _, o, i in chans])
        phys = [fit_two_mass(frf.freq_hz, frf.response[o, i], None if var is None else
                             var[o, i], delay_s=delay_s, name=n) for n, o, i in chans]
        for fit in phys:
            for line in fit.summary(hold):
                say(f'  {line}')
        values = {f.name: f.parameters() for f in phys}
        measured = np.stack([frf.response[o, i] for _, o, i in chans])
        fitted = np.stack([f.model for f in phys])
        labels = [f'{n}: two-mass fit' for n in names]
        verdicts = [short_verdict(f.cost) for f in phys]
    delays = None if delay_s is not None else {
        f.name: (f.delay_s if coupled is None else coupled.delay_s) for f in phys}
    written = write_fitted_model(values, None if coupled is None else
                                 coupled.link_coupling()[0], delays, model, out)
    for line in written.lines:
        say(f'  {line}')
    return FitStage(phys, coupled, None, measured, fitted,
                    None if v is None else v.reshape(measured.shape), labels, verdicts,
                    [written.path] + export_drive(written.robot, out, say))


def say_coupled(coupled: CoupledFit, hold: float, say: Callable[[str], None]) -> None:
    """Print the coupled fit; the per-axis starts in one line each (details to the log)."""
    for fit in coupled.per_axis:
        for line in fit.summary(hold):
            _log.debug(f'per axis: {line}')
        say(f'  per axis: {fit.name}: cost ratio {fit.cost.ratio:.3g}: {fit.cost.verdict} '
            f'(parameters: fit.json, -v)')
    for line in coupled.summary(hold):
        say(f'  {line}')
    apart = coupled.disagreements()
    for line in apart[:MAX_DISAGREEMENT_LINES]:
        say(f'  per axis vs coupled: {line}')
    for line in apart[MAX_DISAGREEMENT_LINES:]:
        _log.debug(f'per axis vs coupled: {line}')
    if apart:
        more = len(apart) - MAX_DISAGREEMENT_LINES
        say(f'  per axis vs coupled: {len(apart)} parameter(s) disagree beyond their errors'
            + (f' ({more} more in fit.json)' if more > 0 else '')
            + '; model.yaml takes the coupled values (the per-axis fits lack the coupling)')


def rational_stage(frf: FrequencyResponse, var: np.ndarray | None, order: int | None,
                   out: Path, say: Callable[[str], None]) -> FitStage:
    """Fit the rational model of the given order, or choose the order; write model.mat."""
    if order is not None and order < 1:
        raise FrfIdentInputError(f'--order {order}: expected an order >= 1')
    orders = [order] if order is not None else range(1, MAX_ORDER + 1)
    sel = select_order(frf.freq_hz, frf.response, var, orders,
                       inputs=list(frf.inputs), outputs=list(frf.outputs))
    for line in sel.best.summary():
        say(f'  {line}')
    if order is None:
        for line in sel.lines():
            say(f'  {line}')
    elif not sel.best.admissible:
        say(f'  --order {order}: a mode lies outside the fitted band; a lower order, or a '
            f'band reaching it (--band), gives a model the data support')
    measured = frf.response.reshape(-1, frf.freq_hz.size)
    return FitStage(None, None, sel, measured, sel.best.model.reshape(measured.shape),
                    None if var is None else var.reshape(measured.shape),
                    [f'{a} -> {b}' for b in frf.outputs for a in frf.inputs],
                    [short_verdict(sel.best.cost)] * measured.shape[0],
                    [write_lti_mat(sel.best, out / 'model.mat')])


def short_verdict(cost: CostTest) -> str:
    """Return the cost test's verdict in a few words for a figure title."""
    if not cost.weighted:
        return 'cost test: no FRF variance'
    word = 'structure missing' if cost.structure_missing else 'explained by the noise'
    return f'cost/dof {cost.ratio:.2f}: {word}'
