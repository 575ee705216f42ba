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
Detection of the excitation in a recording without descriptors, as segments, and its checks.

The excitation is detected in the data (:mod:`frf_ident.core.excitation.detect`): a periodic
multisine or an exponential chirp, on the velocity reference when the bag has one, else on
the torque (:func:`~frf_ident.core.excitation.detect_input.excitation_source`); what the
:class:`~frf_ident.core.estimation.excitation_options.ExcitationOptions` give replaces the
respective detection. Each detection of an excited input becomes a
:class:`~frf_ident.core.recording.Segment` (:func:`detect_segments`), checked before it is
estimated (:func:`check_detected_segment`). The two refusals of detection are here:
nothing found (:class:`NoExcitationError`, the LPM may estimate the record) and found but
unusable (:class:`UnusableExcitationError`, nothing may).
"""
from __future__ import annotations

from dataclasses import replace

from frf_ident.core.estimation.checks import (check_band, check_covers, check_not_clipped,
                                              check_periods, check_whole_period, JOINT_STATES)
from frf_ident.core.estimation.excitation_options import ExcitationOptions
from frf_ident.core.estimation.spectra import periodic_spectra
from frf_ident.core.excitation.detect import detect_excitation
from frf_ident.core.excitation.detect_input import excitation_source
from frf_ident.core.excitation.detection_results import ChirpDetection, MultisineDetection
from frf_ident.core.excitation.multisine_detect import multisine_at_period
from frf_ident.core.excitation.sweep_law import MAX_MISMATCH, sweep_mismatch
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import EstimationError
import numpy as np

__all__ = ['SWEEP_HINT', 'NoExcitationError', 'UnusableExcitationError', 'check_detected_segment',
           'detect_segments']

#: what works for a sweep the chirp estimator refuses (down, linear, another law): the LPM
#: needs no law (test/cli/test_estimate_sweep.py: a linear 15 -> 2 Hz sweep, analytic FRF)
SWEEP_HINT = ("method='lpm' (frf-ident estimate --method lpm) estimates a sweep of any law "
              'and direction')


class NoExcitationError(EstimationError):
    """No multisine or chirp found in a recording: the LPM may estimate it instead."""


class UnusableExcitationError(EstimationError):
    """
    An excitation was found but cannot be estimated (the message says what and why).

    E.g. a multisine whose period is not a whole number of samples. The LPM must not estimate
    such a record instead: its line spectrum leaves most LPM lines without excitation (a
    silent wrong FRF, issue 39), so the record is refused.
    """


def _given_chirp(opts: ExcitationOptions, fs: float) -> ChirpDetection:
    """Return the exponential chirp f(t) = exp(a0 t + a1) through (t0, f_low) and (t1, f_high)."""
    (f_low, f_high), (t0, t1) = opts.chirp, opts.chirp_time
    a0 = float(np.log(f_high / f_low) / (t1 - t0))
    return ChirpDetection(float(fs), float(f_low), float(f_high), float(t0), float(t1), a0,
                          float(np.log(f_low) - a0 * t0), 0, 0.0)


def _excitation_of(x: np.ndarray, fs: float, opts: ExcitationOptions
                   ) -> MultisineDetection | ChirpDetection:
    """Return the excitation of one channel: from the options where given, else detected."""
    if opts.chirp is not None:
        return _checked_chirp(x, fs, _given_chirp(opts, fs), 'the given chirp')
    if opts.multisine_period is not None:
        return multisine_at_period(x, fs, opts.multisine_period, band=opts.band)
    det = detect_excitation(x, fs)
    if isinstance(det, ChirpDetection):
        det = _checked_chirp(x, fs, det, 'the detected chirp')
    if opts.band is not None:
        if not isinstance(det, MultisineDetection):
            raise EstimationError(f'band={opts.band} restricts multisine lines but a chirp was '
                                  f'detected ({det.describe()})')
        f = det.freq_hz
        keep = (f >= opts.band[0]) & (f <= opts.band[1])
        if not np.any(keep):
            raise EstimationError(f'band={opts.band}: none of the {f.size} detected lines '
                                  f'{f[0]:.4g}-{f[-1]:.4g} Hz lies inside')
        det = replace(det, harmonics=det.harmonics[keep],
                      odd=bool(np.all(det.harmonics[keep] % 2 == 1)))
    return det


def _checked_chirp(x: np.ndarray, fs: float, det: ChirpDetection, what: str
                   ) -> ChirpDetection:
    """Refuse a down-sweep, or a chirp whose law the recorded excitation does not follow."""
    law = (f'{what} {det.f_low:.4g} -> {det.f_high:.4g} Hz over {det.t0:.4g}-{det.t1:.4g} s '
           f'(exponential, eq. 16)')
    if not det.f_high > det.f_low:
        raise EstimationError(f'{law} sweeps down; the chirp estimator needs an up-sweep '
                              f'(f_low < f_high) — {SWEEP_HINT}')
    dev, found = sweep_mismatch(x, fs, det.frequency, det.t0, det.t1)
    if not dev <= MAX_MISMATCH:
        seen = found.describe() if found is not None else 'no sweep in that interval'
        raise EstimationError(f'{law} does not match the recorded excitation: it is a {seen}; '
                              f'its half cycles are {100 * dev:.3g} % off the given law '
                              f'(median; expected < {100 * MAX_MISMATCH:.0f} %) — {SWEEP_HINT}')
    return det


def _describe(det: MultisineDetection | ChirpDetection, opts: ExcitationOptions) -> str:
    """Return the detection sentence, marked where options replaced detection."""
    if opts.chirp is not None:
        return (f'exponential chirp {det.f_low:.6g}-{det.f_high:.6g} Hz from t0 = '
                f'{det.t0:.6g} s to t1 = {det.t1:.6g} s, sweep rate a0 = {det.a0:.4g} 1/s '
                f'(given)')
    text = det.describe()
    if opts.multisine_period is not None:
        text += f' (period given: {opts.multisine_period:g} s)'
    if opts.band is not None:
        text += f' (lines restricted to {opts.band[0]:g}-{opts.band[1]:g} Hz)'
    return text


def detect_segments(rec: Recording, options: ExcitationOptions | None = None
                    ) -> tuple[list[Segment], list[str]]:
    """
    Detect the excitation per joint.

    Detect the excitation per joint (or take it from ``options``); returns segments and
    one sentence per detection.

    Parameters
    ----------
    rec : Recording
        The recording, without experiment descriptors.
    options : ExcitationOptions, optional
        What is known about the excitation; default None: detect everything.

    Returns
    -------
    segments : list of Segment
        One segment per excited input, ``info['design']`` 'detected_multisine' or
        'detected_chirp' with the detected parameters and the input's column index.
    notes : list of str
        One sentence per detection, and why joints were passed over.

    Raises
    ------
    EstimationError
        The options are refused, or no multisine or chirp is found in any joint (or in the
        given input).

    """
    opts = options or ExcitationOptions()
    opts.check(rec)
    x, source = excitation_source(rec.reference, rec.effort)
    fs = rec.fs
    present = np.isfinite(x)
    level = np.array([np.std(x[present[:, j], j]) if np.any(present[:, j]) else 0.0
                      for j in range(x.shape[1])])
    found: list[tuple[int, MultisineDetection | ChirpDetection]] = []
    notes: list[str] = []
    order = ([rec.joint_names.index(opts.input)] if opts.input is not None
             else np.argsort(level)[::-1])
    for j in order:
        if opts.input is None and level[j] < 1e-3 * level.max():
            continue
        try:
            det = _excitation_of(x[:, j], fs, opts)
        except EstimationError as exc:
            if opts.input is not None:
                raise NoExcitationError(f'input={opts.input!r} ({source}): {exc}') from None
            notes.append(f'{rec.joint_names[j]}: no excitation found in the {source} ({exc})')
            continue
        strongest = _strongest_channel(x, det, fs)
        if opts.input is None and strongest != j:
            notes.append(f'{rec.joint_names[j]}: follows the excitation of '
                         f'{rec.joint_names[strongest]} (coupling), not an input')
            continue
        found.append((int(j), det))
        notes.append(f'{rec.joint_names[j]} ({source}): {_describe(det, opts)}')
    if not found and opts.given():
        raise EstimationError(f'the given excitation ({opts.text()}) fits the {source} of '
                              f'no joint ({"; ".join(notes) or "no joint moves"})')
    if not found:
        raise NoExcitationError(f'no multisine or chirp found in the {source} of any joint '
                                f'({"; ".join(notes) or "no joint moves"}); pass the '
                                f'experiment descriptors or the excitation as options')
    return [_segment(rec, j, det) for j, det in found], notes


def _segment(rec: Recording, j: int, det: MultisineDetection | ChirpDetection) -> Segment:
    """Return the segment of a detection of input j (its parameters in ``info``)."""
    fs = rec.fs
    if isinstance(det, MultisineDetection):
        i0 = det.start
        info = {'design': 'detected_multisine', 'input': j, 'period_samples':
                det.period_samples, 'periods': det.n_periods, 'start': int(i0),
                'harmonics': np.asarray(det.harmonics).tolist(), 'f0': det.f0,
                'drift': float(det.drift)}
        t1 = rec.t[0] + (i0 + det.n_periods * det.period_samples) / fs
    else:
        info = {'design': 'detected_chirp', 'input': j, 'f_low': det.f_low,
                'f_high': det.f_high, 't0': det.t0, 't1': det.t1, 'a0': det.a0,
                'a1': det.a1}
        i0 = int(round(det.t0 * fs))
        t1 = rec.t[0] + det.t1
    return Segment(rec.t[0] + i0 / fs, t1, info)


def check_detected_segment(rec: Recording, seg: Segment) -> None:
    """
    Check a detected segment before it is estimated.

    Band below Nyquist, at least two whole periods (multisine) or the sweep inside the
    data (chirp), and no clipped torque in the segment: refused with one line otherwise.

    Parameters
    ----------
    rec : Recording
        The recording the segment was detected in.
    seg : Segment
        A segment from :func:`detect_segments`.

    Raises
    ------
    EstimationError
        One of the checks fails.

    """
    info = seg.info
    name = rec.joint_names[info['input']]
    if info['design'] == 'detected_multisine':
        what = f'detected multisine of {name} ({seg.t_start:.3f}..{seg.t_end:.3f} s)'
        check_band(np.asarray(info['harmonics']) * info['f0'], rec.fs, where=what)
        check_periods(int(info['periods']), need=2, where=what,
                      hint='record more periods or give a shorter multisine period')
        check_whole_period(float(info.get('drift', 0.0)), int(info['period_samples']),
                           where=what)
    else:
        what = f'chirp of {name} ({seg.t_start:.3f}..{seg.t_end:.3f} s)'
        check_band([info['f_low'], info['f_high']], rec.fs, where=what)
        check_covers(rec.t[0], rec.t[-1], seg.t_start, seg.t_end, dt=rec.dt, where=what)
    check_not_clipped(rec.effort[rec.slice(seg.t_start, seg.t_end)],
                      joint_names=rec.joint_names, where=JOINT_STATES, span=f'the {what}')


def _strongest_channel(x: np.ndarray, det: MultisineDetection | ChirpDetection,
                       fs: float) -> int:
    """Return the channel with the most power at the detected excitation (lines or sweep)."""
    # missing samples (NaN in every channel alike) count as zero in this comparison only
    if isinstance(det, MultisineDetection):
        seg = np.nan_to_num(x[det.start:det.start + det.period_samples])
        p = np.abs(periodic_spectra(seg, np.asarray(det.harmonics), axis=0)) ** 2
        return int(np.argmax(p.sum(axis=0)))
    i0, i1 = int(det.t0 * fs), int(det.t1 * fs)
    return int(np.argmax(np.std(np.nan_to_num(x[i0:i1]), axis=0)))
