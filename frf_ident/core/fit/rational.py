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
A continuous-time rational model of chosen order fitted to a (MIMO) FRF by maximum likelihood.

P_ij(s) = N_ij(s) / D(s): one monic denominator of degree ``order`` shared by every channel
(the poles of a MIMO system are common), numerators of degree ``n_num`` (default
``order - 1``: strictly proper). Stages of :func:`fit_rational`:

1. Sanathanan-Koerner start (:mod:`frf_ident.core.fit.levy`), weighted by 1 / sigma;
2. ML: Levenberg-Marquardt on the residual normalised by the FRF's standard deviation;
3. Cramer-Rao covariance of the coefficients, first-order standard errors of the modes'
   natural frequencies and damping ratios, and the cost test.

Coefficients are kept in the scaled variable s / omega_0 (omega_0 the highest measured
angular frequency), which keeps the problem well conditioned; :attr:`RationalFit.num` /
``den`` and :meth:`RationalFit.state_space` give the unscaled model.
:func:`select_order` fits several orders and picks the lowest one that passes the cost test
(else the lowest AIC).
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.fit.cost import cost_test, CostTest
from frf_ident.core.fit.levy import sk_common_denominator
import numpy as np
from scipy import optimize

__all__ = ['Mode', 'OrderSelection', 'RationalFit', 'fit_rational', 'select_order']


@dataclass(frozen=True)
class Mode:
    """
    One pole pair (or real pole) of a fitted model with its first-order standard errors.

    Attributes
    ----------
    frequency_hz, frequency_std_hz : float
        Natural frequency |p| / 2 pi [Hz] and its standard error.
    damping, damping_std : float
        Damping ratio -Re p / |p| and its standard error (1 for a real pole).

    """

    frequency_hz: float
    frequency_std_hz: float
    damping: float
    damping_std: float

    def summary(self) -> str:
        """Return one line: frequency and damping with their standard errors."""
        return (f'{self.frequency_hz:.3f} +- {self.frequency_std_hz:.2g} Hz, damping ratio '
                f'{self.damping:.4f} +- {self.damping_std:.2g}')


