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
Block-by-block estimation of a recording that carries no experiment descriptors.

A recording without descriptors (foreign bags, imports) is estimated block by block
(:func:`estimate_in_blocks`, blocks of ``DEFAULT_WINDOW_S``, :func:`window_length`), in
memory (:class:`RecordingBlocks`) and when a bag is streamed alike, so both take the same
decisions whatever the size of the bag. Each block's excitation is detected
(:mod:`frf_ident.core.estimation.detected_segments`, what
:class:`~frf_ident.core.estimation.excitation_options.ExcitationOptions` give replaces
detection) and added to the column estimates
(:class:`~frf_ident.core.estimation.detected_estimator.DetectedEstimator`).
Where neither a multisine nor a chirp is found (PRBS, noise, normal motion) the Local
Polynomial Method estimates the FRF instead (:mod:`frf_ident.core.estimation.nonperiodic`);
a periodic record is never the LPM's (:func:`check_not_periodic`).
"""
from __future__ import annotations

from typing import Callable, Iterable, Iterator

from frf_ident.core.estimation.detected_estimator import DetectedEstimator
from frf_ident.core.estimation.detected_segments import (NoExcitationError,
                                                         UnusableExcitationError)
from frf_ident.core.estimation.excitation_options import ExcitationOptions, LPM_METHODS
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.nonperiodic import LpmBlocks
from frf_ident.core.excitation.detect_input import excitation_source
from frf_ident.core.excitation.multisine_detect import detect_multisine
from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError
import numpy as np

__all__ = ['DEFAULT_WINDOW_S', 'DEFAULT_WINDOW_SAMPLES', 'MIN_ADVANCE_S', 'RecordingBlocks',
           'check_not_periodic', 'estimate_in_blocks', 'window_length']

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


def _failed_block(exc: EstimationError, rec: Recording, det: DetectedEstimator,
                  lpm: LpmBlocks, resume: Callable[[float], None] | None, notes: list[str],
                  first: EstimationError | None, unusable: str | None
                  ) -> tuple[EstimationError | None, str | None]:
    """
    Note a block whose detection or checks failed; its frames go to the LPM where none found.

    Returns the first failure and the note of the first refused excitation, updated
    (:func:`estimate_in_blocks`).
    """
    if _leftover(det, rec):
        notes.append(f'block {rec.t[0]:.3f}..{rec.t[-1]:.3f} s: the rest after the '
                     f'last whole period, shorter than two periods')
        return first, unusable
    first = first or exc
    notes.append(f'block {rec.t[0]:.3f}..{rec.t[-1]:.3f} s: {exc}')
    if isinstance(exc, UnusableExcitationError):
        unusable = unusable or notes[-1]
    if isinstance(exc, NoExcitationError) and not det.entries and unusable is None:
        try:                                # not periodic: the LPM's frames
            _add_lpm(lpm, rec, resume)
        except EstimationError as why:
            notes.append(f'block {rec.t[0]:.3f}..{rec.t[-1]:.3f} s: LPM: {why}')
    return first, unusable


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
            first, unusable = _failed_block(exc, rec, det, lpm, resume, notes, first, unusable)
            continue
        if det.used_until is not None and resume is not None:
            resume(det.used_until)
    length = window_length(window_s, span[2])
    if not det.entries:
        return _without_detection(lpm, opts, n, span, length, notes, first, unusable)
    estimates = det.results()
    for frf in estimates.values():
        frf.meta['detected'] = frf.meta['detected'] + notes
    return estimates


def _without_detection(lpm: LpmBlocks, opts: ExcitationOptions, n: int, span: list,
                       length: float, notes: list[str],
                       first: EstimationError | None, unusable: str | None
                       ) -> dict[str, FrequencyResponse]:
    """
    Return the LPM's estimates where no block was estimated, or raise why not.

    The end of :func:`estimate_in_blocks` when no detected excitation was added: the
    refused excitation's reason, the LPM's estimates of the blocks' frames, or the
    reason no block holds an estimable excitation (blocks of at most ``length`` [s]).
    """
    if unusable is not None:
        # an excitation was found and refused: no other block's LPM stands in for it
        if n == 1:
            raise first
        whole = span[1] - span[0] + (1.0 / span[2] if span[2] else 0.0)
        raise UnusableExcitationError(
            f'an excitation was found but refused ({unusable}); {n} blocks of at most '
            f'{length:g} s, none estimated; a block that holds more of the record may show '
            f'the excitation whole: --window {np.ceil(whole):g} (the whole record, '
            f'{whole:.4g} s)')
    if lpm.frames or lpm.dropped or opts.method in LPM_METHODS:
        if not lpm.frames and not lpm.dropped and first is not None:
            raise first                     # (frames only gaps dropped: the LPM says why)
        why = ([] if opts.method in LPM_METHODS else
               [f'no multisine or chirp found in {n} block(s) of at most {length:g} s'])
        return lpm.results(why)
    if n == 1 and first is not None:
        raise first
    raise EstimationError(f'no multisine or chirp found in any {length:g} s '
                          f'block ({n} blocks; first: '
                          f'{notes[0] if notes else "no joint states"})')
