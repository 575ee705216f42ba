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
The HTML page of ``frf-ident diagnose``: report.html beside report.json.

Drawn from the typed :class:`frf_ident.core.diagnosis.Diagnosis`, the object report.json is
written from: the ranked effects with their values, units, standard errors and evidence; what
is left unexplained and where; the gain on held-out data (per axis, per other record, against
the least-squares baseline, the integrator check); the rejected candidates; the figures of
:func:`frf_ident.report.figures.diagnosis_figures`.
"""
from __future__ import annotations

import html
from pathlib import Path
from typing import TYPE_CHECKING

from frf_ident.report import figures
from frf_ident.report.page import figure_tag, page, table
from frf_ident.report.text import not_determined_text, parameters_text

if TYPE_CHECKING:
    from frf_ident.core.diagnosis import Diagnosis, DiagnosisResult
    from frf_ident.core.diagnosis.crosscheck.checks import CrossChecks

__all__ = ['write_diagnosis_report']


def write_diagnosis_report(out_dir: str | Path, diag: Diagnosis, data: str | Path) -> Path:
    """
    Write ``out_dir/report.html`` of ``frf-ident diagnose`` and its figures.

    Parameters
    ----------
    out_dir
        Directory of report.json (created if missing).
    diag
        The diagnosis.
    data
        The diagnosed file (shown in the title).

    Returns
    -------
    Path of report.html.

    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    res, rec = diag.result, diag.recording
    evidence = ('identification experiments (FRF of multisine and chirp, closed-loop '
                'simulation of the same reference)' if res.mode == 'experiments' else
                'time series (inverse-dynamics residual regression)')
    sections = [
        ('effects', 'Effects (most likely first)',
         f'<p>Evidence: {html.escape(evidence)}.</p>' + _effects(res)
         + '<p>Extended model: <a href="extended_model.yaml">extended_model.yaml</a></p>'),
        ('unexplained', 'Unexplained', _unexplained(res)),
        ('metrics', 'Gain on held-out data', _metrics(res) + _checks(diag.checks)
         + _integrator(res)),
        ('rejected', 'Rejected candidates', _rejected(res)),
        ('figures', 'Figures', _figures(out, diag))]
    p = out / 'report.html'
    p.write_text(page(f'Diagnosis of {data}', sections, rec))
    return p


def _effects(res: DiagnosisResult) -> str:
    if not res.effects:
        return '<p>none of the candidate effects improves the held-out data.</p>'
    return table(['#', 'effect', 'axis', 'score', 'value (\u00b1 standard error)', 'evidence'],
                 [[k + 1, e.name, e.axis, round(e.score, 3),
                   parameters_text(e.parameters, e.standard_error) + ''.join(
                       '; ' + ': '.join(not_determined_text(n)) for n in e.not_determined),
                   e.evidence]
                  for k, e in enumerate(res.effects)])


def _unexplained(res: DiagnosisResult) -> str:
    une = res.unexplained
    if une:
        text = ('<p>The extended model leaves these axes clearly above their noise floor; '
                'the signature says where the rest of the misfit lives.</p>'
                + table(['axis', 'share of the nominal misfit left',
                         'bands [Hz], strongest first', 'residual correlates with'],
                        [[u.axis, u.misfit_share if u.misfit_share is not None else u.kind,
                          ', '.join(f'{b[0]:g}-{b[1]:g}' for b in (
                              u.signature.bands_hz or ([u.signature.band_hz]
                                                       if u.signature.band_hz else []))) or '-',
                          u.signature.correlates_with or '-'] for u in une]))
    else:
        text = '<p>nothing: every axis is explained to within its noise floor.</p>'
    if res.band is not None:
        b = res.band
        text += (f'<p>Effects fitted in the analysis band 0-{b.fc_hz:g} Hz (set by the '
                 f'{html.escape(b.reason)}); the residual above it is scanned for '
                 f'resonances (listed above as "resonance above the analysis band").</p>')
    return text


def _metrics(res: DiagnosisResult) -> str:
    m = res.metrics
    rows = [['nominal', m.baseline.frf_error_db, m.baseline.time_nrmse],
            ['extended', m.extended.frf_error_db, m.extended.time_nrmse]]
    for ax, v in m.baseline.per_axis.items():
        e = m.extended.per_axis[ax]
        rows += [[f'{ax}: nominal', v.frf_error_db, v.time_nrmse],
                 [f'{ax}: extended', e.frf_error_db, e.time_nrmse]]
    return (table(['model', 'frf_error_db', 'time_nrmse'], rows)
            + f'<p>{html.escape(m.validation)}</p>')


def _checks(checks: CrossChecks) -> str:
    text = ''
    for v in checks.validation_records:
        text += (f'<h3>other record {html.escape(v.record)}</h3>'
                 + table(['model', 'frf_error_db', 'time_nrmse'],
                         [['nominal', v.baseline.frf_error_db, v.baseline.time_nrmse],
                          ['extended', v.extended.frf_error_db, v.extended.time_nrmse]]))
        if v.beyond_fitted_range:
            text += ('<p class="warn">This record leaves the configuration range the model '
                     'was fitted on (position-dependent terms are extrapolated): '
                     + '; '.join(html.escape(r.describe(ax))
                                 for ax, r in v.beyond_fitted_range.items()) + '.</p>')
    ls = checks.least_squares
    if ls is not None:
        text += ('<h3>Against the least-squares baseline</h3>'
                 f'<p>{html.escape(ls.model)}; {html.escape(ls.metric)}.</p>'
                 + table(['held-out set', 'axis', 'nominal', 'least squares',
                          'extended (as fitted)'],
                         [[s.record, ax, v.nominal, v.least_squares, v.extended]
                          for s in ls.held_out_as_fitted for ax, v in s.per_axis.items()])
                 + '<ul>' + ''.join(f'<li>{html.escape(ax)}: the extended model '
                                    f'{html.escape(v)}</li>'
                                    for ax, v in ls.extended_vs_baseline.items()) + '</ul>')
    return text


def _integrator(res: DiagnosisResult) -> str:
    step = res.discretisation
    if step is None:
        return ''
    moved = ', '.join(f'{html.escape(ax)} {x:.4g} -> {y:.4g}' for ax, x, y in zip(
        step.axes, step.held_out_misfit, step.held_out_misfit_double_substeps))
    return (f'<p>Integrator check: the extended model simulated at twice its '
            f'simulation.substeps ({step.substeps}) moves the held-out misfit {moved} noise '
            f'floors; ' + html.escape(step.verdict()) + '</p>')


def _rejected(res: DiagnosisResult) -> str:
    if not res.rejected:
        return '<p>none.</p>'
    return table(['effect', 'axis', 'numbers', 'value', 'reason'],
                 [[r.name, r.axis, r.numbers() or '-',
                   parameters_text(r.parameters) if r.parameters else '-', r.reason or '-']
                  for r in res.rejected])


def _figures(out: Path, diag: Diagnosis) -> str:
    res = diag.result
    figs = figures.diagnosis_figures(out, res, diag.recording, res.mode)
    if res.band is not None:
        from .residual_spectrum import residual_spectrum_figure
        residual_spectrum_figure(res, diag.recording, out / 'residual_spectrum.png')
        figs.append(('residual_spectrum.png',
                     'Residual spectrum of the extended model: the analysis band (grey) and '
                     'the peaks above it the scan reports (orange, in Unexplained)'))
    return '\n'.join(figure_tag(fn, html.escape(cap), cap) for fn, cap in figs)
