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
Estimation from recordings that carry no experiment descriptors (foreign bags, imports).

The excitation is detected in the data (:mod:`frf_ident.core.excitation.detect`): a periodic
multisine or an exponential chirp, on the velocity reference when the bag has one, else on
the torque (:func:`~frf_ident.core.excitation.detect.excitation_source`).
Where neither is found (PRBS, noise, normal motion) the Local Polynomial Method estimates
the FRF instead (:mod:`frf_ident.core.estimation.nonperiodic`).
Each detection becomes a :class:`~frf_ident.core.recording.Segment`, and the FRF is estimated
column by column for the excited inputs (one experiment cannot separate simultaneously excited
inputs that share lines, so those are refused with the reason).

What detection would find can also be given (:class:`ExcitationOptions`, the options of
`frf-ident estimate`): the excited joint, a multisine period (and the band of its lines), or a
chirp's band and sweep times; the given parts replace the respective detection.

Missing samples (NaN rows of a recording read with ``gaps='mark'``) cost only what they
touch: a multisine period holding one is dropped, as is a chirp analysis frequency whose
excerpt holds one; the estimate's meta lists what was dropped, and the estimate is refused
only when fewer than two periods (or no line) remain.

A recording is estimated block by block (:func:`estimate_in_blocks`, blocks of
``DEFAULT_WINDOW_S``), in memory (:class:`RecordingBlocks`) and when a bag is streamed alike,
so both take the same decisions whatever the size of the bag.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable, Iterable, Iterator

from frf_ident.core.estimation.checks import (check_band, check_covers, check_not_clipped,
                                              check_periods, check_remaining, check_whole_period,
                                              JOINT_STATES, missing_rows)
from frf_ident.core.estimation.distortion import distortion_lines
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.lpm import default_half_width, DEFAULT_ORDER, robust_lpm_periods
from frf_ident.core.estimation.missing_periodic import (fill_steady_periods, FilledPeriods,
                                                        GAP_HINT)
from frf_ident.core.estimation.nonperiodic import LpmBlocks
from frf_ident.core.estimation.spectra import periodic_spectra
from frf_ident.core.estimation.transient import steady_periods, SteadyState
from frf_ident.core.excitation.chirp import ChirpDesign
from frf_ident.core.excitation.chirp_dft import chirp_analysis_frequencies, chirp_spectra
from frf_ident.core.excitation.detect import (ChirpDetection, detect_excitation, detect_multisine,
                                              excitation_source, multisine_at_period,
                                              MultisineDetection)
from frf_ident.core.excitation.multisine import reference_frequency_set
from frf_ident.core.excitation.sweep_law import MAX_MISMATCH, sweep_mismatch
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import EstimationError
import numpy as np

__all__ = ['DEFAULT_WINDOW_S', 'DEFAULT_WINDOW_SAMPLES', 'LPM_METHODS', 'MIN_ADVANCE_S',
           'DetectedEstimator', 'ExcitationOptions', 'NoExcitationError', 'RecordingBlocks',
           'UnusableExcitationError', 'window_length', 'check_detected_segment',
           'check_not_periodic', 'detect_segments', 'detected_frf', 'estimate_in_blocks']

#: block length [s] in which recordings without descriptors are detected and estimated (in
#: memory and streamed alike): a few multisine periods or a whole chirp must fit in one block.
#: Defined here only: every signature above (app, cli) takes ``window_s=None`` and
#: :func:`window_length` resolves it.
DEFAULT_WINDOW_S = 300.0
#: ... and a block holds at least this many samples: 300 s at the 1 kHz the default was set
#: for (a block's memory and a period's length in samples scale with the samples, not the
#: seconds). A record sampled slower gets a longer block: the DaISy arm at 1 s per sample is
#: one block of its 1024 samples, where 300 s cut it into four that each held a wrong period
DEFAULT_WINDOW_SAMPLES = 300_000

#: a block that used data up to t starts the next block there (no period lost at the
#: boundary), unless t is less than this far [s] into the block (the scan must move on)
MIN_ADVANCE_S = 0.5

#: the methods that force the LPM without detecting (ExcitationOptions.method): the indirect
#: estimate through r where r is recorded, or the direct one of y on u
LPM_METHODS = ('lpm', 'lpm-direct')

#: fewest multisine periods an estimate needs (mean and noise variance over periods)
MIN_PERIODS = 2

#: what works for a sweep the chirp estimator refuses (down, linear, another law): the LPM
#: needs no law (test/cli/test_estimate_sweep.py: a linear 15 -> 2 Hz sweep, analytic FRF)
SWEEP_HINT = ("method='lpm' (frf-ident estimate --method lpm) estimates a sweep of any law "
              'and direction')


