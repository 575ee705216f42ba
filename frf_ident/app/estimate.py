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
Offline FRF estimation from a bag: every estimate the bag supports, written to a directory.

Bags that would not fit the memory budget are read window by window
(:mod:`frf_ident.app.stream_estimate`); both paths give the same estimates.
"""
from __future__ import annotations

import json
from pathlib import Path

from frf_ident.app import stream_estimate
from frf_ident.app.outdir import clear_outputs
from frf_ident.core.progress import Progress, sink
from frf_ident.errors import FrfIdentInputError
import numpy as np

__all__ = ['OUTPUT_FILES', 'dropped_text', 'estimate_bag', 'estimate_columns', 'frf_units',
           'missing_lines',
           'read_estimates', 'report_distortion', 'report_robust_lpm']

#: the files :func:`estimate_bag` writes into its output directory
OUTPUT_FILES = ('frf.json', 'estimates.json', 'summary.json', 'bode.png', 'distortion.png',
                'robust_lpm.png')


def read_estimates(bag: Path, joints, t_range, options, stream: bool | None, max_memory_mb,
                   window_s: float | None, progress: Progress):
    """
    Read the bag (in memory or streamed) and estimate.

    Parameters
    ----------
    bag : Path
        Bag directory or .mcap file.
    joints : list of str or None
        Joint names to analyse; None: all joints of the first joint state message.
    t_range : tuple of float or None
        (start, end) in s of the bag clock: analyse only this time range; None: all of it.
    options : ExcitationOptions or None
        :class:`~frf_ident.core.estimation.excitation_options.ExcitationOptions` replacing
        detection in bags without experiment descriptors; None: detect the excitation.
    stream : bool or None
        True: read window by window; False or None: only when the bag would exceed the
        memory budget.
    max_memory_mb : float or None
        Memory budget of the in-memory reader in MB (> 0); None: a quarter of the physical
        memory, at most 4 GiB (:func:`~frf_ident.app.stream_estimate.default_memory_budget`).
    window_s : float or None
        Block length in s (> 0) for bags without experiment descriptors; None: the
        default :data:`~frf_ident.core.estimation.detected.DEFAULT_WINDOW_S`.
    progress : callable
        Called with one line of text per step.

    Returns
    -------
    tuple
        (estimates by name, timing report, experiment summary, streaming stats or None).

    """
    if max_memory_mb is not None and not max_memory_mb > 0:
        raise FrfIdentInputError(f'--max-memory {max_memory_mb}: expected a size in MB > 0')
    if window_s is not None and not window_s > 0:
        raise FrfIdentInputError(f'--window {window_s}: expected a block length in s > 0')
    budget = stream_estimate.default_memory_budget() if max_memory_mb is None else \
        int(max_memory_mb * (1 << 20))
    if stream or stream_estimate.needs_streaming(bag, budget):
        res = stream_estimate.stream_estimate(bag, joints=joints, t_range=t_range,
                                              window_s=window_s, options=options,
                                              progress=progress)
        st = res.stats
        progress(f'streamed {sum(st.messages.values())} messages in {st.windows} windows, '
                 f'at most {st.peak_rows} held at once')
        return res.estimates, res.timing, res.summary, {
            'windows': st.windows, 'peak_rows': st.peak_rows, 'messages': st.messages,
            'budget_bytes': budget}
    from frf_ident.bag import read_recording
    from frf_ident.core.estimation.channels import (check_joints, experiment_joints,
                                                    joint_channels)
    from frf_ident.core.estimation.described import estimate_recording
    from frf_ident.errors import FrfIdentInputError as InputError
    if joints is not None:
        check_joints(joints)
    try:
        rec, timing = read_recording(bag, t_range=t_range)
    except InputError:
        if joints is None:
            raise
        # a joint not asked for is unreadable (inf, say): the asked ones alone, as before
        rec, timing = read_recording(bag, joints=joints, t_range=t_range)
    for line in timing.summary():
        progress(line)
    if joints is None:
        return (estimate_recording(rec, options=options, window_s=window_s), timing,
                rec.summary, None)
    check_joints(joints, rec.joint_names)
    # every joint the experiments excited takes part; the wanted channels are picked
    part = rec.select_joints(experiment_joints(rec, joints))
    est = estimate_recording(part, options=options, window_s=window_s)
    return ({k: joint_channels(v, joints) for k, v in est.items()}, timing,
            rec.summary, None)


def estimate_bag(bag: Path, out: Path, *, joints=None, t_range=None, primary=None,
                 options=None, stream: bool | None = None, max_memory_mb: float | None = None,
                 window_s: float | None = None, fit=None,
                 progress: Progress | None = None) -> dict:
    """
    Estimate every FRF the bag supports; write frf.json, estimates.json, summary.json, bode.png.

    With ``fit``, :func:`frf_ident.app.fit.fit_frf` (what ``frf-ident fit`` runs) then fits a
    model to the frf.json just written and writes its files into ``out`` too.

    Parameters
    ----------
    bag
        Bag directory or .mcap file.
    out
        Output directory (created; untouched when the bag is refused). Its
        :data:`OUTPUT_FILES` of an earlier run are removed before the new ones are written.
    joints
        Joint names to analyse (default: all).
    t_range
        (start, end) in s: analyse only this time range.
    primary
        Which estimate goes to frf.json (default: multisine, else chirp).
    options : :class:`~frf_ident.core.estimation.excitation_options.ExcitationOptions` replacing
        detection in bags without experiment descriptors.
    stream
        Read window by window; None: only when the bag exceeds ``max_memory_mb``.
    max_memory_mb
        Memory budget of the in-memory reader (default: a quarter of RAM).
    window_s
        Block length for bags without experiment descriptors [s]; None: the default
        :data:`~frf_ident.core.estimation.detected.DEFAULT_WINDOW_S`.
    fit : :class:`~frf_ident.app.fit.FitOptions`, optional
        Fit a model to frf.json with these options (``estimate --fit``); None: no fit.
    progress
        Called with one line per step; None: silent.

    Returns
    -------
    dict
        Estimate name -> :class:`~frf_ident.core.estimation.frd.FrequencyResponse`.

    Raises
    ------
    EstimationError
        The data do not support an estimate (the message names the bag).

    """
    from frf_ident.errors import DesignError, EstimationError
    from frf_ident.report.figures import bode_figure
    progress = sink(progress)
    try:
        estimates, timing, experiment, streamed = read_estimates(
            bag, joints, t_range, options, stream, max_memory_mb, window_s, progress)
    except (EstimationError, DesignError) as exc:      # every refusal names the bag
        raise EstimationError(f'{bag}: {exc}') from None
    if streamed is not None:
        for line in timing.summary():
            progress(line)
    first = next(iter(estimates.values())).notes
    for line in first.get('detected', []):
        progress(f'detected: {line}')
    for line in first.get('left_out', []):
        progress(f'left out: {line}')
    for k, v in estimates.items():
        if 'transient' in v.notes:
            progress(f'{k}: {v.notes["transient"]}')
    key = primary or ('multisine' if 'multisine' in estimates else next(iter(estimates)))
    if key not in estimates:
        raise FrfIdentInputError(f'--primary {key!r}: the bag supports {sorted(estimates)}')
    out.mkdir(parents=True, exist_ok=True)
    clear_outputs(out, OUTPUT_FILES)
    frf = estimates[key]
    doc = frf.to_dict()
    doc['estimate'] = key
    (out / 'frf.json').write_text(json.dumps(doc))
    (out / 'estimates.json').write_text(json.dumps({k: v.to_dict()
                                                    for k, v in estimates.items()}))
    dropped = {k: v.dropped for k, v in estimates.items() if v.dropped}
    for k, d in dropped.items():
        line = dropped_text(d)
        if line:
            progress(f'{k}: {line}')
    missing = {k: v.missing.to_dict() for k, v in estimates.items() if v.missing}
    for line in missing_lines(estimates):
        progress(line)
    summary = {'bag': str(bag), 'primary': key, 'estimates': sorted(estimates),
               'timing': timing.to_dict(), 'experiment': experiment, 'streaming': streamed,
               'gaps': timing.missing, 'dropped': dropped, 'missing': missing}
    (out / 'summary.json').write_text(json.dumps(summary, indent=1, default=str))
    shown = ('multisine', 'chirp', 'lpm', 'lpm_h1')
    pairs = [(k, v) for k, v in estimates.items() if k in shown]
    bode_figure(dict(pairs or [(key, frf)]), out / 'bode.png',
                title=f'{bag.name}: {" vs ".join(k for k, _ in pairs) or key}',
                units=frf_units(frf))
    # the folder once, the files by name (a deep output folder made 250-character lines)
    progress(f'wrote frf.json ({key}: {frf.noutputs}x{frf.ninputs} channels, '
             f'{frf.freq_hz.size} lines) and bode.png in {out}')
    report_distortion(estimates, out, title=bag.name, progress=progress)
    report_robust_lpm(estimates, out, title=bag.name, progress=progress)
    if fit is not None:
        from frf_ident.app.fit import fit_frf
        fit_frf(out, out, **vars(fit), progress=progress)
    return estimates


def report_robust_lpm(estimates: dict, out: Path | None = None, *, title: str = '',
                      progress: Progress | None = None) -> Path | None:
    """
    Print one line per output of the robust LPM and write robust_lpm.png.

    The robust LPM (one multisine realisation, several periods) puts the per-line noise and
    nonlinear variances in each estimate's meta['robust_lpm'] (estimates.json); the figure
    shows the first such estimate's |P| with both levels per line.

    Parameters
    ----------
    estimates : dict
        Estimate name -> FrequencyResponse.
    out : Path, optional
        Output directory of robust_lpm.png; None: print only.
    title : str, optional
        Figure title (the bag's name).
    progress : callable, optional
        Called with one line per output (None: silent).

    Returns
    -------
    Path or None
        The PNG, or None when no estimate carries robust-LPM levels (or ``out`` is None).

    """
    from frf_ident.report.distortion import robust_lpm_figure
    progress = sink(progress)
    found = [(k, v, v.robust_lpm) for k, v in estimates.items() if v.robust_lpm is not None]
    for k, _, levels in found:
        for line in levels.summary():
            progress(f'{k} robust LPM: {line}')
    if not found or out is None:
        return None
    k, frf, levels = found[0]
    path = robust_lpm_figure(levels, frf, out / 'robust_lpm.png', title=f'{title}: {k}')
    progress(f'wrote {path.name} (|P| with its noise and nonlinear level per line, {k})')
    return path


def report_distortion(estimates: dict, out: Path, *, title: str,
                      progress: Progress | None = None) -> Path | None:
    """
    Print one distortion line per output and write distortion.png (multisine estimates).

    The per-line levels are in each estimate's meta['distortion'] (estimates.json).

    Parameters
    ----------
    estimates : dict
        Estimate name -> FrequencyResponse.
    out : Path
        Output directory.
    title : str
        Figure title (the bag's name).
    progress : callable, optional
        Called with one line per output (None: silent).

    Returns
    -------
    Path or None
        The PNG, or None when no estimate carries distortion levels.

    """
    from frf_ident.report.distortion import distortion_figure
    progress = sink(progress)
    found = [(k, v.distortion) for k, v in estimates.items() if v.distortion is not None]
    for line in distortion_table(found):
        progress(line)
    if not found:
        return None
    k, levels = found[0]
    path = distortion_figure(levels, out / 'distortion.png', title=f'{title}: {k}')
    progress(f'wrote {path.name} (output levels at excited, odd and even lines of {k})')
    return path


def distortion_table(found: list) -> list[str]:
    """
    Return the distortion levels of several estimates as one small table for the console.

    One row per estimate and output: the median level of the odd and even detection lines
    and of the excited lines over the noise [dB]; estimates without a noise level (one
    period) get their summary sentence instead.
    """
    rows, one_period = [], []
    for k, levels in found:
        if levels.noise is None:
            one_period += [f'{k} distortion: {line}' for line in levels.summary()]
            continue
        lv = [levels.above_noise_db(x) for x in ('odd', 'even', 'excited')]
        rows += [(k, name, *(f'{x[i]:+.1f}' for x in lv))
                 for i, name in enumerate(levels.outputs)]
    if not rows:
        return one_period
    levels = next(v for _, v in found if v.noise is not None)
    n_odd, n_even = (int(np.sum(levels.kind == x)) for x in ('odd', 'even'))
    head = ('estimate', 'output', 'odd', 'even', 'excited')
    w = [max(len(r[c]) for r in rows + [head]) for c in range(len(head))]
    table = ['  ' + '  '.join(v.ljust(w[c]) if c < 2 else v.rjust(w[c]) for c, v in enumerate(r))
             for r in [head] + rows]
    return [f'distortion above the noise [dB], median over {n_odd} odd and {n_even} even '
            f'lines ({levels.freq_hz[0]:.3g}-{levels.freq_hz[-1]:.3g} Hz) and the excited lines:'
            ] + table + one_period


def frf_units(frf) -> str | None:
    """
    Return the unit of P for the Bode axis, '(out)/(in)'; None when it is not one unit.

    Parameters
    ----------
    frf : FrequencyResponse
        An estimate; its meta['units'] ({'input', 'outputs'}) says the units.

    Returns
    -------
    str or None
        e.g. '(m/s^2)/(N)'; the sensor_msgs/JointState units of a revolute joint,
        '(rad/s)/(N m)', where the estimate names none; None where the outputs' (or the
        inputs') units differ, so no single unit labels the axis.

    """
    from frf_ident.core.recording import JOINT_STATE_FRF_UNIT
    u = frf.units
    if not u:
        return JOINT_STATE_FRF_UNIT
    outs = set(u.get('outputs') or [''])
    out, inp = outs.pop(), u.get('input', '')
    return f'({out})/({inp})' if out and inp and not outs else None


def estimate_columns(bag: Path, out: Path, progress: Progress | None, **options
                     ) -> dict:
    """
    Estimate one bag of a campaign (:func:`estimate_bag`) and return its summary columns.

    The task :func:`frf_ident.app.campaign.run_campaign` maps over the bags: the estimates
    stay in ``out`` (frf.json ...), the worker returns only these few numbers.

    Parameters
    ----------
    bag : Path
        Bag directory or .mcap file.
    out : Path
        Its output folder.
    progress : callable
        Called with one line per step (the bag's log).
    **options
        The keyword arguments of :func:`estimate_bag`.

    Returns
    -------
    dict
        ``primary`` (estimate in frf.json), ``estimates`` (all, joined by +), ``channels``
        (outputs x inputs), ``lines`` and ``f_min_hz`` / ``f_max_hz`` of the primary
        estimate; per excited joint J (an input that is also an output) its
        ``resonance_hz_J`` and ``antiresonance_hz_J``
        (:func:`~frf_ident.core.estimation.resonance.axis_modes`); per joint
        ``pose_rad_J`` when the bag was recorded at a pose (``identify --poses``).

    """
    from frf_ident.core.estimation.resonance import axis_modes
    est = estimate_bag(bag, out, progress=progress, **options)
    key = json.loads((out / 'frf.json').read_text())['estimate']
    frf = est[key]
    cols = {'primary': key, 'estimates': '+'.join(sorted(est)),
            'channels': f'{frf.noutputs}x{frf.ninputs}', 'lines': int(frf.freq_hz.size),
            'f_min_hz': round(float(frf.freq_hz.min()), 4),
            'f_max_hz': round(float(frf.freq_hz.max()), 4)}
    # channels are named 'tau_m/joint_1' -> 'dq_m/joint_1': the joint is the last part
    ins = [c.rsplit('/', 1)[-1] for c in frf.inputs]
    outs = [c.rsplit('/', 1)[-1] for c in frf.outputs]
    pose = json.loads((out / 'summary.json').read_text())['experiment'].get('pose_rad')
    if pose is not None and len(pose) == len(outs):
        cols.update({f'pose_rad_{j}': q for j, q in zip(outs, pose)})
    own = [j for j in ins if j in outs]
    if own:
        sq = frf.response[np.ix_([outs.index(j) for j in own], [ins.index(j) for j in own])]
        modes = axis_modes(frf.freq_hz, sq)
        for j, r, a in zip(own, modes.resonance_hz, modes.antiresonance_hz):
            cols[f'resonance_hz_{j}'] = round(float(r), 4)
            cols[f'antiresonance_hz_{j}'] = round(float(a), 4)
    return cols


def missing_lines(estimates: dict) -> list[str]:
    """
    One line per estimate whose record's missing samples were estimated (each text once).

    Parameters
    ----------
    estimates : dict
        Estimate name -> FrequencyResponse; meta['missing'] is a
        :class:`~frf_ident.core.estimation.missing.MissingSamples` dict.

    Returns
    -------
    list of str
        e.g. 'detected/joint_2: 2700 missing samples (5.5 %) in 6 of 6 periods estimated
        from the other periods and kept; sd of the estimates: tau_m/joint_2 0.064 N m ...';
        an estimate whose line equals the one before it is named there.

    """
    from frf_ident.core.recording import JOINT_STATE_UNITS
    texts: dict[str, list[str]] = {}
    for k, v in estimates.items():
        acc = v.missing
        if acc is None:
            continue
        u = v.units
        units = {c: (u.get('input') or JOINT_STATE_UNITS['effort']) if c.startswith('tau_m/')
                 else JOINT_STATE_UNITS['velocity'] for c in acc.channels}
        for c, unit in zip(v.outputs, u.get('outputs') or []):
            units[c] = unit or units.get(c, '')
        texts.setdefault(acc.text(units), []).append(k)
    return [f'{", ".join(names)}: {text}' for text, names in texts.items()]


def dropped_text(d: dict) -> str:
    """
    One line saying what gaps removed from an estimate (its meta['dropped']), '' if nothing.

    Parameters
    ----------
    d
        {'periods', 'items' | 'times'} of a multisine or {'lines', 'freq_hz'} of a chirp.

    Returns
    -------
    str
        e.g. '2 periods dropped for gaps (realisation 0 period 1 at 28.43..31.50 s, ...)'.

    """
    if d.get('lines'):
        f = ', '.join(f'{x:.4g}' for x in d['freq_hz'][:8])
        more = ' ...' if len(d['freq_hz']) > 8 else ''
        return f'{d["lines"]} analysis lines dropped for gaps in their excerpts ({f}{more} Hz)'
    if not d.get('periods'):
        return ''
    if 'items' in d:
        seen, parts = set(), []
        for it in d['items']:
            k = (it['realisation'], it['period'])
            if k not in seen:
                seen.add(k)
                parts.append(f'realisation {k[0]} period {k[1]} at '
                             f'{it["t_start"]:.2f}..{it["t_end"]:.2f} s')
        cut = d.get('incomplete') or []
        gone = [p for p in d.get('realisations') or [] if p not in cut]
        tail = f'; realisation(s) {gone} left without a period' if gone else ''
        if cut and not parts:     # nothing lost to gaps: the periods went with the cut
            return (f'{d["periods"]} multisine period(s) dropped: realisation(s) {cut} cut '
                    'short (a segment missing, never ended or only partly recorded) left '
                    f'out{tail}')
        if cut:
            tail += (f'; realisation(s) {cut} cut short (a segment missing, never ended or '
                     'only partly recorded) left out')
    else:
        parts = [f'{a:.2f}..{b:.2f} s' for a, b in d.get('times', [])]
        tail = ''
    more = ' ...' if len(parts) > 6 else ''
    return (f'{d["periods"]} multisine period(s) dropped for gaps ({", ".join(parts[:6])}'
            f'{more}){tail}')
