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
from frf_ident.report.effect_names import effect_phrase
from frf_ident.report.page import figure_tag, page, table
from frf_ident.report.text import not_determined_text, parameters_text

if TYPE_CHECKING:
    from frf_ident.core.diagnosis import Diagnosis, DiagnosisResult
    from frf_ident.core.diagnosis.crosscheck.checks import CrossChecks
    from frf_ident.io.mjcf.diagnosed import MjcfResult

__all__ = ['write_diagnosis_report']


def write_diagnosis_report(out_dir: str | Path, diag: Diagnosis, data: str | Path, *,
                           mjcf: MjcfResult | None = None) -> Path:
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
    mjcf
        A diagnosis against an MJCF: extended_model.xml, its drive terms, what the MJCF cannot
        hold and the gain MuJoCo measured (a section of its own).

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
    if mjcf is not None:
        sections.insert(1, ('mjcf', 'Written back as MJCF', _mjcf(mjcf)))
    p = out / 'report.html'
    p.write_text(page(f'Diagnosis of {data}', sections, rec))
    return p


def _effects(res: DiagnosisResult) -> str:
    if not res.effects:
        return '<p>none of the candidate effects improves the held-out data.</p>'
    return table(['#', 'effect', 'axis', 'score', 'value (\u00b1 standard error)', 'evidence'],
                 [[k + 1, effect_phrase(e.name), e.axis, round(e.score, 3),
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
        causes = [u for u in une if u.cause is not None]
        if causes:
            text += ('<p>What locks each peak (its frequency at the steady speeds of the '
                     'record):</p><ul>' + ''.join(
                         f'<li>{html.escape(u.axis)}, {u.cause.frequency_hz:g} Hz: '
                         f'{html.escape(u.cause.describe())}</li>' for u in causes) + '</ul>')
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
            + f'<p>{html.escape(m.validation)}</p>' + _resonance_bands(m))


def _resonance_bands(m) -> str:
    """Return the held-out error in the band of every named or unexplained mode (or '')."""
    if not m.resonance_bands:
        return ''
    verdict = ('an improvement: no worse over all lines and in no band' if m.improved else
               'not an improvement: worse over all lines or in a resonance band')
    return ('<p>In the band of every named or unexplained mode (the error over all lines '
            'hides the few lines around a resonance):</p>'
            + table(['axis', 'band [Hz]', 'source', 'nominal [dB]', 'extended [dB]',
                     'nominal p95 [dB]', 'extended p95 [dB]', 'lines'],
                    [[r.axis, f'{r.band_hz[0]:g}-{r.band_hz[1]:g}', r.source, r.nominal_db,
                      r.extended_db, r.nominal_p95_db, r.extended_p95_db, r.n_lines]
                     for r in m.resonance_bands])
            + f'<p>The extension is {verdict}.</p>')


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
                                    for ax, v in ls.extended_vs_baseline.items()) + '</ul>'
                 + '<p>After the rule (time_nrmse, extended against least squares):</p>'
                 + '<ul>' + ''.join(f'<li>{html.escape(v.sentence())}</li>'
                                    for v in ls.verdicts) + '</ul>')
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


def _mjcf(m: MjcfResult) -> str:
    """Return the MJCF section: both files' drive terms, the limitations, MuJoCo's metrics."""
    rows = [[t.axis, k, _term(a), _term(b)] for t in m.axes for k, (a, b) in t.changed().items()]
    text = (f'<p><a href="{html.escape(m.file)}">{html.escape(m.file)}</a>: '
            f'{html.escape(m.base)} with the diagnosed drive terms '
            f'(<code>mujoco.MjModel.from_xml_path</code> loads it; docs/mujoco.md).</p>')
    text += (table(['axis', 'MJCF term', 'nominal', 'extended'], rows) if rows
             else '<p>no drive term changed.</p>')
    if m.not_representable or m.notes:
        text += '<p>Not representable in MJCF, and notes:</p><ul>' + ''.join(
            f'<li>{html.escape(x)}</li>' for x in m.not_representable + m.notes) + '</ul>'
    if m.nominal is not None:
        text += table(['held out, simulated by MuJoCo', 'FRF error [dB]', 'time NRMSE'],
                      [['nominal MJCF', f'{m.nominal.frf_error_db:.3g}',
                        f'{m.nominal.time_nrmse:.3g}'],
                       [m.file, f'{m.extended.frf_error_db:.3g}',
                        f'{m.extended.time_nrmse:.3g}']])
        text += f'<p>{html.escape(m.validation)}</p>'
    return text


def _term(x) -> str:
    return 'rigid' if x is None else f'{x:.4g}'


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
