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
The Local Polynomial Method (Pintelon & Schoukens 2012, ch. 7) for arbitrary excitation.

Per DFT line k the output spectrum in the window k-n..k+n is modelled as

    Y(k+r) = G(k+r) U(k+r) + T(k+r) + V(k+r),
    G(k+r) = G_k + sum_{s=1..R} g_s r^s,   T(k+r) = T_k + sum_{s=1..R} t_s r^s,

with U the DFT of the inputs, T the transient (leakage) term and V the noise. Least squares
over the 2n+1 lines gives G_k, and the residual the noise covariance C_V(k) with
q = 2n+1 - (R+1)(n_in+1) degrees of freedom (the dof correction). Lines near the ends of the
spectrum use a window shifted to stay inside it. All lines are solved in one compiled pass
(numba): the normal equations of a line are built from the distinct window sums
sum_r conj(x_a) x_b (r/n)^t (slid from the previous line's), scaled to unit diagonal and
Cholesky-solved; no Python loop over lines (``python -m benchmarks lpm`` compares it with
per-line ``np.linalg.lstsq``).

- :func:`lpm_lines` — the LPM on given spectra (data first, every line)
- :func:`robust_lpm` — periodic records: noise and stochastic nonlinear variance of the BLA
  from one realisation (local polynomial over the excited lines)

Time records in frames (the direct or indirect estimate, averaged over frames, with the Welch
H1 baseline) are in :mod:`frf_ident.core.estimation.lpm_frames`; frames with missing output
samples in :mod:`frf_ident.core.estimation.missing_lpm`.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.robust_levels import RobustLpmLevels
from frf_ident.errors import EstimationError
import numba
import numpy as np

__all__ = ['DEFAULT_ORDER', 'LpmLines', 'RobustLpmResult',
           'default_half_width', 'lpm_lines', 'robust_lpm', 'robust_lpm_periods']

#: polynomial degree R of G and T in each window (P&S ch. 7 recommend R = 2: the bias of a
#: lightly damped mode falls as (resolution / 3 dB bandwidth)^(R+2))
DEFAULT_ORDER = 2

#: fewest residual degrees of freedom q per window; the noise covariance is estimated from
#: q lines, its relative spread 1/sqrt(q) (complex); 2 n_in + 2 keeps it near 30 % per line
#: for 3 inputs while the window stays narrow (P&S ch. 7: q >= n_out for a full covariance)
MIN_DOF_PER_INPUT = 2


def default_half_width(n_in: int, order: int = DEFAULT_ORDER, transient: bool = True) -> int:
    """
    Return the smallest half width n with q >= MIN_DOF_PER_INPUT * (n_in + 1).

    Parameters
    ----------
    n_in : int
        Number of inputs of the local model.
    order : int
        Polynomial degree R.
    transient : bool
        Whether the transient term is estimated too.

    Returns
    -------
    int
        Half width n of the window k-n..k+n.

    """
    n_par = (order + 1) * (n_in + int(transient))
    need = n_par + MIN_DOF_PER_INPUT * (n_in + 1)
    return int(np.ceil((need - 1) / 2))


@dataclass
class LpmLines:
    """
    The LPM per line: local G_k, its noise covariance and the dof.

    Attributes
    ----------
    G : ndarray, complex, shape (n_out, n_in, n_lines)
        The local FRF at the window centre.
    noise_cov : ndarray, complex, shape (n_lines, n_out, n_out)
        Covariance of the output noise V(k) (in the scaling of the given spectra), residual
        sum of squares over q.
    minv : ndarray, complex, shape (n_lines, n_in, n_in)
        The G_k block of (K K^H)^-1: Cov(G_k[i, :]) = noise_cov[i, i] minv (transposed).
    dof : int
        q = window - parameters.

    """

    G: np.ndarray
    noise_cov: np.ndarray
    minv: np.ndarray
    dof: int

    def variance(self) -> np.ndarray:
        """
        Return var(G_k[i, j]) = C_V[i, i] minv[j, j], shape (n_out, n_in, n_lines).

        Returns
        -------
        ndarray
            Variance of each element of G.

        """
        cv = np.real(np.einsum('kii->ik', self.noise_cov))
        mv = np.real(np.einsum('kjj->jk', self.minv))
        return cv[:, None, :] * mv[None, :, :]


#: a line's window sums are updated from the previous line's (one line out, one in, powers
#: of r re-centred); every RESUM_LINES lines they are summed afresh so rounding cannot grow
#: (the re-centring multiplies older rounding errors by up to (1 + RESUM_LINES / n)^(2R))
RESUM_LINES = 32


@numba.njit(cache=True)
def _accumulate(X, Y, j, x, sign, suu, suy, syy, pw):  # pragma: no cover - compiled
    """Add sign times line j at offset x = r / n to the window sums (compiled)."""
    pw[0] = sign
    for t in range(1, pw.size):
        pw[t] = pw[t - 1] * x
    n_c, n_out, R1 = suy.shape
    for a in range(n_c):
        ca = np.conj(X[a, j])
        for b in range(n_c):
            v = ca * X[b, j]
            for t in range(pw.size):
                suu[a, b, t] += v * pw[t]
        for i in range(n_out):
            v = ca * Y[i, j]
            for t in range(R1):
                suy[a, i, t] += v * pw[t]
    for i in range(n_out):
        ci = np.conj(Y[i, j]) * sign
        for i2 in range(n_out):
            syy[i, i2] += ci * Y[i2, j]


@numba.njit(cache=True)
def _shift(s, binom):  # pragma: no cover - compiled
    """Re-centre sums of x^t to sums of (x - h)^t along the last axis (compiled, in place)."""
    n1, n2, T = s.shape
    for a in range(n1):
        for b in range(n2):
            for t in range(T - 1, 0, -1):           # descending: s[.., :t] still old
                v = 0.0j
                for q in range(t + 1):
                    v += binom[t, q] * s[a, b, q]
                s[a, b, t] = v


@numba.njit(cache=True)
def _lpm_kernel(Y, U, n, order, transient):  # pragma: no cover - compiled
    """
    Solve the LPM normal equations of every line (compiled loop over lines).

    For line k the window k-n..k+n (shifted to stay inside the spectrum at its ends) gives
    M = K^H K, b = K^H Y^T and yy = Y^* Y^T from the distinct sums
    sum_r conj(x_a) x_b (r/n)^t (the regressors U_m (r/n)^s and (r/n)^s are never formed);
    M is scaled to unit diagonal (conditioning whatever the input levels), Cholesky
    factored and solved. Returns G_k (L, n_in, n_out), the residual sums
    S = sum conj(e_i) e_j (L, n_out, n_out) and the G_k block of M^-1 (L, n_in, n_in); a
    line whose M is singular (an input without power in its window) gives NaN.
    """
    n_out, n_lines = Y.shape
    n_in = U.shape[0]
    R1 = order + 1
    n_c = n_in + (1 if transient else 0)
    p = n_c * R1
    W = 2 * n + 1
    G = np.empty((n_lines, n_in, n_out), dtype=np.complex128)
    res = np.empty((n_lines, n_out, n_out), dtype=np.complex128)
    minv = np.empty((n_lines, n_in, n_in), dtype=np.complex128)
    X = np.ones((n_c, n_lines), dtype=np.complex128)       # the columns' factors
    X[:n_in] = U
    suu = np.zeros((n_c, n_c, 2 * order + 1), dtype=np.complex128)
    suy = np.zeros((n_c, n_out, R1), dtype=np.complex128)
    syy = np.zeros((n_out, n_out), dtype=np.complex128)
    pw = np.empty(2 * order + 1)
    M = np.empty((p, p), dtype=np.complex128)
    L = np.zeros((p, p), dtype=np.complex128)
    rhs = np.empty((p, n_out + n_in), dtype=np.complex128)
    d = np.empty(p)
    h = 1.0 / max(n, 1)
    binom = np.zeros((2 * order + 1, 2 * order + 1))   # (x - h)^t = sum_a binom[t, a] x^a
    for t in range(2 * order + 1):
        c = 1.0
        for a in range(t + 1):
            binom[t, a] = c * (-h) ** (t - a)
            c = c * (t - a) / (a + 1)
    centred_before = False
    for k in range(n_lines):
        start = min(max(k - n, 0), n_lines - W)
        centred = start == k - n
        if centred and centred_before and k % RESUM_LINES != 0:
            # slide the window by one line: re-centre the sums, drop one line, add one
            _shift(suu, binom)
            _shift(suy, binom)
            _accumulate(X, Y, k - 1 - n, -(n + 1) * h, -1.0, suu, suy, syy, pw)
            _accumulate(X, Y, k + n, n * h, 1.0, suu, suy, syy, pw)
        else:
            suu[:] = 0.0
            suy[:] = 0.0
            syy[:] = 0.0
            for w in range(W):
                _accumulate(X, Y, start + w, (start + w - k) * h, 1.0, suu, suy, syy, pw)
        centred_before = centred
        for a in range(n_c):
            for s in range(R1):
                for b in range(n_c):
                    for s2 in range(R1):
                        M[a * R1 + s, b * R1 + s2] = suu[a, b, s + s2]
                for i in range(n_out):
                    rhs[a * R1 + s, i] = suy[a, i, s]
        for q in range(p):
            d[q] = np.sqrt(max(M[q, q].real, 1e-300))
        ok = True
        for jj in range(p):                          # Cholesky of the scaled M
            sd = M[jj, jj].real / (d[jj] * d[jj])
            for q in range(jj):
                sd -= L[jj, q].real ** 2 + L[jj, q].imag ** 2
            if not sd > 1e-13:
                ok = False
                break
            L[jj, jj] = np.sqrt(sd)
            for i in range(jj + 1, p):
                v = M[i, jj] / (d[i] * d[jj])
                for q in range(jj):
                    v -= L[i, q] * np.conj(L[jj, q])
                L[i, jj] = v / L[jj, jj]
        if not ok:
            G[k] = np.nan
            res[k] = np.nan
            minv[k] = np.nan
            continue
        for q in range(p):
            for i in range(n_out):
                rhs[q, i] /= d[q]
            for a in range(n_in):
                rhs[q, n_out + a] = 1.0 / d[q] if q == a * R1 else 0.0
        for col in range(n_out + n_in):
            for i in range(p):                       # L z = rhs
                v = rhs[i, col]
                for q in range(i):
                    v -= L[i, q] * rhs[q, col]
                rhs[i, col] = v / L[i, i]
            for i in range(p - 1, -1, -1):           # L^H x = z
                v = rhs[i, col]
                for q in range(i + 1, p):
                    v -= np.conj(L[q, i]) * rhs[q, col]
                rhs[i, col] = v / L[i, i]
        for i in range(n_out):                       # residual: yy - b^H theta
            for i2 in range(n_out):
                v = syy[i, i2]
                for a in range(n_c):
                    for s in range(R1):
                        v -= np.conj(suy[a, i, s]) * rhs[a * R1 + s, i2] / d[a * R1 + s]
                res[k, i, i2] = v
        for a in range(n_in):
            q = a * R1
            for i in range(n_out):
                G[k, a, i] = rhs[q, i] / d[q]
            for a2 in range(n_in):
                minv[k, a, a2] = rhs[q, n_out + a2] / d[q]
    return G, res, minv


def lpm_lines(Y: np.ndarray, U: np.ndarray, *, order: int = DEFAULT_ORDER,
              half_width: int | None = None, transient: bool = True) -> LpmLines:
    """
    Estimate G on every line by the LPM.

    Parameters
    ----------
    Y : array_like, complex, shape (n_out, n_lines)
        Output spectra on consecutive lines.
    U : array_like, complex, shape (n_in, n_lines)
        Input spectra on the same lines.
    order : int
        Polynomial degree R (>= 0).
    half_width : int, optional
        n of the window k-n..k+n; default :func:`default_half_width`.
    transient : bool
        Estimate the transient term T (False: steady state, e.g. periodic data).

    Returns
    -------
    LpmLines
        G_k, the noise covariance and (K K^H)^-1 per line.

    Raises
    ------
    EstimationError
        Fewer lines than one window, or no residual degree of freedom left.

    """
    Y = np.atleast_2d(np.asarray(Y, dtype=complex))
    U = np.atleast_2d(np.asarray(U, dtype=complex))
    n_out, n_lines = Y.shape
    n_in = U.shape[0]
    if U.shape[1] != n_lines:
        raise EstimationError(f'spectra shapes {Y.shape=} {U.shape=}: expected (n_out, L) and '
                              f'(n_in, L) on the same lines')
    n = default_half_width(n_in, order, transient) if half_width is None else int(half_width)
    n_par = (order + 1) * (n_in + int(transient))
    dof = 2 * n + 1 - n_par
    if dof < 1:
        raise EstimationError(f'LPM window of {2 * n + 1} lines for {n_par} parameters '
                              f'(order {order}, {n_in} inputs): expected a wider window')
    if n_lines < 2 * n + 1:
        raise EstimationError(f'{n_lines} frequency lines are fewer than one LPM window of '
                              f'{2 * n + 1}; expected a longer record')
    G, S, minv = _lpm_kernel(np.ascontiguousarray(Y), np.ascontiguousarray(U), n, int(order),
                             bool(transient))
    cov = np.conj(S) / dof                           # cov[i, j] = sum e_i conj(e_j) / q
    return LpmLines(np.transpose(G, (2, 1, 0)), cov, minv, dof)


@dataclass
class RobustLpmResult:
    """
    The BLA of one periodic realisation with its noise and stochastic nonlinear variance.

    Attributes
    ----------
    frf : FrequencyResponse
        The BLA Y/U of this realisation at the excited lines (n_out, 1, n_lines), with
        ``noise_variance`` and ``total_variance`` (noise plus stochastic nonlinear
        distortion): the variances of this one-realisation estimate, comparable with the
        spread over realisations of the multisine BLA.
    nonlinear_variance : ndarray, shape (n_out, 1, n_lines)
        max(total - noise, 0).
    noise_from : str
        'periods' (spread over >= 2 periods) or 'non-excited lines' (one period: the LPM
        residual at the non-excited lines of the band; it holds even distortions too).
    dof : int
        Residual dof of the local polynomial over excited lines.

    """

    frf: FrequencyResponse
    nonlinear_variance: np.ndarray
    noise_from: str
    dof: int

    def levels(self, outputs: list[str] | None = None, units: list[str] | None = None,
               input_unit: str = '') -> 'RobustLpmLevels':
        """
        Per-line noise and nonlinear variance of each output (what estimates.json keeps).

        Parameters
        ----------
        outputs : list of str, optional
            Output channel names (default: those of :attr:`frf`).
        units : list of str, optional
            Unit of each output ('' where unknown).
        input_unit : str
            Unit of the input.

        Returns
        -------
        RobustLpmLevels
            The variances of the FRF Y/U per output and line.

        """
        f = self.frf
        units = list(units) if units is not None else [''] * f.noutputs
        return RobustLpmLevels(f.freq_hz, f.noise_variance[:, 0], f.total_variance[:, 0],
                               list(outputs or f.outputs),
                               [f'({u})^2/({input_unit})^2' for u in units],
                               int(f.meta['periods']), self.dof, self.noise_from)


def robust_lpm(y: np.ndarray, u: np.ndarray, period_samples: int, lines: np.ndarray, *,
               fs: float = 1.0, order: int = DEFAULT_ORDER,
               half_width: int | None = None) -> RobustLpmResult:
    """
    Robust LPM for periodic data: the BLA and its noise and nonlinear variance from one record.

    The record holds P >= 1 whole steady-state periods of a random-phase multisine on one
    input. The spectra of the periods are averaged at the excited ``lines``, where the BLA
    is Y/U. Over neighbouring excited lines G_BLA is smooth while the stochastic nonlinear
    contribution varies randomly from line to line like noise: the residual of a local
    polynomial of G over the excited lines (no transient: steady state; dof-corrected)
    estimates the variance of both at the output, total / |U|^2 that of Y/U. The noise
    variance comes from the spread over periods (P >= 2) or, with one period, from the
    LPM residual at the non-excited lines of the band (their input leakage regressed out,
    transient included), averaged over the non-excited lines near each excited one.

    Parameters
    ----------
    y : array_like, shape (P * period_samples, n_out) or (P * period_samples,)
        Outputs.
    u : array_like, shape (P * period_samples,)
        The input.
    period_samples : int
        Samples per period.
    lines : array_like of int
        Excited DFT bins of one period, increasing (at least one window of them).
    fs : float
        Sample rate [Hz] (for the frequencies).
    order, half_width
        Degree R and half width n of the local polynomial of G in frequency over the 2n+1
        nearest excited lines (no transient); default n: :func:`default_half_width` of
        one input without transient.

    Returns
    -------
    RobustLpmResult

    Raises
    ------
    EstimationError
        More than one input (one realisation cannot separate inputs), less than one whole
        period, or too few lines for one window.

    """
    y = np.asarray(y, dtype=float).reshape(len(y), -1)
    u = np.asarray(u, dtype=float).reshape(len(u), -1)
    if u.shape[1] != 1:
        raise EstimationError(f'robust LPM of one realisation: {u.shape[1]} inputs; expected '
                              f'one (one multisine realisation cannot separate inputs)')
    n = int(period_samples)
    n_p = y.shape[0] // n
    if n_p < 1:
        raise EstimationError(f'record of {y.shape[0]} samples holds no whole period of {n}')
    lines = np.asarray(lines, dtype=int)

    def per_period(x):                                  # (P, n_ch, n//2+1), 1/sqrt(N) scaled
        return np.fft.rfft(x[:n_p * n].reshape(n_p, n, -1), axis=1).transpose(0, 2, 1) \
            / np.sqrt(n)
    Yp, Up = per_period(y), per_period(u)
    if n_p >= 2:
        return robust_lpm_periods(Yp[:, :, lines], Up[:, 0, lines], lines * fs / n,
                                  order=order, half_width=half_width)
    Ym, Um = Yp[0], Up[0]
    free = np.setdiff1d(np.arange(lines[0], lines[-1] + 1), lines)
    fitn = lpm_lines(Ym[:, free], Um[:, free], order=order)
    level = np.real(np.einsum('kii->ik', fitn.noise_cov))              # (n_out, n_free)
    reach = 2 * (default_half_width(1, order, False) + 1)
    near = np.abs(free[None, :] - lines[:, None]) <= reach
    noise_y = (near @ level.T / np.maximum(near.sum(axis=1), 1)[:, None]).T
    return _robust_result(Ym[:, lines], Um[0, lines], noise_y, lines * fs / n, 1,
                          'non-excited lines', order, half_width)


def robust_lpm_periods(Y: np.ndarray, U: np.ndarray, freq_hz: np.ndarray, *,
                       order: int = DEFAULT_ORDER, half_width: int | None = None
                       ) -> RobustLpmResult:
    """
    Robust LPM from the spectra of P >= 2 steady periods of one realisation, excited lines.

    The period-spectra form of :func:`robust_lpm` (same numbers): the noise variance is the
    spread over the periods, the total (noise plus stochastic nonlinear) variance the
    residual of the local polynomial of G over neighbouring excited lines.

    Parameters
    ----------
    Y : array_like, shape (P, n_out, n_lines)
        Output spectrum of each period at the excited lines (any common DFT scaling).
    U : array_like, shape (P, n_lines)
        Input spectrum of each period at the same lines, the same scaling.
    freq_hz : array_like, shape (n_lines,)
        Frequencies of the lines [Hz], increasing.
    order, half_width
        Degree R and half width n of the local polynomial of G in frequency over the 2n+1
        nearest excited lines (no transient); default n: :func:`default_half_width` of
        one input without transient.

    Returns
    -------
    RobustLpmResult

    Raises
    ------
    EstimationError
        Fewer than two periods, or too few lines for one window.

    """
    Y, U = np.asarray(Y), np.asarray(U)
    n_p = Y.shape[0]
    if n_p < 2:
        raise EstimationError(f'robust LPM from period spectra: {n_p} period(s); expected '
                              f'at least 2 (the noise is their spread)')
    Ym = Y.mean(axis=0)
    noise_y = np.sum(np.abs(Y - Ym) ** 2, axis=0) / (n_p - 1) / n_p
    return _robust_result(Ym, U.mean(axis=0), noise_y, np.asarray(freq_hz, float), n_p,
                          'periods', order, half_width)


def _excited_residual(Ym, Um, freq_hz, order, half_width) -> tuple[np.ndarray, int]:
    """
    Residual variance of Y - G U, G a local polynomial in frequency, over the excited lines.

    Per excited line the 2n+1 nearest excited lines (the window shifted inside at the ends);
    the polynomial is in the lines' frequency offset, not their index, so lines spaced
    unevenly (random-odd and log-spaced multisines) leave no model error a polynomial in
    the index would. Returns the dof-corrected residual power (n_out, L) and the dof.
    """
    n = default_half_width(1, order, transient=False) if half_width is None else int(half_width)
    w, n_lines = 2 * n + 1, freq_hz.size
    dof = w - (order + 1)
    if dof < 1 or n_lines < w:
        raise EstimationError(f'robust LPM: {n_lines} excited lines, window {w} for order '
                              f'{order}; expected at least one window with a residual dof')
    idx = np.clip(np.arange(n_lines) - n, 0, n_lines - w)[:, None] + np.arange(w)   # (L, w)
    d = freq_hz[idx] - freq_hz[:, None]
    d = d / np.max(np.abs(d), axis=1, keepdims=True)
    K = Um[idx][:, :, None] * d[:, :, None] ** np.arange(order + 1)             # (L, w, R+1)
    Q = np.linalg.qr(K)[0]
    Yw = Ym[:, idx]                                                            # (n_out, L, w)
    res = Yw - np.einsum('lwp,lvp,olv->olw', Q, np.conj(Q), Yw)
    return np.sum(np.abs(res) ** 2, axis=2) / dof, dof


def _robust_result(Ym, Um, noise_y, freq_hz, n_p, noise_from, order, half_width
                   ) -> RobustLpmResult:
    """Local polynomial over the excited lines: total variance; with the noise, the result."""
    total_y, dof = _excited_residual(Ym, Um, freq_hz, order, half_width)    # (n_out, n_lines)
    u2 = np.abs(Um) ** 2
    total = (total_y / u2)[:, None, :]
    noise = (noise_y / u2)[:, None, :]
    frf = FrequencyResponse(freq_hz, (Ym / Um)[:, None, :],
                            noise_variance=noise, total_variance=total, meta={
                                'method': 'robust_lpm', 'periods': n_p, 'order': order,
                                'dof': dof, 'noise_from': noise_from})
    return RobustLpmResult(frf, np.maximum(total - noise, 0.0), noise_from, dof)
