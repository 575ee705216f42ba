"""Closed-loop FRF estimation from a Recording (Sections 4.3, 4.4, 5.1, 7).

Works only from what a bag holds: the time series and the experiment segments. So estimation
from a bag equals estimation from the in-memory run.

- :func:`multisine_frf` — BLA over realisations x periods, optionally with the
  constant-velocity run subtracted (periodic-disturbance compensation, Sec. 4.4 E), by the
  reference-based estimator or the plain Y U^+ (eq. 7)
- :func:`chirp_frf` — Sec. 5.1 processing of a chirp iteration's experiments
- :func:`estimate_recording` — every estimate a recording supports
"""
from __future__ import annotations

from typing import Any

import numpy as np

from frf_ident.core.chirp import ChirpDesign
from frf_ident.core.estimation import (BLAResult, best_linear_approximation,
                                       best_linear_approximation_reference, chirp_spectra,
                                       detection_line_levels, frf_from_reference,
                                       frf_from_spectra, periodic_spectra)
from frf_ident.core.frd import FrequencyResponse
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import EstimationError


def _names(rec: Recording) -> tuple[list[str], list[str]]:
    return ([f'tau_m/{j}' for j in rec.joint_names], [f'dq_m/{j}' for j in rec.joint_names])


def _segment_arrays(rec: Recording, seg: Segment) -> dict[str, np.ndarray]:
    sl = rec.slice(seg.t_start, seg.t_end)
    exc = rec.excitation if rec.excitation is not None else rec.reference
    if exc is None:
        raise EstimationError('recording has no reference/excitation to estimate from')
    return {'u': rec.effort[sl], 'y': rec.velocity[sl], 'r': exc[sl], 'q': rec.position[sl]}


def _disturbance_at(cv: dict[str, np.ndarray], key: str, q: np.ndarray,
                    align: str) -> np.ndarray:
    """The constant-velocity run's series to subtract (Sec. 4.4 E).

    align 'time': sample by sample, as the paper does. 'position': per axis, the run's series
    read at the excited run's positions (the run moves monotonically, so position maps to
    time): position-periodic disturbances such as torque ripple then cancel even when the
    excited run starts a little elsewhere or the multisine displaces it.
    """
    x = cv[key][:q.shape[0]]
    if align == 'time':
        return x
    out = np.empty_like(x)
    for i in range(q.shape[1]):
        qc = cv['q'][:, i]
        if np.all(np.diff(qc) > 0):
            out[:, i] = np.interp(q[:, i], qc, cv[key][:, i])
        elif np.all(np.diff(qc) < 0):
            out[:, i] = np.interp(q[::-1, i][::-1], qc[::-1], cv[key][::-1, i])
        else:
            out[:, i] = x[:, i]          # not monotonic: fall back to time alignment
    return out


