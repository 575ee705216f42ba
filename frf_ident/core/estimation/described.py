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
Every estimate a Recording with experiment descriptors supports (Sections 4.3, 4.4, 5.1, 7).

Works only from what a bag holds: the time series and the experiment segments. So estimation
from a bag equals estimation from the in-memory run.

- :class:`SegmentEstimator` — the segments fed window by window (constant-velocity run first)
  into :class:`~frf_ident.core.estimation.multisine_estimate.MultisineSpectra` and
  :class:`~frf_ident.core.estimation.chirp_estimate.ChirpSpectra`
- :func:`multisine_frf` — BLA over realisations x periods, optionally with the
  constant-velocity run subtracted (periodic-disturbance compensation, Sec. 4.4 E), by the
  reference-based estimator or the plain Y U^+ (eq. 7)
- :func:`estimate_recording` — every estimate a recording supports (without descriptors the
  detected ones), and the refusal of a recording whose every experiment was cut short

Elsewhere: the chirp estimate in :mod:`~frf_ident.core.estimation.chirp_estimate`, the
channels and joints in :mod:`~frf_ident.core.estimation.channels`.
"""
from __future__ import annotations

from frf_ident.core.estimation.chirp_estimate import ChirpSpectra
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.multisine_estimate import MultisineSpectra
from frf_ident.core.estimation.spectra import BLAResult
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import EstimationError


def multisine_frf(rec: Recording, *, compensate: bool = True, method: str = 'reference',
                  align: str = 'position') -> tuple[FrequencyResponse, BLAResult]:
    """
    Estimate the multisine best linear approximation of closed-loop data.

    Multisine best linear approximation (eq. 14) of the closed-loop data (see
    :meth:`MultisineSpectra.frf`); ``align`` see
    :func:`~frf_ident.core.estimation.compensation.disturbance_at`.
    """
    est = SegmentEstimator(rec.segments, align=align)
    est.add_window(rec, compensate=compensate)
    if est.multisine is None:
        raise EstimationError('recording has no multisine segments')
    return est.multisine.frf(compensate=compensate, method=method)


class SegmentEstimator:
    """
    Every estimate the experiment segments support, fed window by window.

    ``add_window(rec)`` takes a recording that holds some of the segments completely (the
    whole run, or one window of a long bag); segments are processed in time order with the
    constant-velocity run first, and nothing but their spectra is kept.
    """

    def __init__(self, segments: list[Segment], *, align: str = 'position') -> None:
        self.segments = sorted(segments, key=lambda s: (
            s.info.get('design') != 'constant_velocity', s.t_start))
        self.align = align
        ms = [s for s in segments if s.info.get('design') == 'multisine']
        self.multisine = MultisineSpectra(ms[0].info, align=align) if ms else None
        self.chirp = ChirpSpectra() if any(s.info.get('design') == 'chirp'
                                           for s in segments) else None
        self.done: set[int] = set()

    def add_window(self, rec: Recording, *, compensate: bool = True) -> int:
        """
        Process the segments that a window overlaps.

        Process the not yet processed segments that ``rec`` overlaps (a segment it holds
        only in part is an error); returns how many.
        """
        t0, t1 = float(rec.t[0]), float(rec.t[-1])
        count = 0
        for i, s in enumerate(self.segments):
            if i in self.done or s.t_end <= t0 or s.t_start > t1:
                continue
            design = s.info.get('design')
            if design == 'constant_velocity' and self.multisine is not None and compensate:
                self.multisine.add_constant_velocity(rec, s)
            elif design == 'multisine' and self.multisine is not None:
                self.multisine.add(rec, s)
            elif design == 'chirp' and self.chirp is not None:
                self.chirp.add(rec, s)
            self.done.add(i)
            count += 1
        return count

    def missing(self) -> list[Segment]:
        """Segments no window covered completely."""
        return [s for i, s in enumerate(self.segments) if i not in self.done
                and s.info.get('design') in ('multisine', 'chirp', 'constant_velocity')]

    def results(self) -> dict[str, FrequencyResponse]:
        """Every estimate, keyed as :func:`estimate_recording` documents."""
        out: dict[str, FrequencyResponse] = {}
        ms = self.multisine if self.multisine is not None and self.multisine.spec else None
        ch = self.chirp if self.chirp is not None and self.chirp.spec else None
        ms_ok = ms is not None and ms.any_complete()
        ch_done = ch.complete() if ch is not None else []
        notes = []                     # meta['left_out'] of every estimate, one line each
        # an aborted procedure takes the other one with it no more; alone it is refused
        if ms is not None and not ms_ok and ch_done:
            notes.append('multisine: no realisation is complete (a run cut short, or a time '
                         'range leaving experiments out), no multisine estimate')
            ms = None
        if ch is not None and not ch_done and ms_ok:
            notes.append('chirp: no iteration is complete (a run cut short, or a time range '
                         'leaving experiments out), no chirp estimate')
            ch = None
        if ch is not None and ch_done and ch.iterations()[-1] not in ch_done:
            notes.append(f'chirp: iteration {ch.iterations()[-1]} was cut short; iteration '
                         f'{ch_done[-1]} is estimated')
        if ms is not None:
            cv = ms.cv is not None
            out['multisine'] = ms.frf(compensate=cv)[0]
            out['multisine_plain'] = ms.frf(compensate=cv, method='plain')[0]
            if cv:
                out['multisine_uncompensated'] = ms.frf(compensate=False)[0]
        if ch is not None:
            out['chirp'] = ch.frf()
            out['chirp_reference'] = ch.frf(method='reference')
        for v in out.values():
            v.meta['left_out'] = list(notes)
        return out


def estimate_recording(rec: Recording, *, options=None, window_s: float | None = None
                       ) -> dict[str, FrequencyResponse]:
    """
    Compute every estimate the recording supports.

    Every estimate the recording supports, keyed by name: 'multisine' (reference-based,
    compensated when a constant-velocity run exists), 'multisine_plain',
    'multisine_uncompensated', 'chirp', 'chirp_reference'; without descriptors the
    detected ones (:func:`estimate_detected`). The data are checked first
    (:func:`frf_ident.core.estimation.checks.check_descriptor_recording`: band, periods,
    clipping). ``options`` (:class:`frf_ident.core.estimation.detected.ExcitationOptions`)
    replace detection in a recording without descriptors; a recording with descriptors
    refuses them. ``window_s``: block length of detection (default
    :data:`frf_ident.core.estimation.detected.DEFAULT_WINDOW_S`).
    """
    check_recording(rec, options)
    est = SegmentEstimator(rec.segments)
    est.add_window(rec)
    out = est.results()
    left_out = cut_short(rec, rec.meta.get('segments_left_out', []))
    if not out and left_out and not any(
            s.info.get('design') in ('multisine', 'chirp') for s in rec.segments):
        raise cut_short_error(left_out)
    if not out:
        out = estimate_detected(rec, options, window_s=window_s)
    return out


def cut_short(rec: Recording, spans: list) -> int:
    """
    Return how many segments left out as never ended lie within the recording's time.

    Parameters
    ----------
    rec : Recording
        The recording (or the window of it that a time range kept).
    spans : list of [t_start, t_end]
        The left-out segments (``meta['segments_left_out']`` of the bag reader).

    Returns
    -------
    int

    """
    return sum(1 for a, b in spans if b >= rec.t[0] and a <= rec.t[-1]) if rec.t.size else 0


def cut_short_error(n: int) -> EstimationError:
    """
    Return the error of a recording whose every experiment segment was cut short.

    Parameters
    ----------
    n : int
        The segments left out as never ended.

    Returns
    -------
    EstimationError

    """
    return EstimationError(f'every experiment of the recording was cut short: its {n} started '
                           f'segment(s) never ended or were recorded only in part (run '
                           f'aborted, recording started or stopped inside one, or a time range '
                           f'cutting one; the warnings name them); expected at least one '
                           f'complete multisine realisation or chirp iteration')


def check_recording(rec: Recording, options=None) -> None:
    """Return the input checks of a recording (or one window of it) with descriptors."""
    from frf_ident.core.estimation.checks import check_descriptor_recording
    if any(s.info.get('design') in ('multisine', 'chirp') for s in rec.segments):
        if options is not None and options.given():
            raise EstimationError(f'{options.text()}: the recording has experiment descriptors; '
                                  f'expected excitation options only without them')
        check_descriptor_recording(rec)


def estimate_detected(rec: Recording, options=None, *, window_s: float | None = None
                      ) -> dict[str, FrequencyResponse]:
    """
    Estimate a recording without descriptors from the detected excitation.

    Estimates of a recording without descriptors: the excitation is detected per joint
    in blocks of ``window_s`` seconds, as a streamed bag is
    (:func:`frf_ident.core.estimation.detected.estimate_in_blocks`; ``options`` replace
    detection where given) and checked; one entry 'detected/<joint>' per excited input, the
    detection sentences in each estimate's meta['detected'].
    """
    from frf_ident.core.estimation.detected import (window_length, estimate_in_blocks,
                                                    RecordingBlocks)
    window_s = window_length(window_s, rec.fs)
    blocks = RecordingBlocks(rec, window_s)
    return estimate_in_blocks(blocks, options, resume=blocks.continue_from, window_s=window_s)
