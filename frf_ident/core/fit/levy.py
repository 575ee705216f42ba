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
Linear least-squares start of a rational fit: Levy's method with Sanathanan-Koerner iterations.

The model P(s) = N(s) / D(s) with a monic denominator is linear in its coefficients once the
error is multiplied by D: N(s_k) - P_k D(s_k). Levy (1959) solves that in one least-squares
step; Sanathanan & Koerner (1963) divide by the previous |D(s_k)| and repeat, which removes the
|D|^2 weighting that biases Levy towards the high frequencies. The weights 1/sigma_k make each
step an approximation of the ML cost. Frequencies are scaled by the highest one so that the
Vandermonde columns stay within [0, 1]. The result only starts the nonlinear ML fit.
"""
from __future__ import annotations

import numpy as np

__all__ = ['SK_ITERATIONS', 'sanathanan_koerner', 'sk_common_denominator']

#: Sanathanan-Koerner iterations after the Levy step; the coefficients of the flexible-joint
#: models of the tests stop changing (to 1e-6) after 5-8, the ML fit that follows needs only a
#: start in its basin of attraction
SK_ITERATIONS = 10


def sk_common_denominator(s: np.ndarray, response: np.ndarray, weight: np.ndarray, n_num: int,
                          n_den: int, iterations: int = SK_ITERATIONS
                          ) -> tuple[np.ndarray, np.ndarray]:
    """
    Fit N_i(s) / D(s) with one monic D to several responses (scaled frequencies).

    Parameters
    ----------
    s : ndarray of complex, shape (n_freq,)
        Scaled Laplace variable j omega / omega_0 (|s| <= 1 keeps the columns bounded).
    response : ndarray of complex, shape (m, n_freq)
        The m responses (the channels of a MIMO FRF, flattened).
    weight : ndarray, shape (m, n_freq)
        1 / sigma of every line of every response.
    n_num, n_den : int
        Degrees of the N_i and of D.
    iterations : int, optional
        Sanathanan-Koerner iterations after the Levy step.

    Returns
    -------
    num : ndarray, shape (m, n_num + 1)
        Coefficients of the N_i in ascending powers of the scaled s.
    den : ndarray, shape (n_den + 1,)
        Coefficients of D in ascending powers of the scaled s, den[-1] = 1.

    """
    m, nf = response.shape
    nb = n_num + 1
    vn = s[:, None] ** np.arange(nb)
    vd = s[:, None] ** np.arange(n_den)
    d_prev = np.ones_like(s)
    a = np.zeros(n_den)
    b = np.zeros((m, nb))
    for _ in range(iterations + 1):
        scale = weight / np.abs(d_prev)[None, :]                        # (m, nf)
        num_cols = vn[None] * scale[:, :, None]                          # (m, nf, nb)
        den_cols = -(response * scale)[:, :, None] * vd[None]            # (m, nf, n_den)
        rhs = response * scale * s[None, :] ** n_den                     # (m, nf)

        def real(x):
            return np.concatenate([x.real, x.imag], axis=1)
        # the numerators are separate per channel: project them out with each channel's QR
        # (small stacked reduced QRs: I - Q1 Q1^T is the projection the complete QR's Q2 Q2^T
        # would give, without its 2nf x 2nf factor), solve the shared denominator, then
        # back-substitute
        q1, r = np.linalg.qr(real(num_cols))                             # (m, 2nf, nb)
        dr, rr = real(den_cols), real(rhs[:, :, None])
        q1t = np.swapaxes(q1, 1, 2)
        red = (dr - q1 @ (q1t @ dr)).reshape(-1, n_den)
        red_rhs = (rr - q1 @ (q1t @ rr)).reshape(-1)
        norm = np.linalg.norm(red, axis=0)
        norm[norm == 0] = 1.0
        a = np.linalg.lstsq(red / norm, red_rhs, rcond=None)[0] / norm
        resid = rr[..., 0] - dr @ a                                      # (m, 2nf)
        b = np.linalg.solve(r, q1t @ resid[..., None])[..., 0]
        d_prev = vd @ a + s ** n_den
    return b, np.concatenate([a, [1.0]])


def sanathanan_koerner(freq_hz: np.ndarray, response: np.ndarray, n_num: int, n_den: int,
                       weight: np.ndarray | None = None,
                       iterations: int = SK_ITERATIONS) -> tuple[np.ndarray, np.ndarray]:
    """
    Fit N(s) / D(s) to a SISO FRF by iterated linear least squares.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Frequencies in Hz.
    response : ndarray of complex, shape (n_freq,)
        The measured FRF.
    n_num, n_den : int
        Degrees of N and D (D monic).
    weight : ndarray, shape (n_freq,), optional
        1 / sigma of every line (default: 1 / |response|, a relative error).
    iterations : int, optional
        Sanathanan-Koerner iterations after the Levy step.

    Returns
    -------
    num, den : ndarray
        Coefficients in descending powers of s (numpy / python-control order), den[0] = 1.

    """
    w0 = 2 * np.pi * float(np.max(freq_hz))
    s = 2j * np.pi * np.asarray(freq_hz, dtype=float) / w0
    p = np.asarray(response, dtype=complex)
    w = 1.0 / np.abs(p) if weight is None else np.asarray(weight, dtype=float)
    b, a = sk_common_denominator(s, p[None, :], w[None, :], n_num, n_den, iterations)
    # back to unscaled s: multiply N and D by w0^n_den, coefficient i by w0^(n_den - i)
    num = b[0] * w0 ** (n_den - np.arange(n_num + 1))
    den = a * w0 ** (n_den - np.arange(n_den + 1))
    return num[::-1], den[::-1]
