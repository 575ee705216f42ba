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
Self-contained HTML reports of estimates and diagnoses.

One self-contained HTML report (inline CSS, no scripts, no external resources) that shows
FRF estimates, their uncertainty, the excitation and the data quality of a run.

``write_report(out_dir, frfs=..., ...)`` writes ``out_dir/report.html`` and its PNG figures
next to it (referenced by relative file name, so the directory can be moved or zipped):

- ``bode.png`` — Bode magnitude/phase per channel, +-2 sigma bands, optional reference
- ``snr.png`` — |P|^2 / variance per line in dB (only for estimates with variances)
- ``distortion.png`` — output levels at excited, odd and even lines with the noise level
  (multisine estimates with meta['distortion']), and one summary line per output
- ``robust_lpm.png`` — |P| with its noise and stochastic nonlinear level per line (robust
  LPM of one realisation, estimates with meta['robust_lpm']), and one summary line per output
- ``timeseries.png`` — torque, velocity and reference over time (with a recording)
- ``spectrogram.png`` — PSD of the torques over time, log frequency axis 1-60 Hz (Fig. 3)
- ``iterations.png`` — chirp iteration: error to u_des in dB per iteration and channel
- the timing findings of the bag reader (``TimingReport``) as tables

``write_fit_report(path, ...)`` writes the page of ``frf-ident fit`` / ``loop`` /
``estimate --fit`` (fit.html, loop.html): the sections of :func:`fit_sections`, the fitted
model over the FRF with its residual against the FRF's standard deviation, the parameters
with their standard errors and units, and the margins with their uncertainty.
"""
from __future__ import annotations

import html
import math
from pathlib import Path
from typing import Any, Mapping, Sequence

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.fit.coupled import CoupledFit
from frf_ident.core.fit.physical import PhysicalFit, UNITS
from frf_ident.core.fit.rational import RationalFit
from frf_ident.core.loop.check import LoopCheck, Margin
from frf_ident.core.recording import Recording
from frf_ident.errors import FrfIdentInputError
from frf_ident.report import figures
from frf_ident.report.distortion import distortion_figure, robust_lpm_figure
from frf_ident.report.page import figure_tag, num, page, table
import numpy as np

__all__ = ['fit_sections', 'proposal_section', 'write_fit_report', 'write_report']

REPORT_NAME = 'report.html'


def write_report(out_dir: str | Path, *, frfs: Mapping[str, FrequencyResponse],
                 reference: FrequencyResponse | None = None,
                 recording: Recording | None = None,
                 timing: Mapping[str, Any] | Any | None = None,
                 iterations: Sequence[Mapping[str, Any]] | None = None,
                 title: str = 'FRF identification report') -> Path:
    """
    Write ``out_dir/report.html`` plus PNG figures; return the HTML path.

    Parameters
    ----------
    out_dir
        Directory (created if needed); existing report files in it are replaced.
    frfs : mapping of str to FrequencyResponse
        Label -> estimate (e.g. {'multisine': ..., 'chirp': ...}); all with the same
        channels as the first.
    reference
        Model or known FRF drawn as a black line.
    recording
        The time series; gives the time plot and the torque spectrogram.
    timing
        ``TimingReport`` or its ``to_dict()``.
    iterations : sequence of dict, optional
        Chirp iteration summaries ``{'iteration': i, 'error_db': [per channel]}``
        (``error_db_per_channel`` is accepted too), optional ``tolerance_db``.
    title
        Page and heading title.

    Returns
    -------
    Path
        Path of the written ``report.html``.

    Raises
    ------
    FrfIdentInputError
        ``frfs`` is empty and no ``recording`` is given.

    """
    if not frfs and recording is None:
        raise FrfIdentInputError('write_report: nothing to report (frfs is empty and no '
                                 'recording given)')
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    timing_d = timing.to_dict() if hasattr(timing, 'to_dict') else timing
    sections: list[tuple[str, str, str]] = []  # (anchor, heading, html)
    if frfs:
        sections.append(('estimates', 'Estimates', _estimates_table(frfs, reference)))
        sections.append(('bode', 'Bode diagrams', _bode_section(out, frfs, reference)))
        snr = _snr_section(out, frfs)
        if snr:
            sections.append(('snr', 'Signal-to-noise ratio per line', snr))
        dist = _distortion_section(out, frfs)
        if dist:
            sections.append(('distortion', 'Nonlinear distortion per line', dist))
        robust = _robust_lpm_section(out, frfs)
        if robust:
            sections.append(('robust_lpm', 'Noise and nonlinear variance (robust LPM)', robust))
    if recording is not None:
        sections.append(('signals', 'Recorded signals', _signals_section(out, recording)))
        sections.append(('spectrogram', 'Torque spectrogram',
                         _spectrogram_section(out, recording)))
    if iterations:
        sections.append(('iterations', 'Chirp iteration', _iteration_section(
            out, iterations, _input_names(frfs, recording))))
    if timing_d:
        sections.append(('timing', 'Timing of the recording', _timing_section(timing_d)))
    path = out / REPORT_NAME
    path.write_text(page(title, sections, recording))
    return path


# --------------------------------------------------------------------------- sections

def _estimates_table(frfs: Mapping[str, FrequencyResponse],
                     reference: FrequencyResponse | None) -> str:
    rows = []
    for label, frf in frfs.items():
        var, which = figures.variance_of(frf)
        snr = (float(np.median(10 * np.log10(np.abs(frf.response) ** 2
                                             / np.maximum(var, 1e-300))))
               if var is not None else None)
        err = _error_to_reference(frf, reference)
        rows.append([label, f'{frf.noutputs} \u00d7 {frf.ninputs}', frf.freq_hz.size,
                     f'{frf.freq_hz[0]:.3g} \u2013 {frf.freq_hz[-1]:.3g}',
                     frf.method or '\u2014',
                     which or 'none', '\u2014' if snr is None else f'{snr:.1f}',
                     '\u2014' if err is None else f'{err:.2f}'])
    first = next(iter(frfs.values()))
    chans = ', '.join(f'{html.escape(i)} \u2192 {html.escape(o)}'
                      for o in first.outputs for i in first.inputs)
    return (table(['estimate', 'outputs \u00d7 inputs', 'lines', 'band [Hz]', 'method',
                   'variance', 'median SNR [dB]', 'RMS error to reference [dB]'], rows)
            + f'<p class="muted">Channels (input \u2192 output): {chans}</p>')


def _error_to_reference(frf: FrequencyResponse, ref: FrequencyResponse | None) -> float | None:
    """RMS over lines and channels of 20 log10 |P / P_ref| (reference interpolated in log f)."""
    if ref is None or ref.response.shape[:2] != frf.response.shape[:2]:
        return None
    inside = (frf.freq_hz >= ref.freq_hz[0]) & (frf.freq_hz <= ref.freq_hz[-1])
    if not inside.any():
        return None
    lf, lr = np.log(frf.freq_hz[inside]), np.log(ref.freq_hz)
    errs = []
    for o in range(frf.noutputs):
        for i in range(frf.ninputs):
            mag_ref = np.exp(np.interp(
                lf, lr, np.log(np.maximum(np.abs(ref.response[o, i]), 1e-300))))
            errs.append(20 * np.log10(np.maximum(np.abs(frf.response[o, i, inside]), 1e-300)
                                      / mag_ref))
    return float(np.sqrt(np.mean(np.concatenate(errs) ** 2)))


def _bode_section(out: Path, frfs: Mapping[str, FrequencyResponse],
                  reference: FrequencyResponse | None) -> str:
    figures.bode_figure(frfs, out / 'bode.png', reference=reference)
    return figure_tag('bode.png',
                      'Magnitude (upper row of each pair) and phase (lower row) of every channel '
                      'input \u2192 output. Markers: estimated lines; shaded: \u00b12\u03c3 '
                      'uncertainty from the total variance (noise + nonlinear distortion) or, '
                      'without it, the noise variance; black line: reference. Wide bands and '
                      'scattered markers mark lines the data do not determine well.',
                      'Bode diagrams of the estimates')


def _distortion_section(out: Path, frfs: Mapping[str, FrequencyResponse]) -> str:
    """Return the detection-line plot and summary of the first estimate with distortion levels."""
    for name, frf in frfs.items():
        levels = frf.distortion
        if levels is not None:
            distortion_figure(levels, out / 'distortion.png', title=name)
            items = ''.join(f'<li>{html.escape(line)}</li>' for line in levels.summary())
            return f'<ul>{items}</ul>' + figure_tag(
                'distortion.png',
                'Output level |Y|² of the period mean at the excited lines (open), at the '
                'odd lines the multisine leaves out (red: odd nonlinearities such as a cubic '
                'spring or friction) and at the even lines (green: even nonlinearities), with '
                'the noise level of the period mean (black). Lines near the noise carry no '
                'distortion; lines far above it show how strongly the system departs from '
                'linear at this level.', 'Distortion levels per line')
    return ''


def _robust_lpm_section(out: Path, frfs: Mapping[str, FrequencyResponse]) -> str:
    """Return the robust-LPM plot and summary of the first estimate with robust-LPM levels."""
    for name, frf in frfs.items():
        levels = frf.robust_lpm
        if levels is not None:
            robust_lpm_figure(levels, frf, out / 'robust_lpm.png', title=name)
            items = ''.join(f'<li>{html.escape(line)}</li>' for line in levels.summary())
            return f'<ul>{items}</ul>' + figure_tag(
                'robust_lpm.png',
                f'|P| of one multisine realisation ({levels.periods} periods; blue) with the '
                'standard deviation of its noise (black, from the spread over periods) and of '
                'its stochastic nonlinear distortion (red, from the local polynomial residual '
                'over neighbouring lines less the noise). Red above black: the nonlinear '
                'distortion, not the noise, limits this estimate; more periods will not '
                'lower it, more realisations will.', 'Robust LPM levels per line')
    return ''


def _snr_section(out: Path, frfs: Mapping[str, FrequencyResponse]) -> str:
    if figures.snr_figure(frfs, out / 'snr.png') is None:
        return ''
    return figure_tag('snr.png',
                      'Coherence-like signal-to-noise ratio per line, |P|\u00b2 / var(P) in dB. '
                      'Above 20 dB (dashed) the 1\u03c3 uncertainty is below 10 % of |P|; near '
                      '0 dB (dotted) the estimate is as large as its uncertainty. Dips usually '
                      'sit at anti-resonances or where friction or too little excitation hide the '
                      'dynamics.', 'SNR per line')


def _signals_section(out: Path, rec: Recording) -> str:
    unit = _common_units(rec)
    series = [('motor torque u', rec.effort, unit('effort', 'N m')),
              ('velocity y', rec.velocity, unit('velocity', 'rad/s'))]
    if rec.reference is not None and np.isfinite(rec.reference).any():
        series.append(('reference r', rec.reference, unit('reference', 'rad/s')))
    figures.timeseries_figure(rec.t, series, rec.joint_names, out / 'timeseries.png')
    units = rec.units
    note = (f' Units per joint (import map): {html.escape(str(units))}.' if units else '')
    return figure_tag('timeseries.png',
                      f'Applied motor torque, measured velocity and velocity reference of each '
                      f'joint over time.{note}', 'time series')


def _common_units(rec: Recording):
    """unit(signal, default): the unit all joints share per the import map, else default."""
    units = rec.units

    def unit(sig: str, default: str) -> str:
        found = {str(u.get(sig)) for u in units.values() if isinstance(u, dict) and u.get(sig)}
        return found.pop() if len(found) == 1 and len(units) == len(rec.joint_names) \
            else default
    return unit


def _spectrogram_section(out: Path, rec: Recording) -> str:
    f_hi = min(60.0, 0.5 * rec.fs)
    figures.spectrogram_figure(rec.effort, rec.fs, rec.joint_names, out / 'spectrogram.png',
                               f_range=(1.0, f_hi), t0=float(rec.t[0]),
                               unit=_common_units(rec)('effort', 'N m'))
    return figure_tag('spectrogram.png',
                      f'Power spectral density of the motor torques over time, 1\u2013{f_hi:g} Hz '
                      'on a log axis (as Fig. 3 of Saupe &amp; Knoblach 2015). A chirp is a '
                      'rising ridge; faint parallel ridges above it are harmonics from '
                      'nonlinearities; a multisine is a set of horizontal lines; broadband '
                      'vertical stripes are impacts or friction reversals.', 'torque spectrogram')


def _input_names(frfs: Mapping[str, FrequencyResponse], rec: Recording | None) -> list[str]:
    if rec is not None:
        return list(rec.joint_names)
    return list(next(iter(frfs.values())).inputs) if frfs else []


def _iteration_section(out: Path, iterations: Sequence[Mapping[str, Any]],
                       names: list[str]) -> str:
    try:
        errs = [figures.iteration_errors(it) for it in iterations]
    except KeyError as exc:
        raise FrfIdentInputError(f'write_report: {exc.args[0]}') from None
    tol = next((float(it['tolerance_db']) for it in iterations if 'tolerance_db' in it), None)
    figures.iteration_figure(iterations, out / 'iterations.png', names, tol)
    n = max(len(e) for e in errs)
    header = ['iteration'] + [names[c] if c < len(names) else f'channel {c}' for c in range(n)]
    rows = [[int(it['iteration'])] + [float(v) for v in e] for it, e in zip(iterations, errs)]
    return (figure_tag('iterations.png',
                       'Error of the measured plant input u to the desired u_des (dB, per '
                       'channel) after each iteration of the closed-loop excitation design '
                       '(Sec. 5.3, eq. 18). It should fall towards 0 dB; the paper needed six '
                       'iterations.', 'iteration convergence')
            + table(header, rows))


def _timing_section(t: Mapping[str, Any]) -> str:
    rate = 1.0 / t['dt_s'] if t.get('dt_s') else float('nan')
    facts = [['samples', t.get('n_samples')], ['sample rate [Hz]', rate],
             ['time span [s]', f"{num(t.get('t_start_s', float('nan')))} \u2013 "
                               f"{num(t.get('t_end_s', float('nan')))}"],
             ['time grid', t.get('grid')], ['resampled', t.get('resampled')]]
    parts = [table(['finding', 'value'], facts)]
    topics = t.get('topics') or {}
    if topics:
        rows = [[name, d.get('count'), d.get('rate_hz'), d.get('stamp_source'),
                 100 * float(d.get('jitter', 0.0)), d.get('gaps'), d.get('missing_samples'),
                 d.get('duplicates'), d.get('non_monotonic'),
                 None if d.get('header_log_offset_mean_s') is None
                 else 1e3 * d['header_log_offset_mean_s']]
                for name, d in topics.items()]
        parts.append(table(['topic', 'messages', 'rate [Hz]', 'stamps', 'jitter [% of dt]',
                            'gaps', 'missing samples', 'duplicates', 'non-monotonic',
                            'log - header [ms]'], rows))
    rec = t.get('recovery') or {}
    if rec.get('damaged'):
        parts.append(f'<p class="warn">Recovered a damaged or unfinished bag: '
                     f'{rec.get("bytes_lost", 0)} bytes and {rec.get("chunks_lost", 0)} chunks '
                     f'lost, messages lost: {html.escape(str(rec.get("messages_lost", "?")))}'
                     f'.</p>')
    warnings = t.get('warnings') or []
    if warnings:
        parts.append('<ul class="warn">' + ''.join(f'<li>{html.escape(str(w))}</li>'
                                                   for w in warnings) + '</ul>')
    else:
        parts.append('<p class="ok">No timing warnings.</p>')
    return '\n'.join(parts)


def _pm(value: float, std: float, scale: float = 1.0) -> str:
    """Return ``value +- std`` (4 significant digits, the error to 2) or the value alone."""
    if not math.isfinite(value):
        return str(value)
    sd = f' \u00b1 {std * scale:.2g}' if math.isfinite(std) else ''
    return f'{value * scale:.4g}{sd}'


def _verdict(cost) -> str:
    cls = 'warn' if cost.structure_missing else 'ok' if cost.weighted else 'muted'
    return (f'<p class="{cls}">{html.escape(cost.summary())}: '
            f'<b>{html.escape(cost.verdict)}</b></p>')


def _delay_row(name: str, delay_s: float, std_s: float, hold_s: float = 0.0) -> list[Any]:
    how = 'fitted' if math.isfinite(std_s) else 'given (--delay)'
    if not hold_s:
        return [name, f'delay ({how})', _pm(delay_s, std_s, 1e3), 'ms',
                _relative(delay_s, std_s)]
    return [name, f'time_delay ({how}; the whole delay {1e3 * delay_s:.4g} ms less the '
                  f"zero-order hold's {1e3 * hold_s:.4g} ms, as model.yaml)",
            _pm(max(delay_s - hold_s, 0.0), std_s, 1e3), 'ms', '\u2014']


def _relative(value: float, std: float) -> str:
    return f'{100 * abs(std / value):.2g}' if value and math.isfinite(std) else '\u2014'


def _physical_html(fits: Sequence[PhysicalFit], hold_s: float = 0.0) -> str:
    rows = []
    for f in fits:
        fa, fr = f.resonances_hz()
        rows += [[f.name, k, _pm(v, sd), UNITS[k], _relative(v, sd)]
                 for k, v, sd in zip(f.names, f.value, f.reported_std)]
        rows.append(_delay_row(f.name, f.delay_s, f.delay_reported_std_s, hold_s))
        rows.append([f.name, 'antiresonance / resonance', f'{fa:.4g} / {fr:.4g}', 'Hz', ''])
    verdicts = ''.join(f'<li>{html.escape(f.name)}: {_verdict(f.cost)}</li>' for f in fits)
    return (table(['axis', 'parameter', 'value \u00b1 standard error', 'unit',
                   'standard error [%]'], rows)
            + f'<p>Cost test per axis:</p><ul>{verdicts}</ul>')


def _coupled_html(fit: CoupledFit, hold_s: float = 0.0) -> str:
    rows = []
    for i, name in enumerate(fit.names):
        sd = fit.axis_std(i, reported=True)
        rows += [[name, k, _pm(v, sd[k]), UNITS[k], _relative(v, sd[k])]
                 for k, v in fit.axis_parameters(i).items()]
    c, csd = fit.link_coupling(reported=True)
    for i, j in zip(*np.triu_indices(len(fit.names), 1)):
        rows.append([f'{fit.names[i]} \u2013 {fit.names[j]}', 'link coupling',
                     _pm(c[i, j], csd[i, j]), 'kg m^2', _relative(c[i, j], csd[i, j])])
    rows.append(_delay_row('all axes', fit.delay_s, fit.delay_reported_std_s, hold_s))
    apart = ''.join(f'<li>{html.escape(line)}</li>' for line in fit.disagreements())
    return (table(['axis', 'parameter', 'value \u00b1 standard error', 'unit',
                   'standard error [%]'], rows)
            + '<p>Cost test of the coupled fit:</p>' + _verdict(fit.cost)
            + (f'<p>Per-axis fits (no coupling) against the coupled fit, beyond their '
               f'errors:</p><ul>{apart}</ul>' if apart else ''))


def _rational_html(fit: RationalFit) -> str:
    rows = [[_pm(m.frequency_hz, math.hypot(m.frequency_std_hz, m.frequency_bound_hz)),
             _pm(m.damping, math.hypot(m.damping_std, m.damping_bound)),
             'yes' if m.in_band else 'NO: not supported by the data'] for m in fit.modes()]
    stab = (f' The free ML fit had {fit.reflected} unstable pole(s); the model is the ML fit '
            f'over stable denominators.' if fit.reflected else '')
    return (f'<p>Order {fit.order} (poles), {fit.n_params} real parameters, '
            f'{fit.freq_hz.size} lines; the model is in model.mat (A, B, C, D).{stab}</p>'
            + table(['natural frequency \u00b1 SE [Hz]', 'damping ratio \u00b1 SE [-]',
                     'in the fitted band'], rows)
            + '<p>Cost test:</p>' + _verdict(fit.cost))


def _margins_html(check: LoopCheck) -> str:
    def m(v: Margin, note: str | None = None) -> str:
        return _pm(v.value, v.std) if math.isfinite(v.value) or note is None else note
    rows, edges = [], []
    for a in check.axes:
        notes = a.notes()
        rows.append([a.axis, a.kp, a.ki, m(a.gain_margin_db, notes.get('gain_margin_db')),
                     m(a.phase_margin_deg, notes.get('phase_margin_deg')),
                     m(a.modulus_margin), m(a.crossover_hz, notes.get('crossover_hz'))])
        if 'band_edge' in notes:
            edges.append(f'<li>{html.escape(a.axis)}: {html.escape(notes["band_edge"])}</li>')
    pi = (f'discrete at dt = {check.discrete_dt:g} s' if check.discrete_dt
          else 'continuous')
    text = (f'<p>L = C P-hat per axis on the measured FRF, velocity PI {pi}. Standard '
            f'deviations over {check.draws} draws of the FRF from its variance'
            + (' (none: the FRF has no variance).' if not check.draws else '.') + '</p>')
    text += table(['axis', 'kp [N m s/rad]', 'ki [N m/rad]', 'gain margin [dB]',
                   'phase margin [deg]', 'modulus margin [-]', 'crossover [Hz]'], rows)
    if edges:
        text += f'<ul class="warn">{"".join(edges)}</ul>'
    if check.peak_sensitivity is not None:
        text += (f'<p>MIMO: peak of the largest singular value of S = (I + P C)^-1: '
                 f'{_pm(check.peak_sensitivity.value, check.peak_sensitivity.std)}</p>')
    return text


def proposal_section(check: LoopCheck | None, target: tuple[float, float],
                     verdicts: Sequence[tuple[str, str, bool]]) -> tuple[str, str, str]:
    """
    Return the report section of proposed PI gains: their margins and the targets' verdicts.

    Parameters
    ----------
    check : LoopCheck or None
        The proposed gains checked on the measured FRF; None when the page's margins section
        already shows them (only ``--propose`` given).
    target : tuple of float
        (bandwidth [Hz], phase margin [deg]) asked for.
    verdicts : sequence of tuple
        (axis, 'targets met' or what is missed, met) per axis.

    Returns
    -------
    tuple of str
        (anchor, heading, html) as :func:`fit_sections` gives them.

    """
    items = ''.join(f'<li class="{"ok" if met else "warn"}">{html.escape(axis)}: '
                    f'{html.escape(text)}</li>' for axis, text, met in verdicts)
    body = (f'<p>PI gains read off the measured FRF for {target[1]:g} deg at {target[0]:g} '
            f'Hz, checked on the measured loop:</p><ul>{items}</ul>')
    if check is not None:
        body += _margins_html(check)
    return ('proposal', f'PI proposed for {target[1]:g} deg at {target[0]:g} Hz', body)


def fit_sections(*, physical: Sequence[PhysicalFit] = (), coupled: CoupledFit | None = None,
                 rational: RationalFit | None = None, check: LoopCheck | None = None,
                 fit_png: str | None = None, loop_png: str | None = None,
                 hold_s: float = 0.0) -> list[tuple[str, str, str]]:
    """
    Return the report sections of a fit and a controller check as (anchor, heading, html).

    Parameters
    ----------
    physical : sequence of PhysicalFit, optional
        Per-axis two-mass fits.
    coupled : CoupledFit, optional
        The coupled robot fit (its per-axis starts are not shown again).
    rational : RationalFit, optional
        The chosen rational fit.
    check : LoopCheck, optional
        Margins of the velocity PI on the measured FRF.
    fit_png, loop_png : str, optional
        File names (next to the page) of the fit figure and the loop figure.
    hold_s : float, optional
        The zero-order hold's half sample [s] of the model file: a fitted delay is shown as
        model.yaml's ``time_delay`` (the delay less it); 0: the whole delay.

    Returns
    -------
    list of tuple
        The sections, empty when nothing is given.

    """
    out = []
    if fit_png:
        out.append(('fit', 'Fitted model over the FRF', figure_tag(
            fit_png, 'Magnitude and phase of the measured FRF (dots) and the fitted model '
            '(line) per channel; bottom row: the residual per line in units of the standard '
            'deviation of the FRF, |P \u2212 P_fit| / \u03c3. A right model leaves it '
            'scattered about 1 (dashed), its squares summing to the chi-square expectation '
            'the cost test checks; a run of lines far above 1 is structure the model lacks.',
            'fitted model over the measured FRF')))
    params = ''
    if coupled is not None:
        params = _coupled_html(coupled, hold_s)
    elif physical:
        params = _physical_html(physical, hold_s)
    if rational is not None:
        params += _rational_html(rational)
    if params:
        out.append(('parameters', 'Fitted parameters (Cram\u00e9r-Rao standard errors, '
                                  'widened by the model-error bound where the cost test fails)',
                    params))
    if check is not None:
        body = _margins_html(check)
        if loop_png:
            body += figure_tag(loop_png, 'Bode plot of L = C P-hat per axis with the 95 % band '
                               'of the draws of the FRF, and its Nyquist curve with the circle '
                               'of the modulus margin around \u22121.', 'loop Bode and Nyquist')
        out.append(('margins', 'Margins of the measured loop', body))
    return out


def write_fit_report(path: str | Path, *, title: str,
                     sections: Sequence[tuple[str, str, str]]) -> Path:
    """
    Write the page of a fit and/or a controller check (sections of :func:`fit_sections`).

    Parameters
    ----------
    path : str or Path
        The page (its figures are next to it).
    title : str
        Page and heading title.
    sections : sequence of tuple
        (anchor, heading, html) of :func:`fit_sections`.

    Returns
    -------
    Path
        ``path``.

    """
    path = Path(path)
    path.write_text(page(title, list(sections), None))
    return path
