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
Physical fit of the coupled robot: every axis's two-mass parameters plus the link coupling.

The MIMO FRF tau_m -> dq_m of the linearised robot (eqs. 20-22 with a full link inertia
matrix M_o = diag(Jo) + offdiag(link_coupling), as
:func:`~frf_ident.core.simulation.analytic.robot_frf`)::

    P(s) = s (Jm s^2 + Bv s + Z - Z (M_o s^2 + Z)^-1 Z)^-1,   Z = K + D s

is fitted to the whole n x n FRF by maximum likelihood (Levenberg-Marquardt on the residual of
every channel over its standard deviation), started from the per-axis fits of the diagonal
(:func:`~frf_ident.core.fit.physical.fit_two_mass`) and no coupling. A delay to fit is one
input delay of every axis, started from the median of the per-axis delays. Cramer-Rao standard
errors and the cost test as for one axis.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.fit.cost import cost_test, CostTest, normalised_residual
from frf_ident.core.fit.cramer_rao import cramer_rao
from frf_ident.core.fit.delay import delay_text
from frf_ident.core.fit.model_error import bound, shape_basis, shifts
from frf_ident.core.fit.physical import fit_two_mass, PARAMETERS, PhysicalFit, UNITS
import numpy as np
from scipy import optimize

__all__ = ['COUPLING_SCALE_SHARE', 'CoupledFit', 'DISAGREEMENT_ERRORS', 'coupled_response',
           'fit_coupled']

#: a per-axis and the coupled estimate of the same parameter are said to disagree when they
#: lie more than this many combined reported errors apart (sqrt(se_axis^2 + se_coupled^2)):
#: 2 is the 95 % band of a difference of two independent Gaussian estimates
DISAGREEMENT_ERRORS = 2.0
#: scale of a link-coupling term (started at 0): this share of sqrt(Jo_i Jo_j); it sets only
#: the conditioning of the first LM steps, not the minimum
COUPLING_SCALE_SHARE = 0.05


def _unpack(theta: np.ndarray, n: int):
    per = theta[:5 * n].reshape(5, n)              # rows in the order of PARAMETERS
    mo = np.diag(per[1])
    iu = np.triu_indices(n, 1)
    mo[iu] = theta[5 * n:]
    mo[(iu[1], iu[0])] = theta[5 * n:]
    return per, mo


def coupled_response(theta: np.ndarray, freq_hz: np.ndarray, n: int,
                     delay_s: float = 0.0) -> np.ndarray:
    """
    Return the MIMO FRF of the coupled robot.

    Parameters
    ----------
    theta : ndarray, shape (5 n + n (n - 1) / 2,)
        Jm (n), Jo (n), k (n), d (n), bv (n), then the upper off-diagonal link-coupling
        terms row by row [kg m^2].
    freq_hz : ndarray, shape (n_freq,)
        Frequencies in Hz.
    n : int
        Number of axes.
    delay_s : float, optional
        Known input delay [s].

    Returns
    -------
    ndarray of complex, shape (n, n, n_freq)
        P[i, j]: motor velocity of axis i per motor torque of axis j.

    """
    per, mo = _unpack(np.asarray(theta, dtype=float), n)
    jm, _, k, d, bv = per
    s = 2j * np.pi * np.asarray(freq_hz, dtype=float)[:, None, None]
    z = np.diag(k) + np.diag(d) * s                                   # (F, n, n)
    dyn = np.diag(jm) * s ** 2 + np.diag(bv) * s + z - z @ np.linalg.solve(mo * s ** 2 + z, z)
    p = s * np.linalg.inv(dyn) * np.exp(-s * delay_s)
    return np.moveaxis(p, 0, -1)


