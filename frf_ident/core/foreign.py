"""Estimation from recordings that carry no experiment descriptors (foreign bags, imports).

The excitation is detected in the data (:mod:`frf_ident.core.detect`): a periodic multisine or
an exponential chirp, on the velocity reference when the bag has one, else on the torque.
Each detection becomes a :class:`~frf_ident.core.recording.Segment`, and the FRF is estimated
column by column for the excited inputs (one experiment cannot separate simultaneously excited
inputs that share lines, so those are refused with the reason).
"""
from __future__ import annotations

import numpy as np

from frf_ident.core.chirp import ChirpDesign
from frf_ident.core.detect import ChirpDetection, MultisineDetection, detect_excitation
from frf_ident.core.estimation import (chirp_analysis_frequencies, chirp_spectra,
                                       periodic_spectra)
from frf_ident.core.frd import FrequencyResponse
from frf_ident.core.multisine import reference_frequency_set
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import EstimationError


def _source(rec: Recording) -> tuple[np.ndarray, str]:
    ref = rec.reference
    if ref is not None and np.all(np.isfinite(ref)) and np.any(np.std(ref, axis=0) > 0):
        return ref, 'velocity reference'
    return rec.effort, 'torque'


def detect_segments(rec: Recording) -> tuple[list[Segment], list[str]]:
    """Detect the excitation per joint; returns segments and one sentence per detection."""
    x, source = _source(rec)
    fs = rec.fs
    level = np.std(x, axis=0)
    found: list[tuple[int, MultisineDetection | ChirpDetection]] = []
    notes: list[str] = []
    for j in np.argsort(level)[::-1]:
        if level[j] < 1e-3 * level.max():
            continue
        try:
            det = detect_excitation(x[:, j], fs)
        except EstimationError as exc:
            notes.append(f'{rec.joint_names[j]}: no excitation found in the {source} ({exc})')
            continue
        strongest = _strongest_channel(x, det, fs)
        if strongest != j:
            notes.append(f'{rec.joint_names[j]}: follows the excitation of '
                         f'{rec.joint_names[strongest]} (coupling), not an input')
            continue
        found.append((int(j), det))
        notes.append(f'{rec.joint_names[j]} ({source}): {det.describe()}')
    if not found:
        raise EstimationError(f'no multisine or chirp found in the {source} of any joint; '
                              f'pass the experiment descriptors or a time range')
    segments = []
    for j, det in found:
        if isinstance(det, MultisineDetection):
            i0 = det.start
            info = {'design': 'detected_multisine', 'input': j, 'period_samples':
                    det.period_samples, 'periods': det.n_periods,
                    'harmonics': np.asarray(det.harmonics).tolist(), 'f0': det.f0}
            t1 = rec.t[0] + (i0 + det.n_periods * det.period_samples) / fs
        else:
            info = {'design': 'detected_chirp', 'input': j, 'f_low': det.f_low,
                    'f_high': det.f_high, 't0': det.t0, 't1': det.t1, 'a0': det.a0,
                    'a1': det.a1}
            i0 = int(round(det.t0 * fs))
            t1 = rec.t[0] + det.t1
        segments.append(Segment(rec.t[0] + i0 / fs, t1, info))
    return segments, notes


def _strongest_channel(x: np.ndarray, det: MultisineDetection | ChirpDetection,
                       fs: float) -> int:
    """The channel with the most power at the detected excitation (lines or sweep)."""
    if isinstance(det, MultisineDetection):
        seg = x[det.start:det.start + det.period_samples]
        p = np.abs(periodic_spectra(seg, np.asarray(det.harmonics), axis=0)) ** 2
        return int(np.argmax(p.sum(axis=0)))
    i0, i1 = int(det.t0 * fs), int(det.t1 * fs)
    return int(np.argmax(np.std(x[i0:i1], axis=0)))


def _check_single_input(u_lines: np.ndarray, j: int, name: str) -> None:
    """Other inputs must be quiet at the lines of input j (column estimation is valid)."""
    p = np.mean(np.abs(u_lines) ** 2, axis=0)
    others = np.delete(p, j)
    if others.size and np.max(others) > 0.1 * p[j]:
        raise EstimationError(f'{name}: other inputs are excited at the same lines '
                              f'({10 * np.log10(np.max(others) / p[j]):.1f} dB); one experiment '
                              f'cannot separate them')


def detected_frf(rec: Recording, seg: Segment) -> FrequencyResponse:
    """Column j of P (all outputs / input j) from a detected excitation of input j."""
    info = seg.info
    j = info['input']
    sl = rec.slice(seg.t_start, seg.t_end)
    u, y = rec.effort[sl], rec.velocity[sl]
    names_in = [f'tau_m/{rec.joint_names[j]}']
    names_out = [f'dq_m/{n}' for n in rec.joint_names]
    if info['design'] == 'detected_multisine':
        n_per, n_q = info['period_samples'], info['periods']
        skip = 1 if n_q >= 3 else 0      # the first period carries the start-up transient
        n_q -= skip
        x0 = skip * n_per
        bins = np.asarray(info['harmonics'])
        U = periodic_spectra(u[x0:x0 + n_q * n_per].reshape(n_q, n_per, -1), bins, axis=1)
        Y = periodic_spectra(y[x0:x0 + n_q * n_per].reshape(n_q, n_per, -1), bins, axis=1)
        # keep the lines the input really excites (a detection may add weak leakage lines)
        pj = np.mean(np.abs(U[:, :, j]) ** 2, axis=0)
        keep = pj >= 1e-2 * np.median(pj)
        bins, U, Y = bins[keep], U[:, keep], Y[:, keep]
        _check_single_input(U.mean(axis=0), j, rec.joint_names[j])
        # H1 over the periods at each line: sum Y conj(U_j) / sum |U_j|^2
        Uj = U[:, :, j]
        P = np.einsum('qfo,qf->of', Y, np.conj(Uj)) / np.sum(np.abs(Uj) ** 2, axis=0)
        var = None
        if n_q >= 2:
            Pq = Y / Uj[:, :, None]
            var = (np.var(Pq, axis=0, ddof=1) / n_q).T[:, None, :]
        return FrequencyResponse(bins * info['f0'], P[:, None, :], names_in, names_out, var,
                                 None, {'design': 'detected_multisine', 'periods': n_q,
                                        'transient_periods': skip})
    design = ChirpDesign(info['f_low'], info['f_high'], info['t1'] - info['t0'],
                         np.ones((1, 1)), t0=info['t0'])
    freqs = chirp_analysis_frequencies(reference_frequency_set(info['f_low'], info['f_high']),
                                       design.time_at, info['t0'], info['t1'])
    tc = design.time_at(freqs)            # detection times count from the first sample
    U = chirp_spectra(rec.effort, rec.fs, freqs, tc)
    Y = chirp_spectra(rec.velocity, rec.fs, freqs, tc)
    _check_single_input(U, j, rec.joint_names[j])
    P = (Y / U[:, j:j + 1]).T[:, None, :]
    return FrequencyResponse(freqs, P, names_in, names_out, meta={'design': 'detected_chirp'})