@dataclass
class RationalFit:
    """
    A fitted common-denominator model P_ij = N_ij / D and its uncertainty.

    Attributes
    ----------
    freq_hz : ndarray, shape (n_freq,)
        The fitted lines [Hz].
    omega0 : float
        Frequency scale [rad/s]: the coefficients are those of s / omega0.
    num_scaled : ndarray, shape (n_out, n_in, n_num + 1)
        Numerator coefficients in ascending powers of s / omega0.
    den_scaled : ndarray, shape (order + 1,)
        Denominator coefficients in ascending powers of s / omega0, the last 1.
    covariance : ndarray, shape (n_par, n_par)
        Cramer-Rao covariance of [num_scaled.ravel(), den_scaled[:-1]].
    cost : CostTest
        The minimum cost against its chi-square expectation.
    model : ndarray of complex, shape (n_out, n_in, n_freq)
        The fitted model at ``freq_hz``.
    inputs, outputs : list of str
        Channel names.

    """

    freq_hz: np.ndarray
    omega0: float
    num_scaled: np.ndarray
    den_scaled: np.ndarray
    covariance: np.ndarray
    cost: CostTest
    model: np.ndarray
    inputs: list[str]
    outputs: list[str]

    @property
    def order(self) -> int:
        """Return the degree of the denominator (the number of poles)."""
        return self.den_scaled.size - 1

    @property
    def n_params(self) -> int:
        """Return the number of fitted real parameters."""
        return self.num_scaled.size + self.order

    @property
    def aic(self) -> float:
        """
        Return Akaike's criterion: -2 log-likelihood (up to a constant) + 2 p.

        With the FRF's variance that is cost + 2 p; without it the noise level is estimated
        from the residual too, N ln(cost / N) + 2 p over the N real residuals.
        """
        if self.cost.weighted:
            return self.cost.cost + 2.0 * self.n_params
        n = self.cost.dof + self.n_params
        return n * float(np.log(self.cost.cost / n)) + 2.0 * self.n_params

    @property
    def num(self) -> np.ndarray:
        """Return the numerators in descending powers of s, shape (n_out, n_in, n_num + 1)."""
        nb = self.num_scaled.shape[-1]
        return (self.num_scaled * self.omega0 ** (self.order - np.arange(nb)))[..., ::-1]

    @property
    def den(self) -> np.ndarray:
        """Return the monic denominator in descending powers of s, shape (order + 1,)."""
        return (self.den_scaled * self.omega0 ** (self.order - np.arange(self.order + 1)))[::-1]

    def poles(self) -> np.ndarray:
        """Return the poles [rad/s]."""
        return np.roots(self.den_scaled[::-1]) * self.omega0

    def modes(self) -> list[Mode]:
        """
        Return the poles as modes with standard errors, one per upper-half-plane pole.

        First order: a change da_m of the scaled denominator moves a pole p by
        -p^m da_m / D'(p); the covariance of the denominator maps through that Jacobian.

        Returns
        -------
        list of Mode
            Sorted by frequency.

        """
        a = self.den_scaled
        n = self.order
        cov_a = self.covariance[-n:, -n:]
        dpoly = np.polyder(a[::-1])
        out = []
        for p in np.roots(a[::-1]):
            if p.imag < -1e-12 * abs(p):
                continue
            dp = -(p ** np.arange(n)) / np.polyval(dpoly, p)     # dp / da_m, complex
            r = abs(p)
            dr = (np.conj(p) * dp).real / r
            dz = -dp.real / r + p.real * dr / r ** 2
            out.append(Mode(float(r * self.omega0 / (2 * np.pi)),
                            float(np.sqrt(max(dr @ cov_a @ dr, 0.0)) * self.omega0 / (2 * np.pi)),
                            float(-p.real / r), float(np.sqrt(max(dz @ cov_a @ dz, 0.0)))))
        return sorted(out, key=lambda m: m.frequency_hz)

    def response(self, freq_hz: np.ndarray) -> np.ndarray:
        """Return the model's FRF at ``freq_hz``, shape (n_out, n_in, n_freq)."""
        s = 2j * np.pi * np.asarray(freq_hz, dtype=float) / self.omega0
        return _evaluate(self.num_scaled, self.den_scaled, s)

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """
        Return a state-space realisation (A, B, C, D) of the fitted model.

        One controllable companion block of the shared denominator per input (order * n_in
        states; not minimal for a MIMO model, exact in every channel), built in the scaled
        variable and then scaled back (A and B times omega0).

        Returns
        -------
        A : ndarray, shape (order n_in, order n_in)
        B : ndarray, shape (order n_in, n_in)
        C : ndarray, shape (n_out, order n_in)
        D : ndarray, shape (n_out, n_in)

        """
        n, a = self.order, self.den_scaled
        n_out, n_in, nb = self.num_scaled.shape
        comp = np.zeros((n, n))
        comp[:-1, 1:] = np.eye(n - 1)
        comp[-1] = -a[:-1]
        A = np.kron(np.eye(n_in), comp)
        B = np.kron(np.eye(n_in), np.eye(n)[:, -1:])
        num = np.zeros((n_out, n_in, n + 1))
        num[..., :nb] = self.num_scaled
        D = num[..., n].copy()
        C = (num[..., :n] - D[..., None] * a[None, None, :n]).reshape(n_out, n_in * n)
        return A * self.omega0, B * self.omega0, C, D

    def summary(self) -> list[str]:
        """Return a few lines for people: order, modes and the cost test."""
        lines = [f'order {self.order} ({self.n_params} parameters, {self.freq_hz.size} lines '
                 f'{self.freq_hz.min():.3g}-{self.freq_hz.max():.3g} Hz)']
        lines += [f'  mode {m.summary()}' for m in self.modes() if m.damping < 1.0]
        lines.append(f'  {self.cost.summary()}')
        return lines


def _evaluate(num: np.ndarray, den: np.ndarray, s: np.ndarray) -> np.ndarray:
    vn = s[:, None] ** np.arange(num.shape[-1])
    return (num @ vn.T) / (s[:, None] ** np.arange(den.size) @ den)


def _as_mimo(response, variance):
    p = np.asarray(response, dtype=complex)
    p = p.reshape(1, 1, -1) if p.ndim == 1 else p
    if variance is None:
        return p, None
    v = np.asarray(variance, dtype=float).reshape(p.shape)
    if not np.all(np.isfinite(v) & (v > 0)):
        raise ValueError('variance must be positive and finite on every line')
    return p, v


