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
Column estimates of detected excitations, gathered block by block: DetectedEstimator.

Each detected segment (:mod:`frf_ident.core.estimation.detected_segments`) adds its
multisine periods or chirp lines (:mod:`frf_ident.core.estimation.detected_spectra`) to the
same excitation found earlier; the FRF is estimated column by column for the excited inputs
(one experiment cannot separate simultaneously excited inputs that share lines, so those are
refused with the reason). A multisine's start-up transient is left out on all its periods at
once, its distortion levels and (one realisation) robust-LPM levels go to the meta; a period
dropped for missing samples or a chirp line lost to them is listed there, and an excitation
is refused only when fewer than two periods (or no line) remain.
"""
from __future__ import annotations

from typing import Any

from frf_ident.core.estimation.checks import check_remaining
from frf_ident.core.estimation.detected_segments import (check_detected_segment,
                                                         detect_segments,
                                                         UnusableExcitationError)
from frf_ident.core.estimation.detected_spectra import (chirp_lines, multisine_periods,
                                                        output_columns)
from frf_ident.core.estimation.distortion import distortion_lines
from frf_ident.core.estimation.excitation_options import ExcitationOptions
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.lpm import default_half_width, DEFAULT_ORDER, robust_lpm_periods
from frf_ident.core.estimation.missing_periodic import FilledPeriods, GAP_HINT
from frf_ident.core.estimation.transient import steady_periods, SteadyState
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import EstimationError
import numpy as np

__all__ = ['MIN_PERIODS', 'DetectedEstimator', 'detected_frf']

#: fewest multisine periods an estimate needs (mean and noise variance over periods)
MIN_PERIODS = 2


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
        outs = output_columns(rec)
        names = (f'tau_m/{rec.joint_names[j]}', [f'dq_m/{rec.joint_names[k]}' for k in outs])
        if info['design'] == 'detected_multisine':
            self._add_multisine(rec, seg, j, outs, names)
            return
        self._add_chirp(rec, seg, j, outs, names)

    def _add_multisine(self, rec: Recording, seg: Segment, j: int, outs: list[int],
                       names: tuple[str, list[str]]) -> None:
        """Add a detected multisine's periods to its excitation (a new one or one going on)."""
        info = seg.info
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
        bins, U, Y, skip, dropped, Yd, Ul, filled = multisine_periods(
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

    def _add_chirp(self, rec: Recording, seg: Segment, j: int, outs: list[int],
                   names: tuple[str, list[str]]) -> None:
        """Add a detected chirp's lines to the sums of the same chirp band."""
        info = seg.info
        freqs, U, Y = chirp_lines(rec, seg)
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


def _steady(e: dict[str, Any]) -> SteadyState:
    """Transient test on every kept period of an excitation: its input and the outputs."""
    if 'steady' not in e:
        u = np.concatenate(e['det_u'])
        y = np.concatenate(e['det_y'])[:, :u.shape[1]]
        e['steady'] = steady_periods(np.concatenate([u[:, :, None], y], axis=2))
    return e['steady']


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
