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
The chirp estimate (Sec. 5.1): spectra of a chirp iteration's experiments and its FRF.

:class:`ChirpSpectra` gathers u, y, r at the analysis frequencies per iteration and
experiment; which iterations a recording holds and which of them are complete (every
experiment's segment present); :func:`chirp_frf` estimates one iteration.
"""
from __future__ import annotations

from typing import Any

from frf_ident.core.estimation.channels import channel_names, segment_arrays
from frf_ident.core.estimation.checks import check_remaining, EXPERIMENT
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.segment_counts import expected_experiments
from frf_ident.core.estimation.spectra import frf_from_reference, frf_from_spectra
from frf_ident.core.excitation.chirp import ChirpDesign
from frf_ident.core.excitation.chirp_dft import chirp_spectra
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import EstimationError
import numpy as np


class ChirpSpectra:
    """
    Gather the spectra of chirp experiments one segment at a time.

    Sec. 5.1 spectra (u, y, r at the analysis frequencies) of chirp experiments, per
    iteration, gathered one segment at a time.
    """

    def __init__(self) -> None:
        self.spec: dict[int, dict[int, dict[str, np.ndarray]]] = {}
        self.info: dict[int, dict[str, Any]] = {}
        self.joint_names: list[str] = []

    def add(self, rec: Recording, seg: Segment) -> None:
        info = seg.info
        it = int(info['iteration'])
        design = ChirpDesign.from_dict(info['design_params'])
        freqs = np.asarray(info['freq_hz'])
        tc = design.time_at(freqs)
        a = segment_arrays(rec, seg)
        self.joint_names = list(rec.joint_names)
        self.info.setdefault(it, info)
        # one pass over the three signals: the excerpt weights are formed once per frequency
        spec = chirp_spectra(np.stack([a[k] for k in ('u', 'y', 'r')], axis=-1), rec.fs,
                             freqs, tc)
        self.spec.setdefault(it, {})[int(info['experiment'])] = {
            k: spec[..., i] for i, k in enumerate(('u', 'y', 'r'))}

    def iterations(self) -> list[int]:
        return sorted(self.spec)

    def complete(self) -> list[int]:
        """
        Return the iterations that hold every experiment's segment, sorted.

        Returns
        -------
        list of int
            Iterations with one experiment per axis (an iteration cut short lacks some).

        """
        return [it for it in self.iterations()
                if chirp_complete(set(self.spec[it]), self.info[it])]

    def frf(self, *, iteration: int | None = None, method: str = 'plain',
            path: str = 'u->y') -> FrequencyResponse:
        """
        Chirp estimate of one iteration (default: the last).

        path 'u->y' is the plant P (eq. 7, or reference-based with method='reference'),
        'r->u' the transfer the iteration inverts (eq. 18).
        """
        if not self.spec:
            raise EstimationError('recording has no chirp segments')
        done = self.complete()
        it = (done or self.iterations())[-1] if iteration is None else iteration
        if it not in self.spec:
            raise EstimationError(f'{iteration=}: the recording holds chirp iterations '
                                  f'{self.iterations()}')
        exps = self.spec[it]
        if it not in done:
            raise EstimationError(f'chirp iteration {it} is incomplete: it holds experiments '
                                  f'{sorted(exps)} of {expected_experiments(exps, self.info[it])} '
                                  f'(one per axis; a run cut short)'
                                  + (f'; complete: {done}' if done else
                                     '; no chirp iteration is complete'))
        Y, U, R = (np.stack([exps[m][k] for m in sorted(exps)], axis=-1)
                   for k in ('y', 'u', 'r'))
        freqs = np.asarray(self.info[it]['freq_hz'])
        # an analysis frequency whose excerpt held a missing sample (NaN) is dropped
        ok = np.all(np.isfinite(Y), axis=(1, 2)) & np.all(np.isfinite(U), axis=(1, 2)) \
            & np.all(np.isfinite(R), axis=(1, 2))
        check_remaining(int(ok.sum()), int((~ok).sum()), need=1, what='chirp analysis lines',
                        where=f'{EXPERIMENT} chirp iteration {it}',
                        hint='the sweep must be recorded without gaps somewhere')
        Y, U, R = Y[ok], U[ok], R[ok]
        dropped = {'lines': int((~ok).sum()), 'freq_hz': freqs[~ok].tolist()}
        ins, outs = channel_names(self.joint_names)
        if path == 'r->u':
            P, cond = frf_from_spectra(U, R)
            ins = [f'r/{j}' for j in self.joint_names]
            outs = [f'tau_m/{j}' for j in self.joint_names]
        elif method == 'reference':
            P, cond = frf_from_reference(Y, U, R)
        elif method == 'plain':
            P, cond = frf_from_spectra(Y, U)
        else:
            raise ValueError(f"{method=} must be 'reference' or 'plain'")
        return FrequencyResponse(freqs[ok], P, ins, outs, meta={
            'design': 'chirp', 'iteration': it, 'method': method, 'path': path,
            'cond_max': float(np.max(cond)), 'dropped': dropped})


def chirp_input_power(rec: Recording, *, iteration: int | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return each input's effective power at the analysis lines of a chirp iteration.

    The estimate :func:`chirp_frf` forms is P = Y U^-1 over the experiments (eq. 7), so
    output noise of variance s^2 in every excerpt puts s^2 sum_m |U^-1[m, j]|^2 on column j
    of P: the effective power of input j is 1 / sum_m |U^-1[m, j]|^2 (|U_jj|^2 for one
    input). The noise of the estimate relative to the response scales with its inverse: how
    the diagnosis sets the noise floor of an iteration weaker than the one it fits.

    Parameters
    ----------
    rec : Recording
        A recording with chirp segments.
    iteration : int, optional
        The iteration (default: the last complete one, else the last).

    Returns
    -------
    freq_hz : ndarray, shape (n_freq,)
        The analysis lines.
    power : ndarray, shape (n_freq, n_inputs)
        Effective power per line and input; NaN where an excerpt held a missing sample or
        the iteration lacks an experiment.

    Examples
    --------
    One axis, a unit torque line: its power is |U|^2 of the excerpt spectrum.

    >>> import numpy as np
    >>> U = np.array([[[2.0 + 0j]]])
    >>> float(effective_input_power(U)[0, 0])
    4.0

    """
    it, acc = iteration_spectra(rec, iteration)
    freqs = np.asarray(acc.info[it]['freq_hz'], dtype=float)
    n = len(rec.joint_names)
    if it not in acc.complete():
        return freqs, np.full((freqs.size, n), np.nan)
    exps = acc.spec[it]
    U = np.stack([exps[m]['u'] for m in sorted(exps)], axis=-1)
    return freqs, effective_input_power(U)


def effective_input_power(U: np.ndarray) -> np.ndarray:
    """
    Return 1 / sum_m |U^-1[m, j]|^2 per line and input (see :func:`chirp_input_power`).

    Parameters
    ----------
    U : ndarray, shape (n_freq, n_inputs, n_experiments)
        Input spectra per line, input and experiment.

    Returns
    -------
    ndarray, shape (n_freq, n_inputs)
        The effective power; NaN on a line with a missing sample.

    """
    out = np.full(U.shape[:2], np.nan)
    ok = np.all(np.isfinite(U), axis=(1, 2))
    if ok.any():
        inv = np.linalg.pinv(U[ok])                     # (n_ok, n_experiments, n_inputs)
        out[ok] = 1.0 / np.maximum(np.sum(np.abs(inv) ** 2, axis=1), 1e-300)
    return out


def chirp_iterations(rec: Recording) -> list[int]:
    return sorted({s.info['iteration'] for s in rec.segments if s.info.get('design') == 'chirp'})


def chirp_complete(experiments: set[int], info: dict[str, Any]) -> bool:
    """
    Whether a chirp iteration holds every experiment (:func:`expected_experiments`).

    Parameters
    ----------
    experiments
        The experiment indices present.
    info
        A segment descriptor of the iteration.

    Returns
    -------
    bool

    """
    return set(range(expected_experiments(experiments, info))) <= set(experiments)


def complete_chirp_iterations(segments: list[Segment]) -> list[int]:
    """
    Return the chirp iterations whose every experiment's segment is among ``segments``.

    Parameters
    ----------
    segments
        Experiment segments (those of other designs are ignored).

    Returns
    -------
    list of int
        Sorted iteration numbers.

    """
    by_it: dict[int, list[Segment]] = {}
    for s in segments:
        if s.info.get('design') == 'chirp':
            by_it.setdefault(int(s.info.get('iteration', 0)), []).append(s)
    return [it for it, ss in sorted(by_it.items())
            if chirp_complete({int(x.info.get('experiment', 0)) for x in ss}, ss[0].info)]


def chirp_frf(rec: Recording, *, iteration: int | None = None, method: str = 'plain',
              path: str = 'u->y') -> FrequencyResponse:
    """Chirp estimate of one iteration (default: the last), see :meth:`ChirpSpectra.frf`."""
    it, acc = iteration_spectra(rec, iteration)
    return acc.frf(iteration=it, method=method, path=path)


def iteration_spectra(rec: Recording, iteration: int | None = None
                      ) -> tuple[int, ChirpSpectra]:
    """
    Return a chirp iteration and the spectra of its segments.

    Parameters
    ----------
    rec : Recording
        A recording with chirp segments.
    iteration : int, optional
        The iteration (default: the last complete one, else the last, which
        :meth:`ChirpSpectra.frf` refuses naming what it lacks).

    Returns
    -------
    int, ChirpSpectra

    """
    its = chirp_iterations(rec)
    if not its:
        raise EstimationError('recording has no chirp segments')
    it = (complete_chirp_iterations(rec.segments) or its)[-1] if iteration is None \
        else iteration
    acc = ChirpSpectra()
    for s in rec.segments_where(design='chirp', iteration=it):
        acc.add(rec, s)
    return it, acc
