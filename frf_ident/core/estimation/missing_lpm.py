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
The Local Polynomial Method with missing output samples (Ugryumova, Pintelon, Vandersteen).

After A. Ugryumova, R. Pintelon, G. Vandersteen, *Frequency response function estimation in
the presence of missing output data*, IEEE Trans. Instrum. Meas. 64(2), 2015: the outputs z
of a frame miss M samples (the same instants t_m in every channel), the regressor x (the
reference r of the indirect estimate, the input u of the direct one) is complete. With Z0 the
DFT of z with zeros at the missing samples and E[k, m] = exp(-2 pi i k t_m / N) / sqrt(N),
the complete spectrum is Z0 + E z_m, and the LPM model of every window w of lines,

    Z0(k) + E(k) z_m = G_w(k) X(k) + T_w(k) + V(k),   G_w, T_w polynomials of degree R,

makes the missing samples z_m extra real unknowns shared by all windows (the local G and T
are each window's own). Over non-overlapping windows covering the lines 1..N/2 the local
parameters are eliminated (P_w: projection onto the window's residual space) and

    A z_m = -Re(E^H P Z0),   A = Re(E^H P E),   P = blockdiag(P_w),

is solved for all channels at once (A depends on the instants and the regressor only). A is
formed without E: (E^H E)[m, m'] and (E^H (I - P) E)[m, m'] depend on t_m - t_m' and the
d-th diagonal of the block-diagonal I - P, so one inverse FFT per diagonal (2 W - 1 of them)
gives every entry (:func:`_normal_matrix`, compiled). Then

- the noise covariance Sigma (per line) from the residual over those windows, with
  2 sum_w (W - p) - M real degrees of freedom (M lost to the missing samples);
- Cov(z_m - true) = Sigma / 2 A^-1 (their own noise is unobserved: the prediction error), the
  standard deviation :attr:`MissingLpm.sd`;
- the LPM (:func:`~frf_ident.core.estimation.lpm.lpm_lines`) of the spectra with the
  estimates in place, its residual noise covariance scaled by q / (q - M / 2) (the dof the
  estimates took, q = sum_w (W - p)) and the covariance of the estimates' error at each
  line, s(k) Sigma, added: what the FRF's variance propagates.

A missing sample of the regressor is outside this model (the response to it would reach
beyond the gap); the callers say so where they meet one.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.estimation.lpm import default_half_width, DEFAULT_ORDER, lpm_lines, LpmLines
from frf_ident.core.estimation.missing import MissingSamples
from frf_ident.errors import EstimationError
import numba
import numpy as np
from scipy import linalg
from scipy.linalg import lapack

__all__ = ['MAX_MISSING_SAMPLES', 'MIN_PIVOT', 'MissingLpm', 'lpm_missing']

#: most missing samples one frame may hold: the normal matrix is M x M and its factor and
#: inverse cost M^3, seconds per frame at a few thousand on one core (``python -m benchmarks
#: missing`` times them); a frame with more is refused (its caller drops it and says so)
MAX_MISSING_SAMPLES = 4096

#: smallest Cholesky pivot of the scaled normal matrix (its diagonal is ~1/2) accepted: below
#: it some missing samples are indistinguishable from the local model (e.g. a gap at the start
#: of a frame, where the transient term can take any value) and their estimate is not
#: determined by the data
MIN_PIVOT = 1e-6


@dataclass
class MissingLpm:
    """
    The LPM of a frame with missing output samples, and the samples' estimates.

    Attributes
    ----------
    lines : LpmLines
        The LPM of the spectra with the estimates in place (lines 1..N/2); its
        ``noise_cov`` holds the residual noise covariance corrected for the dof the estimates
        took, plus the covariance of their error at each line.
    index : ndarray of int, shape (M,)
        The missing samples.
    values : ndarray, shape (M, n_z)
        Their estimates.
    sd : ndarray, shape (M, n_z)
        Standard deviation of estimate minus true sample.
    noise : ndarray, complex, shape (n_z, n_z)
        Noise covariance per line (1/sqrt(N)-scaled DFT; white noise of variance s^2 per sample
        gives s^2 on the diagonal) from the residual over the estimation windows.
    noise_dof : int
        Its real degrees of freedom.

    """

    lines: LpmLines
    index: np.ndarray
    values: np.ndarray
    sd: np.ndarray
    noise: np.ndarray
    noise_dof: int

    def account(self, channels: list[str], n_samples: int) -> MissingSamples:
        """
        Return the :class:`~frf_ident.core.estimation.missing.MissingSamples` of this frame.

        Parameters
        ----------
        channels : list of str
            Names of the output channels.
        n_samples : int
            Samples in the frame.

        Returns
        -------
        MissingSamples

        """
        m = self.index.size
        var = np.real(np.diag(self.noise))
        return MissingSamples(m, int(n_samples), int(m > 0), 1, 'frame', list(channels),
                              np.sum(self.sd ** 2, axis=0), var * self.noise_dof / 2,
                              np.full(var.size, self.noise_dof / 2), 'lpm')


def _windows(n_lines: int, half_width: int) -> list[tuple[int, int]]:
    """Return non-overlapping windows of 2 n + 1 lines covering all lines (rest in the last)."""
    w = 2 * half_width + 1
    starts = list(range(0, n_lines - w + 1, w))
    bounds = [(a, a + w) for a in starts]
    bounds[-1] = (bounds[-1][0], n_lines)
    return bounds


def _regressors(X: np.ndarray, a: int, b: int, order: int, transient: bool) -> np.ndarray:
    """Return the local model's columns on lines a..b-1: X (r/h)^s and (r/h)^s."""
    r = np.arange(a, b) - (a + b - 1) / 2
    pw = (r / max(np.max(np.abs(r)), 1.0))[:, None] ** np.arange(order + 1)     # (W, R+1)
    cols = [X[i, a:b, None] * pw for i in range(X.shape[0])]
    if transient:
        cols.append(pw.astype(complex))
    return np.concatenate(cols, axis=1)


@numba.njit(cache=True)
def _normal_matrix(t, n, D, F, phase):  # pragma: no cover - compiled
    """Return A[a, b] = Re(D(t_a - t_b) - sum_d phase[d, b] F[d, t_a - t_b]) (compiled)."""
    m = t.size
    A = np.empty((m, m))
    for a in range(m):
        for b in range(a, m):
            tau = (t[a] - t[b]) % n
            v = D[tau]
            for j in range(F.shape[0]):
                v -= phase[j, b] * F[j, tau]
            A[a, b] = v.real
            A[b, a] = v.real
    return A


def _spread(Q: list[np.ndarray], bounds: list[tuple[int, int]], n: int, width: int
            ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the offsets d and f_d(tau) = 1/N sum_k (I - P)[k, k + d] exp(2 pi i k tau / N).

    Line i is DFT bin i + 1; (I - P) is the block-diagonal Q Q^H of the windows.
    """
    offsets = np.arange(-(width - 1), width)
    a = np.zeros((offsets.size, n), complex)
    for (lo, hi), q in zip(bounds, Q):
        proj = q @ np.conj(q).T                                        # (W, W)
        for j, d in enumerate(offsets):
            if abs(d) < hi - lo:
                diag = np.diagonal(proj, offset=d)
                first = lo + max(0, -d)
                a[j, first + 1:first + 1 + diag.size] = diag
    return offsets, np.fft.ifft(a, axis=1)


def lpm_missing(z: np.ndarray, x: np.ndarray, missing: np.ndarray | None = None, *,
                order: int = DEFAULT_ORDER, half_width: int | None = None,
                transient: bool = True) -> MissingLpm:
    """
    Estimate the FRF of z on x by the LPM with the missing samples of z as extra unknowns.

    Parameters
    ----------
    z : array_like, shape (N, n_z)
        Outputs of one frame (NaN, or anything, at the missing samples).
    x : array_like, shape (N, n_x)
        The regressor (complete).
    missing : array_like of bool, shape (N,), optional
        The missing samples; default the rows of z holding a NaN.
    order, half_width, transient
        As :func:`~frf_ident.core.estimation.lpm.lpm_lines`.

    Returns
    -------
    MissingLpm
        The LPM per line and the missing samples' estimates with their standard deviations.

    Raises
    ------
    EstimationError
        A missing regressor sample, or missing samples the data do not determine.

    """
    z = np.asarray(z, float).reshape(len(z), -1)
    x = np.asarray(x, float).reshape(len(x), -1)
    gone = np.any(~np.isfinite(z), axis=1) if missing is None else np.asarray(missing, bool)
    if not np.all(np.isfinite(x)):
        raise EstimationError(f'{int(np.sum(~np.isfinite(x).all(axis=1)))} regressor samples '
                              f'missing; expected a complete regressor (only outputs may '
                              f'miss samples)')
    n = z.shape[0]
    t = np.flatnonzero(gone)
    z0 = np.where(gone[:, None], 0.0, z)
    Z0 = np.fft.rfft(z0, axis=0)[1:].T / np.sqrt(n)                   # (n_z, L)
    X = np.fft.rfft(x, axis=0)[1:].T / np.sqrt(n)
    hw = default_half_width(X.shape[0], order, transient) if half_width is None \
        else int(half_width)
    if t.size == 0:
        fit = lpm_lines(Z0, X, order=order, half_width=hw, transient=transient)
        empty = np.empty((0, z.shape[1]))
        return MissingLpm(fit, t, empty, empty, np.zeros((z.shape[1],) * 2, complex), 0)
    if t.size > MAX_MISSING_SAMPLES:
        raise EstimationError(f'{t.size} missing samples in a frame of {n}: more than '
                              f'{MAX_MISSING_SAMPLES} (MAX_MISSING_SAMPLES, the cost of '
                              f'estimating them grows with their cube); expected fewer')
    bounds = _windows(Z0.shape[1], hw)
    Q = [np.linalg.qr(_regressors(X, a, b, order, transient))[0] for a, b in bounds]
    p = Q[0].shape[1]
    resid = sum(b - a - p for a, b in bounds)                          # complex dof
    if 2 * resid - t.size < 1:
        raise EstimationError(f'{t.size} missing samples of {n}: more unknowns than the '
                              f'{2 * resid} real degrees of freedom the local model leaves; '
                              f'expected fewer missing samples')
    A = _scaled_normal(t, n, Q, bounds, hw)
    try:
        chol = linalg.cho_factor(A, lower=True, check_finite=False)
    except linalg.LinAlgError:
        chol = None
    if chol is None or np.min(np.diag(chol[0])) ** 2 < MIN_PIVOT:
        raise EstimationError(f'{t.size} missing samples at {t[0] / n:.0%}..{t[-1] / n:.0%} of '
                              f'the frame are not determined by the data (the local model '
                              f'can take them); expected gaps away from its ends')
    rhs = -np.real(_adjoint(_project(Z0, Q, bounds), t, n))            # (M, n_z)
    values = linalg.cho_solve(chol, rhs, check_finite=False)
    zc = z0.copy()
    zc[t] = values
    Zc = np.fft.rfft(zc, axis=0)[1:].T / np.sqrt(n)
    e = _project(Zc, Q, bounds)
    dof = 2 * resid - t.size
    noise = 2 * (e @ np.conj(e).T) / dof                                # (n_z, n_z)
    ainv, info = lapack.dpotri(chol[0], lower=1)          # A^-1 from the factor, lower half
    ainv = np.tril(ainv) + np.tril(ainv, -1).T
    sd = np.sqrt(np.clip(np.diag(ainv)[:, None] * np.real(np.diag(noise))[None, :] / 2, 0,
                         None))
    fit = lpm_lines(Zc, X, order=order, half_width=hw, transient=transient)
    s = _error_spectrum(ainv, t, n)[:fit.G.shape[-1]]                   # (L,)
    cov = fit.noise_cov * (resid / (resid - t.size / 2) + s[:, None, None])
    return MissingLpm(LpmLines(fit.G, cov, fit.minv, fit.dof), t, values, sd, noise, dof)


def _scaled_normal(t: np.ndarray, n: int, Q: list[np.ndarray],
                   bounds: list[tuple[int, int]], hw: int) -> np.ndarray:
    """Return A = Re(E^H P E) for the instants t (lines 1..N/2 in windows ``bounds``)."""
    ind = np.zeros(n)
    ind[1:bounds[-1][1] + 1] = 1.0
    D = np.fft.ifft(ind)
    width = max(b - a for a, b in bounds)
    offsets, F = _spread(Q, bounds, n, width)
    phase = np.exp(-2j * np.pi * np.outer(offsets, t) / n)
    return _normal_matrix(t.astype(np.int64), n, D, F, phase)


def _project(Z: np.ndarray, Q: list[np.ndarray], bounds: list[tuple[int, int]]) -> np.ndarray:
    """Return P Z, each window's part of Z orthogonal to its local model (n_z, L)."""
    out = np.empty_like(Z)
    for (a, b), q in zip(bounds, Q):
        w = Z[:, a:b]
        out[:, a:b] = w - (w @ np.conj(q)) @ q.T
    return out


def _adjoint(V: np.ndarray, t: np.ndarray, n: int) -> np.ndarray:
    """Return E^H V at the instants t: sum_k exp(2 pi i k t / N) V(k) / sqrt(N)."""
    a = np.zeros((V.shape[0], n), complex)
    a[:, 1:V.shape[1] + 1] = V
    return (np.fft.ifft(a, axis=1) * n / np.sqrt(n))[:, t].T


def _error_spectrum(ainv: np.ndarray, t: np.ndarray, n: int) -> np.ndarray:
    """Return s(k) = 1/(2N) sum A^-1[m, m'] exp(-2 pi i k (t_m - t_m') / N), lines 1..."""
    lag = (t[:, None] - t[None, :]) % n
    c = np.bincount(lag.ravel(), weights=ainv.ravel(), minlength=n)
    return np.real(np.fft.fft(c))[1:] / (2 * n)
