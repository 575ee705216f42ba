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
Non-parametric FRF estimation (Saupe & Knoblach 2015, Sections 3, 4.3 and 5.1).

- :func:`frf_from_spectra` — eq. 7, P(w_k) = Y(w_k) U(w_k)^+ per line, with cond(U)
- :func:`frf_from_reference` — closed-loop estimate P = (Y R^H)(U R^H)^-1 that uses the
  reference r, so output noise fed back through the controller does not bias P
- :func:`periodic_spectra` — DFT of whole periods at given bins (no leakage)
- :func:`best_linear_approximation` — eq. 14 over n_p realisations x n_q periods, with the
  noise variance (from periods) and total / nonlinear variance (from realisations)
- :func:`detection_line_levels` — output levels at non-excited odd and even lines

The chirp's Sec. 5.1 processing (excerpt DFTs) is :mod:`frf_ident.core.excitation.chirp_dft`,
beside the chirp design: the chirp iteration needs it before anything is estimated.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.errors import EstimationError
import numpy as np


def frf_from_spectra(Y: np.ndarray, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    FRF P(w_k) = Y(w_k) U(w_k)^+ on every line (eq. 7).

    Parameters
    ----------
    Y
        (n_freq, n_y, n_ex) output spectra, experiments stacked as columns.
    U
        (n_freq, n_u, n_ex) input spectra.

    Returns
    -------
    P : (n_y, n_u, n_freq) and cond : (n_freq,) condition number of U(w_k).

    """
    Y = np.asarray(Y, dtype=complex)
    U = np.asarray(U, dtype=complex)
    if Y.ndim != 3 or U.ndim != 3 or Y.shape[0] != U.shape[0] or Y.shape[2] != U.shape[2]:
        raise EstimationError(f'spectra shapes {Y.shape=} {U.shape=} must be '
                              f'(n_freq, n_y, n_ex) and (n_freq, n_u, n_ex)')
    n_u, n_ex = U.shape[1], U.shape[2]
    if n_ex < n_u:
        raise EstimationError(f'{n_ex=} experiments cannot identify {n_u=} inputs (eq. 7 needs '
                              f'n_ex >= n_u)')
    sv = np.linalg.svd(U, compute_uv=False)
    cond = sv[:, 0] / np.maximum(sv[:, -1], 1e-300)
    P = Y @ np.linalg.pinv(U)
    return np.moveaxis(P, 0, -1), cond


def frf_from_reference(Y: np.ndarray, U: np.ndarray,
                       R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Closed-loop FRF through the reference: P = (Y R^H)(U R^H)^-1 per line.

    Equivalent to P = S_yr S_ur^-1 (indirect / joint input-output method): noise that the
    controller feeds back into u is uncorrelated with r and drops out, while Y U^+ is biased
    towards -1/K where the output noise dominates.

    Shapes as :func:`frf_from_spectra`, R : (n_freq, n_r, n_ex). Returns (P, cond(U R^H)).
    """
    Y = np.asarray(Y, dtype=complex)
    U = np.asarray(U, dtype=complex)
    R = np.asarray(R, dtype=complex)
    RH = np.conj(np.swapaxes(R, 1, 2))
    Syr = Y @ RH
    Sur = U @ RH
    sv = np.linalg.svd(Sur, compute_uv=False)
    cond = sv[:, 0] / np.maximum(sv[:, -1], 1e-300)
    P = Syr @ np.linalg.pinv(Sur)
    return np.moveaxis(P, 0, -1), cond


def periodic_spectra(x: np.ndarray, bins: np.ndarray, axis: int = -2) -> np.ndarray:
    """
    DFT coefficients of whole periods at the given bins (Sec. 4.2; mean removal is implicit).

    ``x`` holds an integer number of samples per period along ``axis``; the result has that
    axis replaced by the bins (scaled by 1/N: a sine of amplitude A gives |X| = A/2).
    """
    x = np.asarray(x, dtype=float)
    n = x.shape[axis]
    X = np.fft.rfft(x, axis=axis) / n
    return np.take(X, np.asarray(bins), axis=axis)


@dataclass
class BLAResult:
    """
    Best linear approximation (eq. 14) with its variances, all (n_y, n_u, n_freq).

    ``noise_variance`` is the variance of the BLA estimate due to noise (from the spread over
    periods), ``total_variance`` that due to noise plus stochastic nonlinear contributions
    (from the spread over realisations), ``nonlinear_variance`` their difference (>= 0).
    ``cond`` (n_p, n_freq) is cond(U) per realisation.
    """

    response: np.ndarray
    noise_variance: np.ndarray | None
    total_variance: np.ndarray | None
    nonlinear_variance: np.ndarray | None
    cond: np.ndarray
    per_realisation: np.ndarray


def _realisations(X, name: str, ndim: int = 4) -> list[np.ndarray]:
    """
    Split an array into per-realisation arrays.

    Per-realisation arrays (n_q_p, ...) of a (n_p, n_q, ...) array or of a sequence of
    them (realisations may keep different numbers of periods when gaps removed some).
    """
    out = [np.asarray(x, dtype=complex) for x in X]
    if not out or any(x.ndim != ndim for x in out):
        raise EstimationError(f'{name}: expected (n_p, n_q, n_freq, n, n_ex) spectra or one '
                              f'(n_q, n_freq, n, n_ex) array per realisation, got '
                              f'{[x.shape for x in out]}')
    return out


def best_linear_approximation(Y, U, *, filled=None) -> BLAResult:
    """
    Multisine BLA P_l = 1/(n_p n_q) sum_p sum_q P[p,q] (eq. 14) with variances.

    Parameters
    ----------
    Y : (n_p, n_q, n_freq, n_y, n_ex) output spectra per realisation p and period q, or one
        (n_q_p, n_freq, n_y, n_ex) array per realisation (periods removed by gaps).
    U
        Input spectra, shaped alike with n_u.
    filled : list of FilledPeriods, optional
        Per realisation, what estimated missing samples do to the spread over its periods
        (:class:`frf_ident.core.estimation.missing_periodic.FilledPeriods`); the noise
        variance is corrected for them.

    Returns
    -------
    BLAResult
        The spectra of each period give P[p,q] by eq. 7 and P_p is their mean over q.
        Following Pintelon & Schoukens' robust method, the spread over q (pooled over the
        realisations, each with its own n_q) gives the noise variance and the sample
        variance over p of the P_p the total variance of the estimate.

    """
    Ys, Us = _realisations(Y, 'Y'), _realisations(U, 'U')
    if len(Ys) != len(Us) or any(y.shape[:2] != u.shape[:2] for y, u in zip(Ys, Us)):
        raise EstimationError(f'spectra shapes {[y.shape for y in Ys]} and '
                              f'{[u.shape for u in Us]} do not match')
    Ppq, cond = [], []
    for Yp, Up in zip(Ys, Us):
        per = [frf_from_spectra(Yq, Uq) for Yq, Uq in zip(Yp, Up)]
        Ppq.append(np.array([P for P, _ in per]))
        cond.append(np.max([c for _, c in per], axis=0))
    Pp = np.array([P.mean(axis=0) for P in Ppq])
    return BLAResult(Pp.mean(axis=0), *_bla_variances(Ppq, Pp, filled), np.array(cond), Pp)


def _bla_variances(Ppq, Pp: np.ndarray, filled=None):
    """
    Compute the variances of the eq. 14 mean.

    (noise, total, nonlinear) variances of the eq. 14 mean from per-period estimates Ppq
    (one (n_q_p, ...) array per realisation) and per-realisation estimates Pp (n_p, ...);
    None where fewer than two periods / realisations.

    The per-period variance is pooled over the realisations (sum of squares over
    sum(n_q_p - 1)); the variance of P_p is that over n_q_p, of the mean over p the sum over
    p divided by n_p^2 (equal n_q: the usual sum_p var_q / (n_q (n_q - 1)) / n_p^2).
    With ``filled`` (per realisation, :class:`~frf_ident.core.estimation.missing_periodic.
    FilledPeriods`), periods holding estimated missing samples: the dof loses their share
    and each realisation's variance its factor.
    """
    n_p = Pp.shape[0]
    nq = np.array([P.shape[0] for P in Ppq])
    noise_var = total_var = nl_var = None
    dof = int(np.sum(nq - 1))
    if dof >= 1:
        ss = sum(np.sum(np.abs(P - P.mean(axis=0)) ** 2, axis=0) for P in Ppq)
        if filled is None:
            noise_var = ss / dof * np.sum(1.0 / nq) / n_p ** 2
        else:
            left = dof - sum(float(np.sum(f.lost)) for f in filled)
            noise_var = (ss / left if left > 0 else np.inf * ss) * np.sum(
                [np.mean(f.factor) / n for f, n in zip(filled, nq)]) / n_p ** 2
    if n_p >= 2:
        total_var = np.sum(np.abs(Pp - Pp.mean(axis=0)) ** 2, axis=0) / (n_p - 1) / n_p
        if noise_var is not None:
            nl_var = np.maximum(total_var - noise_var, 0.0)
    return noise_var, total_var, nl_var


def best_linear_approximation_reference(Y, U, R, *, filled=None) -> BLAResult:
    """
    Estimate the closed-loop BLA through the reference.

    Closed-loop BLA through the reference: P_p = (sum_q Y R^H)(sum_q U R^H)^-1, then eq. 14
    over realisations.

    Shapes as :func:`best_linear_approximation` (arrays or one array per realisation), R with
    n_r. Averaging the cross spectra with r over the periods before inverting removes the
    noise that the controller feeds back into u (uncorrelated with r), which biases the
    per-period Y U^+. Noise variance from the spread of the per-period estimates (corrected
    for estimated missing samples by ``filled``, as :func:`best_linear_approximation`), total
    variance from the spread over realisations.
    """
    Ys, Us, Rs = _realisations(Y, 'Y'), _realisations(U, 'U'), _realisations(R, 'R')
    Pp, cond, Ppq = [], [], []
    for Yp, Up, Rp in zip(Ys, Us, Rs):
        RH = np.conj(np.swapaxes(Rp, -1, -2))
        Syr = Yp @ RH                                   # (q, F, n_y, n_r)
        Sur = Up @ RH
        Pp.append(np.moveaxis(Syr.mean(axis=0) @ np.linalg.pinv(Sur.mean(axis=0)), 0, -1))
        sv = np.linalg.svd(Sur.mean(axis=0), compute_uv=False)
        cond.append(sv[..., 0] / np.maximum(sv[..., -1], 1e-300))
        Ppq.append(np.moveaxis(Syr @ np.linalg.pinv(Sur), 1, -1))     # (q, n_y, n_u, F)
    Pp = np.array(Pp)
    return BLAResult(Pp.mean(axis=0), *_bla_variances(Ppq, Pp, filled), np.array(cond), Pp)


@dataclass
class DetectionLevels:
    """
    Mean output power (per output channel) at excited, non-excited odd and even lines.

    Energy at non-excited odd lines reveals odd nonlinearities (friction, stiffness,
    saturation), at even lines even ones (asymmetry, gravity-dependent effects); the noise level
    is the period-to-period variance. All are power spectral levels |Y|^2 averaged over lines
    and realisations; ``*_db`` relative to the excited level.
    """

    excited: np.ndarray
    odd: np.ndarray
    even: np.ndarray
    noise: np.ndarray | None

    def to_dict(self) -> dict:
        ex = np.maximum(self.excited, 1e-300)

        def db(x):
            return (10 * np.log10(np.maximum(x, 1e-300) / ex)).tolist()
        d = {'excited_power': self.excited.tolist(), 'odd_db': db(self.odd),
             'even_db': db(self.even)}
        if self.noise is not None:
            d['noise_db'] = db(self.noise)
        return d


def detection_line_levels(y_periods: np.ndarray, excited_bins: np.ndarray,
                          max_bin: int) -> DetectionLevels:
    """
    Levels at excited, non-excited odd and even detection lines (Sec. 4.3 remark).

    ``y_periods`` : (n_p, n_q, N, n_y) output time series, N samples = one period.
    Lines above ``max_bin`` (the top of the band) are ignored; DC is excluded.
    """
    bins, Y = detection_line_spectra(y_periods, max_bin, axis=2)
    return detection_levels_from_spectra(Y, bins, excited_bins)


def detection_line_spectra(y_periods: np.ndarray, max_bin: int, *, axis: int = -2
                           ) -> tuple[np.ndarray, np.ndarray]:
    """
    Compute the DFT of whole periods at the detection bins.

    Bins 1..min(max_bin, N/2) and the DFT of whole periods there (the input of
    :func:`detection_levels_from_spectra`; computable one segment at a time).
    """
    y = np.asarray(y_periods, dtype=float)
    n = y.shape[axis]
    bins = np.arange(1, min(max_bin, n // 2) + 1)
    return bins, periodic_spectra(y, bins, axis=axis)


def detection_levels_from_spectra(Y, bins: np.ndarray,
                                  excited_bins: np.ndarray) -> DetectionLevels:
    """
    Compute detection-line levels from period spectra.

    Detection-line levels from period spectra ``Y`` (n_p, n_q, n_bins, n_y), or one
    (n_q_p, n_bins, n_y) array per realisation, at ``bins``.
    """
    Ys = _realisations(Y, 'Y', ndim=3)
    n_y = Ys[0].shape[2]
    Ym = np.array([y.mean(axis=0) for y in Ys])
    power = np.mean(np.abs(Ym) ** 2, axis=0)
    excited = np.isin(bins, excited_bins)
    odd = (bins % 2 == 1) & ~excited
    even = bins % 2 == 0
    noise = None
    if all(y.shape[0] >= 2 for y in Ys):
        noise = np.mean([(np.var(y, axis=0, ddof=1).real / y.shape[0]).mean(axis=0)
                         for y in Ys], axis=0)
        noise = np.broadcast_to(noise, (n_y,)).copy()

    def level(mask):
        return power[mask].mean(axis=0) if np.any(mask) else np.full(n_y, np.nan)
    return DetectionLevels(level(excited), level(odd), level(even), noise)