def multisine_periods(rec: Recording, *, compensate: bool = True, align: str = 'position'
                      ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Per (p, m) segment: the measured periods after the transient, compensated by the
    constant-velocity run when requested (``align`` see :func:`_disturbance_at`). Returns
    arrays shaped (n_p, n_ex, n_q, N, n)."""
    segs = [s for s in rec.segments if s.info.get('design') == 'multisine']
    if not segs:
        raise EstimationError('recording has no multisine segments')
    info = segs[0].info
    n_per, n_q, n_tr = info['period_samples'], info['periods'], info['transient_periods']
    n_p = 1 + max(s.info['realisation'] for s in segs)
    n_ex = 1 + max(s.info['experiment'] for s in segs)
    n = len(rec.joint_names)
    cv = None
    if compensate:
        cv_segs = [s for s in rec.segments if s.info.get('design') == 'constant_velocity']
        if not cv_segs:
            raise EstimationError('compensation requested but the recording has no '
                                  'constant-velocity run')
        cv = _segment_arrays(rec, cv_segs[0])
    out = {k: np.full((n_p, n_ex, n_q, n_per, n), np.nan) for k in ('u', 'y', 'r')}
    for s in segs:
        a = _segment_arrays(rec, s)
        need = (n_tr + n_q) * n_per
        if a['u'].shape[0] < need:
            raise EstimationError(f'multisine segment at t={s.t_start:.3f} s has '
                                  f'{a["u"].shape[0]} samples, expected {need} '
                                  f'({n_tr} transient + {n_q} periods of {n_per})')
        for k in ('u', 'y', 'r'):
            x = a[k][:need]
            if cv is not None and k != 'r':
                x = x - _disturbance_at(cv, k, a['q'][:need], align)
            out[k][s.info['realisation'], s.info['experiment']] = \
                x[n_tr * n_per:].reshape(n_q, n_per, n)
    if np.isnan(out['u']).any():
        raise EstimationError(f'multisine segments incomplete: expected {n_p} realisations x '
                              f'{n_ex} experiments')
    return out, info


def multisine_frf(rec: Recording, *, compensate: bool = True, method: str = 'reference',
                  align: str = 'position') -> tuple[FrequencyResponse, BLAResult]:
    """Multisine best linear approximation (eq. 14) of the closed-loop data.

    method 'reference': P_p = (sum_q Y R^H)(sum_q U R^H)^-1 per realisation, averaged over p;
    'plain': P[p,q] = Y U^+ (eq. 7) per period, averaged over p and q.
    """
    data, info = multisine_periods(rec, compensate=compensate, align=align)
    bins = np.asarray(info['design_params']['harmonics'])
    spec = {k: np.moveaxis(periodic_spectra(v, bins, axis=3), 1, -1)
            for k, v in data.items()}                         # (p, q, F, n, n_ex)
    if method == 'reference':
        bla = best_linear_approximation_reference(spec['y'], spec['u'], spec['r'])
    elif method == 'plain':
        bla = best_linear_approximation(spec['y'], spec['u'])
    else:
        raise ValueError(f"{method=} must be 'reference' or 'plain'")
    ins, outs = _names(rec)
    f0 = info['design_params']['f0']
    det = detection_line_levels(data['y'][:, 0], bins, int(bins[-1]))
    frf = FrequencyResponse(bins * f0, bla.response, ins, outs, bla.noise_variance,
                            bla.total_variance, {
                                'design': 'multisine', 'method': method,
                                'compensated': compensate, 'alignment': align,
                                'n_p': int(data['u'].shape[0]), 'n_q': int(data['u'].shape[2]),
                                'cond_max': float(np.max(bla.cond)),
                                'detection_lines': det.to_dict()})
    return frf, bla


def chirp_iterations(rec: Recording) -> list[int]:
    return sorted({s.info['iteration'] for s in rec.segments if s.info.get('design') == 'chirp'})


def chirp_frf(rec: Recording, *, iteration: int | None = None, method: str = 'plain',
              path: str = 'u->y') -> FrequencyResponse:
    """Chirp estimate of one iteration (default: the last) by the Sec. 5.1 processing.

    path 'u->y' is the plant P (eq. 7, or reference-based with method='reference'),
    'r->u' the transfer the iteration inverts (eq. 18).
    """
    its = chirp_iterations(rec)
    if not its:
        raise EstimationError('recording has no chirp segments')
    it = its[-1] if iteration is None else iteration
    segs = sorted((s for s in rec.segments if s.info.get('design') == 'chirp'
                   and s.info['iteration'] == it), key=lambda s: s.info['experiment'])
    info = segs[0].info
    design = ChirpDesign.from_dict(info['design_params'])
    freqs = np.asarray(info['freq_hz'])
    tc = design.time_at(freqs)
    fs = rec.fs
    S = {k: [] for k in ('u', 'y', 'r')}
    for s in segs:
        a = _segment_arrays(rec, s)
        for k in S:
            S[k].append(chirp_spectra(a[k], fs, freqs, tc))
    Y, U, R = (np.stack(S[k], axis=-1) for k in ('y', 'u', 'r'))
    ins, outs = _names(rec)
    if path == 'r->u':
        P, cond = frf_from_spectra(U, R)
        ins = [f'r/{j}' for j in rec.joint_names]
        outs = [f'tau_m/{j}' for j in rec.joint_names]
    elif method == 'reference':
        P, cond = frf_from_reference(Y, U, R)
    elif method == 'plain':
        P, cond = frf_from_spectra(Y, U)
    else:
        raise ValueError(f"{method=} must be 'reference' or 'plain'")
    return FrequencyResponse(freqs, P, ins, outs, meta={
        'design': 'chirp', 'iteration': it, 'method': method, 'path': path,
        'cond_max': float(np.max(cond))})


def estimate_recording(rec: Recording, *, options=None) -> dict[str, FrequencyResponse]:
    """Every estimate the recording supports, keyed by name. The data are checked first
    (:func:`frf_ident.core.checks.check_descriptor_recording`: band, periods, clipping).
    ``options`` (:class:`frf_ident.core.foreign.ExcitationOptions`) replace detection in a
    recording without descriptors; a recording with descriptors refuses them."""
    from frf_ident.core.checks import check_descriptor_recording
    if any(s.info.get('design') in ('multisine', 'chirp') for s in rec.segments):
        if options is not None and options.given():
            raise EstimationError(f'{options.text()}: the recording has experiment descriptors; '
                                  f'expected excitation options only without them')
        check_descriptor_recording(rec)
    out: dict[str, FrequencyResponse] = {}
    if any(s.info.get('design') == 'multisine' for s in rec.segments):
        has_cv = any(s.info.get('design') == 'constant_velocity' for s in rec.segments)
        out['multisine'] = multisine_frf(rec, compensate=has_cv)[0]
        out['multisine_plain'] = multisine_frf(rec, compensate=has_cv, method='plain')[0]
        if has_cv:
            out['multisine_uncompensated'] = multisine_frf(rec, compensate=False)[0]
    if chirp_iterations(rec):
        out['chirp'] = chirp_frf(rec)
        out['chirp_reference'] = chirp_frf(rec, method='reference')
    if not out:
        out = estimate_detected(rec, options)
    return out


def estimate_detected(rec: Recording, options=None) -> dict[str, FrequencyResponse]:
    """Estimates of a recording without descriptors: the excitation is detected per joint
    (:mod:`frf_ident.core.foreign`; ``options`` replace detection where given) and checked;
    one entry 'detected/<joint>' per excited input, the detection sentences in each
    estimate's meta['detected']."""
    from frf_ident.core.foreign import check_detected_segment, detect_segments, detected_frf
    segments, notes = detect_segments(rec, options)
    for seg in segments:
        check_detected_segment(rec, seg)
    out = {}
    for seg in segments:
        frf = detected_frf(rec, seg)
        frf.meta['detected'] = notes
        out[f"detected/{rec.joint_names[seg.info['input']]}"] = frf
    return out
