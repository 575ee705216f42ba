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
Maximum likelihood over stable denominators only (a rational fit with an unstable pole).

A free ML fit of a common-denominator model may place a pole in the right half-plane (a
lightly damped pair whose damping noise or a nonlinear distortion pushes below zero; the
Silverbox BLA at order 9-12 did). A model of a physical, stable plant must not have one. The
refit (Pintelon & Schoukens, System Identification, 2nd ed., Sec. 9.7: reflect the unstable
poles, then constrain):

1. the unstable poles are reflected into the left half-plane (p -> -conj(p)), which keeps
   |D(j omega)| and so the magnitude of the start;
2. the denominator is written as a product of factors ``s^2 + 2 zeta omega s + omega^2``
   with ``omega = exp(a)`` and ``zeta = MIN_DAMPING + exp(b)`` (a complex pair, or two real
   poles where zeta > 1) and at most one ``s + exp(c)``: every such product is Hurwitz, so
   Levenberg-Marquardt over (numerators, a, b, c) cannot leave the stable models; numerators
   stay free. Where the data pull a pair towards instability it stops just above
   :data:`MIN_DAMPING` (then the summary's damping ratio says so).

All in the scaled variable s / omega_0 of :mod:`frf_ident.core.fit.rational`.
"""
from __future__ import annotations

import numpy as np
from scipy import optimize

__all__ = ['MIN_DAMPING', 'factor_parameters', 'reflect_unstable', 'stable_refit']

#: the smallest damping ratio a refitted pole pair can have: asymptotically stable, and below
#: anything a measured FRF resolves (the lightest measured damping of the tests, the DaISy
#: arm's first mode, is 0.002); a pair that ends there is a pair the data would push
#: unstable: the fit is then at the edge of the stable models
MIN_DAMPING = 1e-4


def reflect_unstable(den: np.ndarray) -> tuple[np.ndarray, int]:
    """
    Reflect the right-half-plane roots of a monic polynomial into the left half-plane.

    Parameters
    ----------
    den : ndarray, shape (n + 1,)
        Coefficients in ascending powers, den[-1] = 1.

    Returns
    -------
    roots : ndarray of complex, shape (n,)
        The roots, every one with a negative real part (a damping ratio of at least twice
        :data:`MIN_DAMPING`).
    n_reflected : int
        How many roots had a non-negative real part.

    """
    roots = np.roots(np.asarray(den, dtype=float)[::-1]).astype(complex)
    bad = roots.real >= 0
    floor = 2 * MIN_DAMPING * np.maximum(np.abs(roots), 1e-12)
    roots = np.where(bad, -np.abs(roots.real) + 1j * roots.imag, roots)
    roots = np.where(roots.real > -floor, -floor + 1j * roots.imag, roots)
    return roots, int(np.sum(bad))


def factor_parameters(roots: np.ndarray) -> tuple[np.ndarray, int]:
    """
    Return the log-parameters of the stable factors of a set of left-half-plane roots.

    Parameters
    ----------
    roots : ndarray of complex, shape (n,)
        Roots with negative real parts, complex ones in conjugate pairs.

    Returns
    -------
    theta : ndarray, shape (n,)
        (log omega, log(zeta - MIN_DAMPING)) per quadratic factor, then log c of the linear
        one if n is odd.
    n_quad : int
        Number of quadratic factors (n // 2).

    """
    cplx = roots[roots.imag > 1e-12 * np.abs(roots)]
    real = np.sort(roots[np.abs(roots.imag) <= 1e-12 * np.abs(roots)].real)
    theta = []
    for p in cplx:                                    # omega = |p|, zeta = -Re p / |p|
        theta += [np.log(abs(p)), np.log(max(-p.real / abs(p) - MIN_DAMPING, MIN_DAMPING))]
    c = -real                                         # (s + c1)(s + c2)
    for k in range(0, c.size - 1, 2):
        w = np.sqrt(c[k] * c[k + 1])
        theta += [np.log(w), np.log((c[k] + c[k + 1]) / (2 * w) - MIN_DAMPING)]
    if c.size % 2:
        theta.append(np.log(c[-1]))
    return np.asarray(theta, dtype=float), len(roots) // 2


def _coefficients(theta: np.ndarray, n_quad: int) -> list[tuple[float, float]]:
    """Return (2 zeta omega, omega^2) of every quadratic factor."""
    out = []
    for q in range(n_quad):
        w, z = np.exp(theta[2 * q]), MIN_DAMPING + np.exp(theta[2 * q + 1])
        out.append((2 * z * w, w * w))
    return out


def _factors(theta: np.ndarray, n_quad: int, s: np.ndarray) -> np.ndarray:
    """Return every factor at s, shape (n_factors, n_freq)."""
    quad = [s ** 2 + a1 * s + a0 for a1, a0 in _coefficients(theta, n_quad)]
    lin = [s + np.exp(theta[-1])] if theta.size > 2 * n_quad else []
    return np.array(quad + lin)


def _polynomial(theta: np.ndarray, n_quad: int) -> np.ndarray:
    """Return the monic denominator in ascending powers of the scaled s."""
    poly = np.ones(1)
    for a1, a0 in _coefficients(theta, n_quad):
        poly = np.polymul(poly, [1.0, a1, a0])
    if theta.size > 2 * n_quad:
        poly = np.polymul(poly, [1.0, np.exp(theta[-1])])
    return poly[::-1]


def stable_refit(s: np.ndarray, response: np.ndarray, weight: np.ndarray, num: np.ndarray,
                 den: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """
    Refit N_i / D by ML over stable denominators, from a start with unstable poles.

    Parameters
    ----------
    s : ndarray of complex, shape (n_freq,)
        Scaled Laplace variable j omega / omega_0.
    response : ndarray of complex, shape (m, n_freq)
        The m measured channels.
    weight : ndarray, shape (m, n_freq)
        sqrt(2) / sigma of every line (the normalised residual's weight).
    num : ndarray, shape (m, nb)
        Start numerators (ascending powers of the scaled s).
    den : ndarray, shape (order + 1,)
        Start denominator (ascending, monic), with unstable roots.

    Returns
    -------
    num : ndarray, shape (m, nb)
        Refitted numerators.
    den : ndarray, shape (order + 1,)
        Refitted monic denominator, every root in the open left half-plane.
    n_reflected : int
        The unstable roots of the start.

    """
    roots, n_reflected = reflect_unstable(den)
    theta0, n_quad = factor_parameters(roots)
    m, nb = num.shape
    vn = s[:, None] ** np.arange(nb)

    def model(x):
        b = x[:m * nb].reshape(m, nb)
        fac = _factors(x[m * nb:], n_quad, s)
        d = np.prod(fac, axis=0)
        return b, fac, d, (b @ vn.T) / d

    def resid(x):
        e = (model(x)[3] - response) * weight
        return np.concatenate([e.real.ravel(), e.imag.ravel()])

    def jac(x):
        b, fac, d, mod = model(x)
        th = x[m * nb:]
        dd = []                                      # dD / dtheta, each (n_freq,)
        for q, (a1, a0) in enumerate(_coefficients(th, n_quad)):
            rest = d / fac[q]                        # d a1 / d log w = a1, d a0 = 2 a0
            dd += [(a1 * s + 2 * a0) * rest,
                   2 * np.exp(th[2 * q + 1]) * np.exp(th[2 * q]) * s * rest]
        if th.size > 2 * n_quad:
            dd.append(np.exp(th[-1]) * d / fac[-1])
        j = np.zeros((m, s.size, x.size), dtype=complex)
        for i in range(m):
            j[i, :, i * nb:(i + 1) * nb] = vn / d[:, None]
        j[:, :, m * nb:] = -(mod / d)[:, :, None] * np.array(dd).T[None]
        j = (j * weight[:, :, None]).reshape(m * s.size, -1)
        return np.vstack([j.real, j.imag])

    # numerators for the reflected start: linear least squares with D fixed
    d0 = np.prod(_factors(theta0, n_quad, s), axis=0)
    b0 = np.empty((m, nb))
    for i in range(m):
        a = vn / d0[:, None] * weight[i][:, None]
        a = np.vstack([a.real, a.imag])
        y = response[i] * weight[i]
        b0[i] = np.linalg.lstsq(a, np.concatenate([y.real, y.imag]), rcond=None)[0]
    sol = optimize.least_squares(resid, np.concatenate([b0.ravel(), theta0]), jac=jac,
                                 method='lm', x_scale='jac')
    return sol.x[:m * nb].reshape(m, nb), _polynomial(sol.x[m * nb:], n_quad), n_reflected