@dataclass
class CoupledFit:
    """
    The coupled robot fitted to its MIMO FRF.

    Attributes
    ----------
    names : list of str
        The axes.
    value, std : ndarray, shape (n_par,)
        ML estimate and Cramer-Rao standard errors, ordered as ``theta`` of
        :func:`coupled_response`.
    covariance : ndarray, shape (n_par, n_par)
        Inverse Fisher information at the estimate.
    per_axis : list of PhysicalFit
        The per-axis fits of the diagonal that started it.
    cost : CostTest
        The minimum cost against its chi-square expectation.
    model : ndarray of complex, shape (n, n, n_freq)
        The fitted FRF.
    delay_s : float
        The input delay of every axis [s]: given, or fitted.
    delay_std_s : float
        Cramer-Rao standard error of a fitted delay [s]; NaN when it was given.
    model_error : ndarray, shape (n_par,)
        Bound of the bias a missing structure can leave in each parameter
        (:mod:`frf_ident.core.fit.model_error`); zeros where the cost test passes.
    delay_model_error_s : float
        The same for a fitted delay [s].

    """

    names: list[str]
    value: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    per_axis: list[PhysicalFit]
    cost: CostTest
    model: np.ndarray
    delay_s: float = 0.0
    delay_std_s: float = float('nan')
    model_error: np.ndarray | None = None
    delay_model_error_s: float = 0.0

    @property
    def reported_std(self) -> np.ndarray:
        """Return the standard errors to report: Cramer-Rao and model-error bound combined."""
        return self.std if self.model_error is None else np.hypot(self.std, self.model_error)

    @property
    def delay_reported_std_s(self) -> float:
        """Return the reported standard error of a fitted delay [s] (NaN when given)."""
        return float(np.hypot(self.delay_std_s, self.delay_model_error_s))

    def axis_parameters(self, i: int) -> dict[str, float]:
        """Return axis i's five parameters as {model-file key: value}."""
        n = len(self.names)
        return {k: float(self.value[r * n + i]) for r, k in enumerate(PARAMETERS)}

    def axis_std(self, i: int, reported: bool = False) -> dict[str, float]:
        """Return axis i's standard errors (Cramer-Rao, or ``reported``) by model-file key."""
        n = len(self.names)
        sd = self.reported_std if reported else self.std
        return {k: float(sd[r * n + i]) for r, k in enumerate(PARAMETERS)}

    def link_coupling(self, reported: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Return the link-coupling matrix (zero diagonal) and its (``reported``) errors."""
        n = len(self.names)
        out = []
        for v in (self.value, self.reported_std if reported else self.std):
            m = np.zeros((n, n))
            iu = np.triu_indices(n, 1)
            m[iu] = v[5 * n:]
            out.append(m + m.T)
        return out[0], out[1]

    def disagreements(self) -> list[str]:
        """
        Return one line per parameter whose per-axis and coupled estimates disagree.

        Disagree: more than :data:`DISAGREEMENT_ERRORS` combined reported errors apart. The
        per-axis fit of the diagonal lacks the coupling (and sees one channel), so where the
        coupling matters the two differ by more than either's noise.
        """
        out = []
        for i, fit in enumerate(self.per_axis):
            sd = self.axis_std(i, reported=True)
            for r, (k, v) in enumerate(self.axis_parameters(i).items()):
                a, sa = float(fit.value[r]), float(fit.reported_std[r])
                apart = abs(a - v) / max(float(np.hypot(sa, sd[k])), 1e-300)
                if apart > DISAGREEMENT_ERRORS:
                    out.append(f'{self.names[i]} {k}: per axis {a:.5g} +- {sa:.2g}, coupled '
                               f'{v:.5g} +- {sd[k]:.2g} {UNITS[k]}: {apart:.3g} combined errors '
                               f'apart')
        return out

    def summary(self, hold_s: float = 0.0) -> list[str]:
        """
        Return each axis's parameters, the coupling terms, the delay and the cost test.

        Every line starts with ``coupled:``; values carry units and the reported errors
        (Cramer-Rao and model-error bound). ``hold_s``: the share of the delay a zero-order
        hold has by itself (half a sample), printed as the model file's ``time_delay``
        convention (delay - hold_s), as model.yaml writes it.
        """
        lines = []
        for i, name in enumerate(self.names):
            sd = self.axis_std(i, reported=True)
            parts = [f'{k} {v:.5g} +- {sd[k]:.2g} {UNITS[k]}'
                     for k, v in self.axis_parameters(i).items()]
            lines += [f'coupled: {name}: ' + ', '.join(parts[:3]),
                      f'coupled: {name}: ' + ', '.join(parts[3:])]
        c, sd = self.link_coupling(reported=True)
        iu = np.triu_indices(len(self.names), 1)
        terms = ', '.join(f'{self.names[i]}-{self.names[j]} {c[i, j]:.4g} +- {sd[i, j]:.2g}'
                          for i, j in zip(*iu))
        delay = delay_text(self.delay_s, self.delay_reported_std_s, hold_s)
        return lines + [f'coupled: link coupling [kg m^2]: {terms}',
                        f'coupled: {delay}',
                        f'coupled: {self.cost.summary()}',
                        f'coupled: {self.cost.verdict}']


def fit_coupled(freq_hz: np.ndarray, response: np.ndarray, variance: np.ndarray | None = None,
                *, delay_s: float | None = 0.0, names: list[str] | None = None) -> CoupledFit:
    """
    Fit every axis's two-mass parameters and the link coupling to a square MIMO FRF.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Frequencies in Hz.
    response : ndarray of complex, shape (n, n, n_freq)
        Measured FRF tau_m -> dq_m, inputs and outputs in the same axis order.
    variance : ndarray, shape (n, n, n_freq), optional
        Its variance; without it the relative error is minimised (see :func:`fit_two_mass`).
    delay_s : float or None, optional
        Known input delay of every axis [s]; None: fit it (one delay for all axes).
    names : list of str, optional
        Axis names.

    Returns
    -------
    CoupledFit
        Estimate, standard errors, the per-axis start and the cost test.

    Raises
    ------
    ValueError
        ``response`` is not square (n, n, n_freq) with n >= 2.

    """
    f = np.asarray(freq_hz, dtype=float)
    p = np.asarray(response, dtype=complex)
    n = p.shape[0]
    if p.ndim != 3 or p.shape[1] != n or n < 2:
        raise ValueError(f'a coupled fit needs a square MIMO FRF (n, n, n_freq), n >= 2; got '
                         f'{p.shape}')
    names = list(names or [f'axis_{i}' for i in range(n)])
    per_axis = [fit_two_mass(f, p[i, i], None if variance is None else variance[i, i],
                             delay_s=delay_s, name=names[i]) for i in range(n)]
    # magnitudes: a per-axis fit may be unphysical (a joint with backlash gave a negative
    # link inertia), and the coupling's scale, sqrt of a product of link inertias, was NaN
    start = np.concatenate([np.abs([a.value[r] for a in per_axis]) for r in range(5)]
                           + [np.zeros(n * (n - 1) // 2)])
    jo = start[n:2 * n]
    iu = np.triu_indices(n, 1)
    scale = np.concatenate([np.maximum(start[:5 * n], 1e-9 * start.max()),
                            COUPLING_SCALE_SHARE * np.sqrt(jo[iu[0]] * jo[iu[1]])])
    var = None if variance is None else np.asarray(variance, dtype=float).reshape(-1)
    fit_delay = delay_s is None
    if fit_delay:        # one delay for all axes; scale: 1 rad of phase at the highest line
        start = np.append(start, np.median([a.delay_s for a in per_axis]))
        scale = np.append(scale, 1.0 / (2 * np.pi * f.max()))

    def split(x):
        th = x * scale
        return (th[:-1], th[-1]) if fit_delay else (th, delay_s)

    def resid(x):
        th, d = split(x)
        return normalised_residual(coupled_response(th, f, n, d).reshape(-1), p.reshape(-1), var)

    sol = optimize.least_squares(resid, start / scale, method='lm', x_scale=1.0)
    test = cost_test(sol.fun, sol.x.size, variance is not None)
    cov_x = cramer_rao(sol.jac)
    if variance is None:
        cov_x = cov_x * test.cost / max(test.dof, 1)
    value, tau = split(sol.x)
    cov = cov_x * np.outer(scale, scale)
    tau_std = float(np.sqrt(cov[-1, -1])) if fit_delay else float('nan')
    cov = cov[:value.size, :value.size]
    model = coupled_response(value, f, n, tau)
    bias = np.zeros(scale.size)
    if test.structure_missing:
        sigma = np.sqrt(var.reshape(n * n, -1))
        basis = shape_basis(f, model.reshape(n * n, -1), np.sqrt(2.0) / sigma)
        bias = bound(shifts(sol.jac, basis, test.cost - test.dof)) * scale
    return CoupledFit(names, value, np.sqrt(np.diag(cov)), cov, per_axis, test, model,
                      float(tau), tau_std, model_error=bias[:value.size],
                      delay_model_error_s=float(bias[-1]) if fit_delay else 0.0)