def fit_rational(freq_hz: np.ndarray, response: np.ndarray, variance: np.ndarray | None = None,
                 order: int = 2, n_num: int | None = None, *,
                 inputs: list[str] | None = None, outputs: list[str] | None = None
                 ) -> RationalFit:
    """
    Fit a common-denominator continuous-time model of ``order`` poles by maximum likelihood.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Frequencies in Hz.
    response : ndarray of complex, shape (n_out, n_in, n_freq) or (n_freq,)
        The measured FRF.
    variance : ndarray, same shape as ``response``, optional
        Its variance E|P_hat - P|^2; without it the relative error is minimised and the
        covariance is scaled by the residual (the cost test cannot decide then).
    order : int, optional
        Degree of the denominator (>= 1).
    n_num : int, optional
        Degree of the numerators (default ``order - 1``, at most ``order``).
    inputs, outputs : list of str, optional
        Channel names carried by the result.

    Returns
    -------
    RationalFit
        The model, its Cramer-Rao covariance and its cost test.

    Raises
    ------
    ValueError
        ``order`` < 1, ``n_num`` > ``order``, too few lines for the parameters, or a variance
        that is not positive.

    """
    f = np.asarray(freq_hz, dtype=float)
    p, var = _as_mimo(response, variance)
    n_out, n_in, nf = p.shape
    n_num = order - 1 if n_num is None else int(n_num)
    if order < 1 or not 0 <= n_num <= order:
        raise ValueError(f'order={order} must be >= 1 and n_num={n_num} in 0..order')
    m, nb = n_out * n_in, n_num + 1
    if 2 * m * nf <= m * nb + order:
        raise ValueError(f'{nf} lines cannot determine {m * nb + order} parameters')
    w0 = 2 * np.pi * float(f.max())
    s = 2j * np.pi * f / w0
    pm = p.reshape(m, nf)
    sigma = np.sqrt(var).reshape(m, nf) if var is not None else np.abs(pm)
    b0, a0 = sk_common_denominator(s, pm, 1.0 / sigma, n_num, order)
    weight = np.sqrt(2.0) / sigma
    vn = s[:, None] ** np.arange(nb)
    vd = s[:, None] ** np.arange(order)

    def split(x):
        return x[:m * nb].reshape(m, nb), np.concatenate([x[m * nb:], [1.0]])

    def resid(x):
        b, a = split(x)
        e = ((b @ vn.T) / (s[:, None] ** np.arange(order + 1) @ a) - pm) * weight
        return np.concatenate([e.real.ravel(), e.imag.ravel()])

    def jac(x):
        b, a = split(x)
        d = s[:, None] ** np.arange(order + 1) @ a
        model = (b @ vn.T) / d
        j = np.zeros((m, nf, m * nb + order), dtype=complex)
        for i in range(m):
            j[i, :, i * nb:(i + 1) * nb] = vn / d[:, None]
        j[:, :, m * nb:] = -(model / d)[:, :, None] * vd[None]
        j = (j * weight[:, :, None]).reshape(m * nf, -1)
        return np.vstack([j.real, j.imag])

    sol = optimize.least_squares(resid, np.concatenate([b0.ravel(), a0[:-1]]), jac=jac,
                                 method='lm', x_scale='jac')
    test = cost_test(sol.fun, sol.x.size, var is not None)
    cov = np.linalg.pinv(sol.jac.T @ sol.jac)
    if var is None:
        cov = cov * test.cost / max(test.dof, 1)
    b, a = split(sol.x)
    num = b.reshape(n_out, n_in, nb)
    return RationalFit(f, w0, num, a, cov, test, _evaluate(num, a, s),
                       list(inputs or [f'u{i}' for i in range(n_in)]),
                       list(outputs or [f'y{i}' for i in range(n_out)]))


@dataclass
class OrderSelection:
    """
    Fits of several orders and the one chosen.

    Attributes
    ----------
    fits : list of RationalFit
        One fit per tried order, in increasing order.
    chosen : int
        Index into ``fits`` of the chosen model.
    reason : str
        ``'cost test'`` (the lowest order whose residual the noise explains) or ``'AIC'``
        (no order passed, or no variance: the lowest Akaike criterion).

    """

    fits: list[RationalFit]
    chosen: int
    reason: str

    @property
    def best(self) -> RationalFit:
        """Return the chosen fit."""
        return self.fits[self.chosen]


def select_order(freq_hz: np.ndarray, response: np.ndarray, variance: np.ndarray | None,
                 orders: list[int] | range, **kwargs) -> OrderSelection:
    """
    Fit the orders from the lowest up; stop at the first that passes the cost test.

    Parameters
    ----------
    freq_hz, response, variance
        As :func:`fit_rational`.
    orders : list of int
        Denominator degrees to try.
    **kwargs
        Passed to :func:`fit_rational` (``n_num`` is then taken relative: ``order - 1``
        unless given).

    Returns
    -------
    OrderSelection
        The fits made (up to the first passing one) and the chosen one: the first passing
        the cost test, else the lowest AIC of all.

    """
    fits = []
    for o in sorted(orders):
        fits.append(fit_rational(freq_hz, response, variance, int(o), **kwargs))
        if fits[-1].cost.weighted and not fits[-1].cost.structure_missing:
            return OrderSelection(fits, len(fits) - 1, 'cost test')
    return OrderSelection(fits, int(np.argmin([f.aic for f in fits])), 'AIC')