@dataclass(frozen=True)
class ExcitationOptions:
    """
    What is known about the excitation of a recording without descriptors; None: detect.

    Parameters
    ----------
    input : str, optional
        Name of the excited joint (the only input analysed).
    multisine_period : float, optional
        Multisine period [s]; the periodic block and lines are found in the data.
    band : tuple of float, optional
        (f_low, f_high) [Hz]; only multisine lines inside are analysed.
    chirp : tuple of float, optional
        (f_low, f_high) [Hz] of an exponential chirp (eq. 16); needs ``chirp_time``.
    chirp_time : tuple of float, optional
        (t0, t1) [s] of the sweep, counted from the first analysed sample (as the
        detection reports them).
    method : str, optional
        'lpm': the excitation is not periodic, estimate with the Local Polynomial Method
        (:mod:`frf_ident.core.estimation.nonperiodic`) without detecting; 'lpm-direct': the
        same, the direct estimate of y on u even where the reference r is recorded (biased
        towards -1/C where noise is fed back; for a reference that does not excite the band);
        None: detect, and use the LPM only where no multisine or chirp is found.

    """

    input: str | None = None  # noqa: A003
    multisine_period: float | None = None
    band: tuple[float, float] | None = None
    chirp: tuple[float, float] | None = None
    chirp_time: tuple[float, float] | None = None
    method: str | None = None

    def given(self) -> bool:
        """
        Return true when any option is set.

        Returns
        -------
        bool
            False when every option is None (detect everything).

        """
        return any(v is not None for v in (self.input, self.multisine_period, self.band,
                                           self.chirp, self.chirp_time, self.method))

    def text(self) -> str:
        """
        Return the given options as 'name=value' pairs.

        Returns
        -------
        str
            Comma-separated ``name=value`` of the options that are not None (for messages).

        """
        return ', '.join(f'{k}={v!r}' for k, v in vars(self).items() if v is not None)

    def check(self, rec: Recording) -> None:
        """
        Refuse options that contradict each other or the recording (one line each).

        Parameters
        ----------
        rec : Recording
            The recording the options are for (joint names, sample rate, duration).

        Raises
        ------
        EstimationError
            An unknown input joint, both a chirp and a multisine period, a chirp without
            sweep times (or the reverse), a band with a chirp, a band or chirp frequency at
            or above Nyquist, fewer than two periods in the recording, or sweep times outside
            it.

        """
        if self.method not in (None, *LPM_METHODS):
            raise EstimationError(f'method={self.method!r}: expected one of {LPM_METHODS} '
                                  f'(or none: detect)')
        if self.method in LPM_METHODS and (self.chirp is not None
                                           or self.multisine_period is not None):
            raise EstimationError(f'method={self.method!r} with {self.text()}: the LPM is for '
                                  f'excitation that is neither a multisine nor a chirp')
        if self.input is not None and self.input not in rec.joint_names:
            raise EstimationError(f'input={self.input!r} is not a joint of the recording; '
                                  f'expected one of {rec.joint_names}')
        if self.chirp is not None and self.multisine_period is not None:
            raise EstimationError('chirp and multisine_period both given; expected one '
                                  'excitation')
        if (self.chirp is None) != (self.chirp_time is None):
            raise EstimationError(f'chirp={self.chirp} and chirp_time={self.chirp_time}: '
                                  f'expected both (band and sweep times) or neither')
        if self.band is not None:
            if self.chirp is not None:
                raise EstimationError(f'band={self.band} restricts multisine lines; for a chirp '
                                      f'give its band as chirp=(f_low, f_high)')
            lo, hi = self.band
            if not lo < hi:
                raise EstimationError(f'band={self.band}: expected f_low < f_high [Hz]')
            check_band([lo, hi], rec.fs, where=f'band={self.band}')
        duration = float(rec.t[-1] - rec.t[0]) + rec.dt
        if self.multisine_period is not None:
            if not self.multisine_period > 0:
                raise EstimationError(f'multisine_period={self.multisine_period}: expected a '
                                      f'positive period in seconds')
            check_periods(int(duration // self.multisine_period), need=2,
                          where=f'multisine_period={self.multisine_period:g} s in a recording '
                                f'of {duration:.4g} s', hint='a shorter period or more data')
        if self.chirp is not None:
            lo, hi = self.chirp
            if not (lo > 0 and hi > 0 and lo != hi):
                raise EstimationError(f'chirp={self.chirp}: expected two different positive '
                                      f'frequencies [Hz]')
            check_band([lo, hi], rec.fs, where=f'chirp={self.chirp}')
            t0, t1 = self.chirp_time
            if not 0 <= t0 < t1 <= duration:
                raise EstimationError(f'chirp_time={self.chirp_time}: expected 0 <= t0 < t1 <= '
                                      f'{duration:.4g} s (seconds from the first analysed '
                                      f'sample)')


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
    segments = []
    for j, det in found:
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
        segments.append(Segment(rec.t[0] + i0 / fs, t1, info))
    return segments, notes


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


def _check_single_input(u_lines: np.ndarray, j: int, name: str) -> None:
    """Other inputs must be quiet at the lines of input j (column estimation is valid)."""
    p = np.mean(np.abs(u_lines) ** 2, axis=0)
    others = np.delete(p, j)
    if others.size and np.max(others) > 0.1 * p[j]:
        raise EstimationError(f'{name}: other inputs are excited at the same lines '
                              f'({10 * np.log10(np.max(others) / p[j]):.1f} dB); one experiment '
                              f'cannot separate them (one input measured once and many sensors: '
                              f'map it under inputs, the sensors under outputs)')


class DetectedEstimator:
    """
    Column estimates of detected excitations, gathered block by block.

    A long recording without descriptors is cut into blocks; each block's detections are
    added here and the same excitation (same input and period, analysed at the lines of its
    first detection, or the same chirp band) found again in a later block adds its periods:
    the H1 sums sum_q Y conj(U_j) and sum_q |U_j|^2 and the spread of the per-period ratios
    (for the variance) are kept, not the data. One block alone gives exactly
    :func:`detected_frf`.
    """

    def __init__(self) -> None:
        self.entries: dict[tuple, dict[str, Any]] = {}
        self.notes: list[str] = []
        #: end [s] of the earliest detection of the last add_detected call: a next block
        #: starting there loses no period at the block boundary
        self.used_until: float | None = None

    def add_detected(self, rec: Recording, options: ExcitationOptions | None = None) -> int:
        """
        Detect, check and add the excitations in a recording.

        Detect the excitation in ``rec`` (:func:`detect_segments`; ``options`` replace
        detection where given), check and add every detection; the sentences go to
        :attr:`notes` (each once). Returns how many.

        Parameters
        ----------
        rec : Recording
            A recording (or block of one) without experiment descriptors.
        options : ExcitationOptions, optional
            What is known about the excitation; default None: detect everything.

        Returns
        -------
        int
            Number of detected excitations added.

        Raises
        ------
        NoExcitationError
            No multisine or chirp found.
        UnusableExcitationError
            A detection fails its checks (then nothing is added), or other inputs are
            excited at the same lines.
        EstimationError
            The options are refused.

        """
        segments, notes = detect_segments(rec, options)
        try:
            for seg in segments:
                check_detected_segment(rec, seg)
            self.notes.extend(n for n in notes if n not in self.notes)
            for seg in segments:
                self.add(rec, seg)
        except EstimationError as exc:      # found, but refused: never the LPM's to estimate
            raise UnusableExcitationError(str(exc)) from exc
        self.used_until = min((s.t_end for s in segments), default=None)
        return len(segments)

    def add(self, rec: Recording, seg: Segment) -> None:
        """
        One detected segment of ``rec`` (from :func:`detect_segments`).

        Parameters
        ----------
        rec : Recording
            The recording (or block) the segment was detected in.
        seg : Segment
            A detected segment; its periods or chirp lines are added to the sums of the
            same excitation found earlier, if any.

        Raises
        ------
        EstimationError
            Other inputs are excited at the same lines.

        """
        info = seg.info
        j = int(info['input'])
        outs = _output_columns(rec)
        names = (f'tau_m/{rec.joint_names[j]}', [f'dq_m/{rec.joint_names[k]}' for k in outs])
        if info['design'] == 'detected_multisine':
            # one excitation per input and period: a later block's detection may pick a
            # slightly different set of weak lines; the first block's lines are used
            key = (j, 'multisine', int(info['period_samples']))
            e = self.entries.get(key)
            if e is not None:
                seg = Segment(seg.t_start, seg.t_end, dict(info, harmonics=e['bins'].tolist()))
                info = seg.info
            # the excitation goes on from an earlier block: the periods that block used are
            # not used again
            going_on = e is not None and seg.t_start - e['t_end'] < 1.5 * info[
                'period_samples'] / rec.fs
            bins, U, Y, skip, dropped, Yd, Ul, filled = _multisine_periods(
                rec, seg, used_until=e['t_end'] if going_on else None)
            Y, Yd = Y[:, :, outs], Yd[:, :, outs]
            if U.shape[0]:          # refused before anything is kept (the reason, not '0 of 0')
                _check_single_input(U.mean(axis=0)[_strong_lines(U[:, :, j])], j,
                                    rec.joint_names[j])
            if e is None:
                e = self.entries[key] = {'names': names, 'f0': info['f0'], 'bins': bins,
                                         'u': [], 'y': [], 'det_y': [], 'det_u': [],
                                         'skip': 0, 'blocks': 0, 'dropped': [],
                                         'filled': [], 'missing': [],
                                         'runs': 0, 'run': [],
                                         'units': [_output_units(rec)[k] for k in outs],
                                         'input_unit': _input_unit(rec, j),
                                         'period_s': info['period_samples'] / rec.fs}
            e['t_end'] = max(seg.t_end, e.get('t_end', seg.t_end))
            # a detection that does not go on from the last one starts another run (another
            # realisation, or the same one restarted with a new transient)
            e['runs'] += 0 if going_on else 1
            e['dropped'].extend(d for d in dropped if d not in e['dropped'])
            e['skip'] += skip
            e['blocks'] += 1
            e.pop('steady', None)
            if U.shape[0] == 0:
                return
            # the periods' spectra are kept (not sums): the transient test decides on all
            # periods of the excitation at once, in memory and streamed alike
            for k, x in (('u', U[:, :, j]), ('y', Y), ('det_y', Yd), ('det_u', Ul)):
                e[k].append(x)
            e['run'].append(np.full(U.shape[0], e['runs']))
            # missing samples estimated: what they do to the spread over these periods, and
            # each period's account of them (merged over the steady periods in the end)
            e['filled'].append(filled[0] if filled else FilledPeriods(
                np.zeros(U.shape[0]), np.ones(U.shape[0])))
            e['missing'].extend(filled[1] if filled else [None] * U.shape[0])
            return
        freqs, U, Y = _chirp_lines(rec, seg)
        Y = Y[:, outs]
        ok = np.isfinite(U[:, j]) & np.all(np.isfinite(Y), axis=1)
        if np.any(ok):
            _check_single_input(U[ok], j, rec.joint_names[j])
        key = (j, 'chirp', round(info['f_low'], 1), round(info['f_high'], 1))
        e = self.entries.setdefault(key, {'names': names, 'freqs': freqs, 'syu': 0.0,
                                          'suu': 0.0, 'cnt': 0, 'blocks': 0})
        if e['freqs'].shape != freqs.shape:
            key = key + (len(self.entries),)
            e = self.entries.setdefault(key, {'names': names, 'freqs': freqs, 'syu': 0.0,
                                              'suu': 0.0, 'cnt': 0, 'blocks': 0})
        Uj = np.where(ok[:, None], U[:, j:j + 1], 0.0)
        e['syu'] = e['syu'] + np.where(ok[:, None], Y, 0.0) * np.conj(Uj)
        e['suu'] = e['suu'] + np.abs(Uj) ** 2
        e['cnt'] = e['cnt'] + ok
        e['blocks'] += 1

    def results(self) -> dict[str, FrequencyResponse]:
        """
        Return one FrequencyResponse per detected excitation.

        One FrequencyResponse per detected excitation, keyed 'detected/<input joint>'
        (a second excitation of the same joint: 'detected/<joint>#2'), the detection
        sentences in meta['detected'].

        Returns
        -------
        dict of str to FrequencyResponse
            Column estimates, one input (the excited joint) and every joint as output.

        Raises
        ------
        EstimationError
            Gaps left fewer than two multisine periods or no chirp line of an excitation.

        """
        out: dict[str, FrequencyResponse] = {}
        for e in self.entries.values():
            _check_enough(e)
        for e in self.entries.values():
            name = 'detected/' + e['names'][0].split('/', 1)[1]
            n = sum(1 for k in out if k == name or k.startswith(name + '#'))
            frf = self._response(e)
            frf.meta['detected'] = list(self.notes)
            out[name if n == 0 else f'{name}#{n + 1}'] = frf
        return out

    @staticmethod
    def _response(e: dict[str, Any]) -> FrequencyResponse:
        name_in, names_out = e['names']
        if 'freqs' in e:
            ok = np.asarray(e['cnt']) > 0
            P = (e['syu'][ok] / e['suu'][ok]).T[:, None, :]
            lost = e['freqs'][~ok]
            return FrequencyResponse(e['freqs'][ok], P, [name_in], names_out, meta={
                'design': 'detected_chirp', 'blocks': e['blocks'],
                'dropped': {'lines': int(lost.size), 'freq_hz': lost.tolist()}})
        steady = _steady(e)
        first = steady.first
        Uj, Y = np.concatenate(e['u'])[first:], np.concatenate(e['y'])[first:]
        n = Uj.shape[0]
        suu = np.sum(np.abs(Uj) ** 2, axis=0)
        keep = _strong_lines(suu[None, :])
        P = (np.einsum('qfo,qf->fo', Y, np.conj(Uj))[keep] / suu[keep, None]).T[:, None, :]
        # estimated missing samples make the spread over periods smaller: its scale
        missing = None
        for acc in e['missing'][first:]:
            missing = acc.merged(missing) if acc is not None else missing
        scale = FilledPeriods(np.concatenate([f.lost for f in e['filled']])[first:],
                              np.concatenate([f.factor for f in e['filled']])[first:]
                              ).spread_scale() if missing is not None else 1.0
        var = None
        if n >= 2:
            var = (np.var(Y / Uj[:, :, None], axis=0, ddof=1)[keep] / n).T[:, None, :]
            var = var * scale if scale != 1.0 else var
        det_y = np.concatenate(e['det_y'])[first:]
        dist = distortion_lines(det_y, np.arange(1, det_y.shape[1] + 1), e['bins'][keep],
                                e['f0'], names_out, units=e['units'])
        if scale != 1.0 and dist.noise is not None:
            dist.noise = dist.noise * scale
        one_run = np.unique(np.concatenate(e['run'])[first:]).size == 1
        robust = _robust_levels(Y[:, keep], Uj[:, keep], e['bins'][keep] * e['f0'], names_out,
                                e, scale) if one_run else None
        return FrequencyResponse(e['bins'][keep] * e['f0'], P, [name_in], names_out, var, None, {
            'design': 'detected_multisine', 'periods': n, 'distortion': dist.to_dict(),
            'units': {'input': e['input_unit'], 'outputs': e['units']},
            'transient_periods': e['skip'] + first, 'transient': steady.describe(),
            'blocks': e['blocks'], **({'robust_lpm': robust} if robust else {}),
            **({'missing': missing.to_dict()} if missing is not None else {}),
            'dropped': {'periods': len(e['dropped']), 'times': [list(d) for d in e['dropped']]}})


def _robust_levels(Y: np.ndarray, U: np.ndarray, freq_hz: np.ndarray, outputs: list[str],
                   e: dict[str, Any], scale: float = 1.0) -> dict[str, Any] | None:
    """
    Robust LPM of the steady periods of one realisation (its meta['robust_lpm']).

    ``Y`` (n_q, F, n_out) and ``U`` (n_q, F) at the excited lines. None when fewer lines
    than one local-polynomial window: the BLA's spread over periods is then all there is.
    ``scale``: of the noise variance from the spread (estimated missing samples reduce it).
    """
    if freq_hz.size < 2 * default_half_width(1, DEFAULT_ORDER, transient=False) + 1:
        return None
    res = robust_lpm_periods(np.transpose(Y, (0, 2, 1)), U, freq_hz)
    levels = res.levels(outputs, e['units'], e['input_unit'])
    levels.noise = levels.noise * scale if scale != 1.0 else levels.noise
    return levels.to_dict()


def _check_enough(e: dict[str, Any]) -> None:
    """Refuse an excitation of which gaps left too little (one line, how much is needed)."""
    name = e['names'][0].split('/', 1)[1]
    if 'freqs' in e:
        n_ok = int(np.count_nonzero(np.asarray(e['cnt']) > 0))
        check_remaining(n_ok, e['freqs'].size - n_ok, need=1, what='chirp analysis lines',
                        where=f'detected chirp of {name}',
                        hint='the sweep must be recorded without gaps somewhere')
        return
    n = sum(u.shape[0] for u in e['u']) - (_steady(e).first if e['u'] else 0)
    check_remaining(n, len(e['dropped']), need=MIN_PERIODS,
                    what='multisine periods', where=f'detected multisine of {name}',
                    dropped_at=e['dropped'], hint=f'{GAP_HINT}; record more periods')


def _multisine_periods(rec: Recording, seg: Segment, *, used_until: float | None = None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int,
                                  list[tuple[float, float]]]:
    """
    Compute the period spectra of a detected multisine.

    Excited bins, the period spectra U, Y (n_q, F, n) of a detected multisine's periods
    without missing samples, the periods skipped, the (t_start, t_end) of the periods
    dropped for missing samples, Y at every detection line (n_q, L, n) and the input at the
    lines up to the band (n_q, B) (for the transient test, :func:`_steady`).

    When the excitation was already running (``used_until``: the end [s] of the periods an
    earlier block used) the periods starting before it are skipped, so overlapping blocks
    never count a period twice, and the whole periods between it and this block's first are
    taken. Only whole periods inside the data are used; the start-up transient is left out
    later, on all periods of the excitation (:func:`_steady`).
    """
    info = seg.info
    i0 = int(info.get('start', rec.index_of(seg.t_start)))
    n_per = int(info['period_samples'])
    n_q = max(0, min(int(info['periods']), (rec.t.size - i0) // n_per))
    if used_until is not None:
        # the excitation goes on: the whole periods between the earlier block's last one and
        # this block's (flush with its end) are periods of the same run, not a transient
        back = min(i0 // n_per, max(0, int(np.floor(
            (rec.t[0] + i0 / rec.fs - used_until) * rec.fs / n_per + 1e-6))))
        i0, n_q = i0 - back * n_per, n_q + back
    starts = rec.t[0] + (i0 + np.arange(n_q) * n_per) / rec.fs
    skip = 0 if used_until is None else int(np.count_nonzero(
        starts < used_until - 0.5 / rec.fs))
    bins = np.asarray(info['harmonics'])
    j = int(info['input'])
    gone = missing_rows(rec.effort[:, j], rec.velocity)
    # detection lines: every line up to three times the band (a cubic's products); the
    # transient test looks at the input's lines up to the band
    lines = np.arange(1, min(3 * int(np.max(bins)), (n_per - 1) // 2) + 1)
    band = np.arange(1, min(int(np.max(bins)), (n_per - 1) // 2) + 1)
    idx = (i0 + np.arange(skip, n_q) * n_per)[:, None] + np.arange(n_per)   # (n_b, n_per)
    miss = gone[idx]
    u, y = rec.effort[idx], rec.velocity[idx]
    keep, filled = ~miss.any(axis=1), None
    if miss.any():
        u, y, keep, filled = _filled_block(rec, u, y, miss, j, band, used_until is None)
    dropped = [(float(starts[q]), float(starts[q] + n_per / rec.fs))
               for q, k in zip(range(skip, n_q), keep) if not k]
    if not np.any(keep):
        empty = np.empty((0, bins.size, rec.velocity.shape[1]), dtype=complex)
        return bins, empty, empty, skip, dropped, empty[:, :0], empty[:, :0, 0], None
    u, y = u[keep], y[keep]
    U = periodic_spectra(u, bins, axis=1)
    Y = periodic_spectra(y, bins, axis=1)
    return (bins, U, Y, skip, dropped, periodic_spectra(y, lines, axis=1),
            periodic_spectra(u[:, :, j], band, axis=1), filled)


def _filled_block(rec: Recording, u: np.ndarray, y: np.ndarray, miss: np.ndarray, j: int,
                  band: np.ndarray, new_run: bool) -> tuple:
    """
    Estimate the missing samples of a block's periods from its other periods.

    ``u``, ``y`` (n_b, n_per, n) the efforts and velocities of the block's periods, ``miss``
    (n_b, n_per) their missing samples (:mod:`frf_ident.core.estimation.missing_periodic`). A
    new run is filled from its steady periods (the transient test on the input's and outputs'
    lines up to the band). Returns u, y, the periods kept (all, unless a sample is missing in
    every period: then those a gap touches are dropped) and (FilledPeriods, account) or None.
    """
    n_u = u.shape[2]

    def first_steady(v: np.ndarray) -> int:
        return steady_periods(np.concatenate([periodic_spectra(v[:, :, j], band, axis=1)[
            :, :, None], periodic_spectra(v[:, :, n_u:], band, axis=1)], axis=2)).first
    fill = fill_steady_periods(np.concatenate([u, y], axis=2), miss,
                               first_steady if new_run else None)
    if not fill.complete:
        return u, y, ~miss.any(axis=1), None
    names = rec.joint_names
    outs = set(_output_columns(rec))
    channels = [f'tau_m/{m}' for m in names] + [f'dq_m/{m}' for m in names]
    keep = np.array([k == j for k in range(n_u)] + [k in outs for k in range(y.shape[2])])
    accounts = [fill.account(channels, keep=keep, periods=np.arange(len(miss)) == q)
                for q in range(len(miss))]
    return (np.ascontiguousarray(fill.values[:, :, :n_u]),
            np.ascontiguousarray(fill.values[:, :, n_u:]), np.ones(len(miss), bool),
            (fill.periods(), accounts))


def _steady(e: dict[str, Any]) -> SteadyState:
    """Transient test on every kept period of an excitation: its input and the outputs."""
    if 'steady' not in e:
        u = np.concatenate(e['det_u'])
        y = np.concatenate(e['det_y'])[:, :u.shape[1]]
        e['steady'] = steady_periods(np.concatenate([u[:, :, None], y], axis=2))
    return e['steady']


def _output_columns(rec: Recording) -> list[int]:
    """Columns that are outputs: all joints, or the outputs of an import layout."""
    return rec.output_columns()


def _output_units(rec: Recording) -> list[str]:
    """Velocity unit per joint as an import map states it (rad/s where it says nothing)."""
    return [rec.unit(n, 'velocity') for n in rec.joint_names]


def _input_unit(rec: Recording, j: int) -> str:
    """Effort unit of joint j as an import map states it (N m where it says nothing)."""
    return rec.unit(rec.joint_names[j], 'effort')


def _strong_lines(uj: np.ndarray) -> np.ndarray:
    """
    Select the lines the input really excites.

    The lines the input really excites (a detection may add weak leakage lines): power
    over the periods ``uj`` (n_q, F) at least 1 % of the median line's.
    """
    pj = np.mean(np.abs(uj) ** 2, axis=0)
    return pj >= 1e-2 * np.median(pj)


def _chirp_lines(rec: Recording, seg: Segment) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Analysis frequencies and the Sec. 5.1 spectra U, Y (F, n) of a detected chirp."""
    info = seg.info
    design = ChirpDesign(info['f_low'], info['f_high'], info['t1'] - info['t0'],
                         np.ones((1, 1)), t0=info['t0'])
    freqs = chirp_analysis_frequencies(reference_frequency_set(info['f_low'], info['f_high']),
                                       design.time_at, info['t0'], info['t1'])
    tc = design.time_at(freqs)            # detection times count from the first sample
    return (freqs, chirp_spectra(rec.effort, rec.fs, freqs, tc),
            chirp_spectra(rec.velocity, rec.fs, freqs, tc))


def detected_frf(rec: Recording, seg: Segment) -> FrequencyResponse:
    """
    Estimate one column of P from a detected excitation.

    Column j of P (all outputs / input j) from a detected excitation of input j: H1 over
    the periods at each line, sum Y conj(U_j) / sum |U_j|^2 (multisine), or Y / U_j at the
    Sec. 5.1 analysis frequencies (chirp).

    Parameters
    ----------
    rec : Recording
        The recording the segment was detected in.
    seg : Segment
        A detected segment (from :func:`detect_segments`).

    Returns
    -------
    FrequencyResponse
        Column j of P: input ``tau_m/<joint j>``, outputs ``dq_m/<joint>`` of every joint.

    Raises
    ------
    EstimationError
        Other inputs are excited at the same lines, or gaps left too little data.

    """
    est = DetectedEstimator()
    est.add(rec, seg)
    frf = next(iter(est.results().values()))
    frf.meta.pop('detected')
    return frf


def window_length(window_s: float | None = None, fs: float | None = None) -> float:
    """
    Return the detection block length [s]: ``window_s``, or the default for the sample rate.

    Parameters
    ----------
    window_s : float, optional
        Block length [s] (> 0); None: :data:`DEFAULT_WINDOW_S`, or
        :data:`DEFAULT_WINDOW_SAMPLES` samples at ``fs`` where that is longer.
    fs : float, optional
        The record's sample rate [Hz] (None: not known, the default in seconds).

    Returns
    -------
    float
        The block length [s].

    Raises
    ------
    EstimationError
        ``window_s`` is not > 0.

    Examples
    --------
    >>> window_length(), window_length(60.0), window_length(fs=1000.0), window_length(fs=1.0)
    (300.0, 60.0, 300.0, 300000.0)

    """
    if window_s is None:
        if fs is not None and fs > 0:
            return max(DEFAULT_WINDOW_S, DEFAULT_WINDOW_SAMPLES / float(fs))
        return DEFAULT_WINDOW_S
    if not window_s > 0:
        raise EstimationError(f'{window_s=}: expected a block length > 0 s')
    return float(window_s)


class RecordingBlocks:
    """
    Cut an in-memory recording into blocks as a streamed bag is cut.

    The blocks of an in-memory recording, cut as a streamed bag is cut
    (:class:`frf_ident.bag.windows.WindowReader` with ``window_s``): from the first sample,
    ``window_s`` long, the next one from where the last used data ended
    (:meth:`continue_from`) or else right after the block.

    Parameters
    ----------
    rec
        The recording.
    window_s
        Block length [s]; None: the default for the recording's rate (:func:`window_length`).

    """

    def __init__(self, rec: Recording, window_s: float | None = None) -> None:
        self.rec = rec
        self.block_ns = int(round(window_length(window_s, rec.fs) * 1e9))
        self._lo: int | None = None
        self._resume: int | None = None

    def continue_from(self, t_s: float) -> None:
        """
        Start the next block at a given time.

        Start the next block at ``t_s`` [s] if that lies more than ``MIN_ADVANCE_S`` into
        the block just given and not beyond it.

        Parameters
        ----------
        t_s : float
            Start time [s] of the next block, on the recording's time axis.

        """
        ns = int(round(t_s * 1e9))
        lo = self._lo
        if lo is not None and lo + int(MIN_ADVANCE_S * 1e9) < ns <= lo + self.block_ns:
            self._resume = ns

    def __iter__(self) -> Iterator[Recording]:
        rec = self.rec
        t_ns = np.round(rec.t * 1e9).astype(np.int64)
        lo = int(t_ns[0])
        while lo <= t_ns[-1]:
            self._lo, self._resume = lo, None
            hi = lo + self.block_ns - 1
            a = int(np.searchsorted(t_ns, lo, side='left'))
            b = int(np.searchsorted(t_ns, hi, side='right'))
            if b - a >= 2:
                yield _sub_recording(rec, slice(a, b))
            lo = self._resume if self._resume is not None else lo + self.block_ns


def _sub_recording(rec: Recording, sl: slice) -> Recording:
    """Return the samples ``sl`` of ``rec`` (views), with the segments and meta."""
    def cut(x):
        return None if x is None else x[sl]
    return Recording(rec.t[sl], list(rec.joint_names), rec.position[sl], rec.velocity[sl],
                     rec.effort[sl], cut(rec.reference), cut(rec.excitation),
                     list(rec.segments), rec.meta)


def _leftover(det: DetectedEstimator, rec: Recording) -> bool:
    """
    Tell whether a block is a leftover too short for detection.

    True for a block that starts where the periods of the block before ended and is too
    short for two periods of that multisine (nothing detectable is expected there).
    """
    periods = [e['period_s'] for e in det.entries.values() if 'period_s' in e]
    return bool(periods and det.used_until is not None
                and rec.t[0] >= det.used_until - 2 * rec.dt
                and rec.t[-1] - rec.t[0] + rec.dt < 2 * max(periods))


def check_not_periodic(rec: Recording, input: str | None = None) -> None:  # noqa: A002
    """
    Refuse a recording whose excitation is a periodic multisine (before the LPM estimates it).

    A multisine has power on its lines only; the LPM's lines between them carry no
    excitation and the polynomial's value there is not the FRF (issue 39: up to 18 dB off on
    a simulated robot, far outside the LPM's own variance). The multisine estimator of
    :func:`estimate_in_blocks` without ``method='lpm'`` is the one for such a record.

    Parameters
    ----------
    rec : Recording
        A recording (or block) without descriptors.
    input : str, optional
        Only this joint's excitation is checked; default: every moving joint's.

    Raises
    ------
    UnusableExcitationError
        The excitation source of a joint holds a periodic multisine.

    """
    x, source = excitation_source(rec.reference, rec.effort)
    present = np.isfinite(x)
    level = np.array([np.std(x[present[:, j], j]) if np.any(present[:, j]) else 0.0
                      for j in range(x.shape[1])])
    joints = ([rec.joint_names.index(input)] if input is not None
              else [j for j in range(x.shape[1]) if level[j] >= 1e-3 * level.max() > 0])
    for j in joints:
        try:
            det = detect_multisine(x[:, j], rec.fs)
        except EstimationError:
            continue                        # not periodic: the LPM's to estimate
        what = (f'input {rec.joint_names[j]}' if rec.is_layout
                else f'the {source} of {rec.joint_names[j]}')
        raise UnusableExcitationError(
            f"method='lpm': {what} is periodic ({det.describe()}); "
            f'between its lines the LPM has no excitation and its FRF there would be wrong; '
            f'expected non-periodic excitation — leave out --method lpm (the multisine '
            f'estimator takes a periodic record)')


def _add_lpm(lpm: LpmBlocks, rec: Recording, resume: Callable[[float], None] | None
             ) -> None:
    """Add a block's frames to the LPM; the next block starts where its last frame ends."""
    end = lpm.add(rec)
    if end is not None and resume is not None:
        resume(end)


def estimate_in_blocks(blocks: Iterable[Recording], options: ExcitationOptions | None = None,
                       *, resume: Callable[[float], None] | None = None,
                       window_s: float | None = None) -> dict[str, FrequencyResponse]:
    """
    Detect and estimate block by block (:class:`DetectedEstimator`).

    A block whose detection or checks fail is left out with a note (in each estimate's
    meta['detected']); when no block contributes, the reason is raised (the only block's,
    or the first of several). ``resume`` is told where the data used by a block end (the
    next block starts there); ``window_s`` only names the block length in messages.

    Where no block holds a multisine or chirp (or ``options.method == 'lpm'``), the blocks'
    frames are estimated by the Local Polynomial Method instead
    (:class:`~frf_ident.core.estimation.nonperiodic.LpmBlocks`: 'lpm' and its Welch H1
    baseline 'lpm_h1'). Where a block's excitation was found but refused
    (:class:`UnusableExcitationError`, e.g. a multisine period that is not a whole number of
    samples) and no block was estimated, the recording is refused with that reason: the LPM
    never estimates a periodic record instead (its lines between the multisine's carry no
    excitation). ``method='lpm'`` on a periodic record is refused alike
    (:func:`check_not_periodic`).

    Parameters
    ----------
    blocks
        Recordings in time order (:class:`RecordingBlocks` or a streamed bag's windows).
    options
        :class:`ExcitationOptions` replacing detection.
    resume
        E.g. ``RecordingBlocks.continue_from``.
    window_s
        Block length [s], for messages; None: the default for the blocks' sample rate
        (:func:`window_length`).

    Returns
    -------
    dict
        'detected/<joint>' -> :class:`FrequencyResponse` (see :meth:`DetectedEstimator.results`).

    Raises
    ------
    UnusableExcitationError
        An excitation was found but refused, and no block was estimated.
    EstimationError
        No block holds an estimable excitation, or gaps left too little of one.

    """
    det = DetectedEstimator()
    opts = options or ExcitationOptions()
    lpm = LpmBlocks(input=opts.input, band=opts.band, direct=opts.method == 'lpm-direct')
    notes: list[str] = []
    first: EstimationError | None = None
    unusable: str | None = None                 # the first block whose excitation was refused
    n = 0
    span = [np.inf, -np.inf, None]              # first and last time [s], sample rate
    for rec in blocks:
        n += 1
        span = [min(span[0], rec.t[0]), max(span[1], rec.t[-1]), rec.fs]
        try:
            if opts.method in LPM_METHODS:
                opts.check(rec)
                check_not_periodic(rec, opts.input)
                _add_lpm(lpm, rec, resume)
                continue
            det.add_detected(rec, options)
        except EstimationError as exc:
            if _leftover(det, rec):
                notes.append(f'block {rec.t[0]:.3f}..{rec.t[-1]:.3f} s: the rest after the '
                             f'last whole period, shorter than two periods')
                continue
            first = first or exc
            notes.append(f'block {rec.t[0]:.3f}..{rec.t[-1]:.3f} s: {exc}')
            if isinstance(exc, UnusableExcitationError):
                unusable = unusable or notes[-1]
            if isinstance(exc, NoExcitationError) and not det.entries and unusable is None:
                try:                                # not periodic: the LPM's frames
                    _add_lpm(lpm, rec, resume)
                except EstimationError as why:
                    notes.append(f'block {rec.t[0]:.3f}..{rec.t[-1]:.3f} s: LPM: {why}')
            continue
        if det.used_until is not None and resume is not None:
            resume(det.used_until)
    length = window_length(window_s, span[2])
    if not det.entries and unusable is not None:
        # an excitation was found and refused: no other block's LPM stands in for it
        if n == 1:
            raise first
        whole = span[1] - span[0] + (1.0 / span[2] if span[2] else 0.0)
        raise UnusableExcitationError(
            f'an excitation was found but refused ({unusable}); {n} blocks of at most '
            f'{length:g} s, none estimated; a block that holds more of the record may show '
            f'the excitation whole: --window {np.ceil(whole):g} (the whole record, '
            f'{whole:.4g} s)')
    if not det.entries and (lpm.frames or lpm.dropped or opts.method in LPM_METHODS):
        if not lpm.frames and not lpm.dropped and first is not None:
            raise first                     # (frames only gaps dropped: the LPM says why)
        why = ([] if opts.method in LPM_METHODS else
               [f'no multisine or chirp found in {n} block(s) of at most {length:g} s'])
        return lpm.results(why)
    if not det.entries:
        if n == 1 and first is not None:
            raise first
        raise EstimationError(f'no multisine or chirp found in any {length:g} s '
                              f'block ({n} blocks; first: '
                              f'{notes[0] if notes else "no joint states"})')
    estimates = det.results()
    for frf in estimates.values():
        frf.meta['detected'] = frf.meta['detected'] + notes
    return estimates
