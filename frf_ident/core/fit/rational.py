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
   where that leaves a pole in the right half-plane, ML over stable denominators only
   (:mod:`frf_ident.core.fit.stable`: the unstable poles reflected, the denominator a
   product of Hurwitz factors), so a fit never returns an unstable pole;
3. Cramer-Rao covariance of the coefficients, first-order standard errors of the modes'
   natural frequencies and damping ratios, the cost test, and where it fails the bound of
   the bias a missing structure can leave (:mod:`frf_ident.core.fit.model_error`).

A mode (a complex pole pair) outside the fitted band is flagged (:attr:`Mode.in_band`): the
data do not show it, the fit used it to shape the response at the band's edge.

Coefficients are kept in the scaled variable s / omega_0 (omega_0 the highest measured
angular frequency), which keeps the problem well conditioned; :attr:`RationalFit.num` /
``den`` and :meth:`RationalFit.state_space` give the unscaled model.
:func:`select_order` fits several orders and picks, among the admissible ones (every mode in
the band and off the stability limit), the lowest that passes the cost test, else the lowest
AIC.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.fit.cost import cost_test, CostTest
from frf_ident.core.fit.cramer_rao import cramer_rao
from frf_ident.core.fit.levy import sk_common_denominator
from frf_ident.core.fit.model_error import shape_basis, shifts
from frf_ident.core.fit.modes import Mode, modes_of
from frf_ident.core.fit.stable import stable_refit
import numpy as np
from scipy import optimize

__all__ = ['Mode', 'OrderSelection', 'RationalFit', 'fit_rational', 'select_order']


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
    reflected : int
        Poles the free ML fit put in the right half-plane (0: it was stable); the model is
        then the ML fit over stable denominators (:mod:`frf_ident.core.fit.stable`).
    shift : ndarray, shape (n_par, n_shapes), or None
        Coefficient shifts of the model-error shapes
        (:func:`frf_ident.core.fit.model_error.shifts`); None where the cost test passes.

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
    reflected: int = 0
    shift: np.ndarray | None = None

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

        Returns
        -------
        list of Mode
            Sorted by frequency (:func:`frf_ident.core.fit.modes.modes_of`).

        """
        n = self.order
        return modes_of(self.den_scaled, self.omega0, self.covariance[-n:, -n:],
                        None if self.shift is None else self.shift[-n:],
                        (float(self.freq_hz.min()), float(self.freq_hz.max())))

    @property
    def admissible(self) -> bool:
        """Return whether the data support every mode (:attr:`Mode.supported`)."""
        return all(m.supported for m in self.modes())

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
        """Return a few lines for people: order, stability, modes, the cost test, verdict."""
        lines = [f'order {self.order} ({self.n_params} parameters, {self.freq_hz.size} lines '
                 f'{self.freq_hz.min():.3g}-{self.freq_hz.max():.3g} Hz)']
        if self.reflected:
            lines.append(f'  the free ML fit had {self.reflected} unstable pole(s): refitted '
                         f'over stable models only (poles reflected, then constrained ML)')
        lines += [f'  mode {m.summary()}' for m in self.modes() if m.damping < 1.0]
        lines.append(f'  {self.cost.summary()}')
        lines.append(f'  {self.cost.verdict}')
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
                 inputs: list[str] | None = None, outputs: list[str] | None = None,
                 stable: bool = True) -> RationalFit:
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
    stable : bool, optional
        Refit over stable denominators where the free ML fit has a pole in the right
        half-plane (default); False returns the free fit as it is.

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
    x, reflected = sol.x, 0
    b, a = split(x)
    if stable and np.any(np.roots(a[::-1]).real >= 0):
        b, a, reflected = stable_refit(s, pm, weight, b, a)
        x = np.concatenate([b.ravel(), a[:-1]])
    fun, jx = resid(x), jac(x)
    test = cost_test(fun, x.size, var is not None)
    cov = cramer_rao(jx)
    if var is None:
        cov = cov * test.cost / max(test.dof, 1)
    num = b.reshape(n_out, n_in, nb)
    model = _evaluate(num, a, s)
    shift = None
    if test.structure_missing:
        basis = shape_basis(f, model.reshape(m, nf), weight)
        shift = shifts(jx, basis, test.cost - test.dof)
    return RationalFit(f, w0, num, a, cov, test, model,
                       list(inputs or [f'u{i}' for i in range(n_in)]),
                       list(outputs or [f'y{i}' for i in range(n_out)]), reflected, shift)


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
        ``'cost test'`` (the lowest admissible order whose residual the noise explains) or
        ``'AIC'`` (no admissible order passed, or no variance: the lowest Akaike criterion,
        among the admissible fits where there are any).
    runner_up : int or None
        Index of the next best candidate: the order tried before the one the cost test
        accepted, or the second-lowest AIC; None when only one order was tried.

    """

    fits: list[RationalFit]
    chosen: int
    reason: str
    runner_up: int | None = None

    @property
    def best(self) -> RationalFit:
        """Return the chosen fit."""
        return self.fits[self.chosen]

    def lines(self) -> list[str]:
        """Return the choice, every tried order's cost, and the runner-up, for people."""
        best = self.best
        why = ('the lowest admissible order the noise explains' if self.reason == 'cost test'
               else 'the lowest AIC = cost + 2 parameters among the admissible orders'
               if any(f.admissible for f in self.fits)
               else 'the lowest AIC; no order is admissible')
        lines = [f'order {best.order} chosen by the {self.reason} ({why})',
                 'tried (order: cost, cost/dof): ' + '; '.join(
                     f'{f.order}: {f.cost.cost:.4g}, {f.cost.ratio:.3g}' for f in self.fits)]
        bad = [str(f.order) for f in self.fits if not f.admissible]
        if bad:
            lines.append(f'not admissible (a mode outside the band or at the stability limit): '
                         f'order {", ".join(bad)}')
        if self.runner_up is not None:
            r = self.fits[self.runner_up]
            q = r.cost.cost / best.cost.cost
            rel = f'{100 * (q - 1):+.2g} %' if q < 2 else f'{q:.3g} times'
            lines.append(f'runner-up: order {r.order}, cost {r.cost.cost:.4g} ({rel} the '
                         f"chosen's), AIC {r.aic - best.aic:+.4g}; {r.cost.verdict}")
        return lines


def select_order(freq_hz: np.ndarray, response: np.ndarray, variance: np.ndarray | None,
                 orders: list[int] | range, **kwargs) -> OrderSelection:
    """
    Fit the orders from the lowest up; stop at the first admissible one the cost test accepts.

    Admissible: every mode supported by the data, none outside the fitted band and none at
    the stability limit of the refit (:attr:`RationalFit.admissible`; every fit is stable,
    :func:`fit_rational`). A model with a mode the data do not support is kept only when no
    order gives one without.

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
        The fits made (up to the first admissible passing one) and the chosen one: that
        one, else the lowest AIC of the admissible fits (of all when none is).

    """
    fits = []
    for o in sorted(orders):
        fits.append(fit_rational(freq_hz, response, variance, int(o), **kwargs))
        last = fits[-1]
        if last.cost.weighted and not last.cost.structure_missing and last.admissible:
            k = len(fits) - 1
            return OrderSelection(fits, k, 'cost test', k - 1 if k else None)
    pool = [k for k, f in enumerate(fits) if f.admissible] or list(range(len(fits)))
    ranked = sorted(pool, key=lambda k: fits[k].aic)
    return OrderSelection(fits, ranked[0], 'AIC', ranked[1] if len(ranked) > 1 else None)
