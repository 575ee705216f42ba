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
Physical fit of one flexible joint: the linearised two-mass model of eqs. 20-22.

The measured FRF of this project is motor velocity per motor torque, dq_m / tau_m
(:func:`~frf_ident.core.simulation.analytic.two_mass_frf`)::

    P(s) = N(s) / D(s),  N = Jo s^2 + d s + k,
    D = Jm Jo s^3 + (Jm d + Jo d + bv Jo) s^2 + (Jm k + Jo k + bv d) s + bv k

with the model-file parameters Jm (motor_inertia), Jo (link_inertia), k (stiffness),
d (damping) and bv (viscous_friction), times exp(-s tau) for an input delay tau (half a
sample for a zero-order-hold input, more with a computation or bus delay): given, or fitted
with the other five. Stages of :func:`fit_two_mass`:

1. linear start: Sanathanan-Koerner fit of the 2/3 rational form, mapped to the five
   parameters in closed form (:func:`physical_from_rational`), so no initial guess is needed;
   a fitted delay starts from the phase slope at high frequency (:func:`delay_from_phase`),
   refined once by the phase the delay-compensated start leaves;
2. maximum likelihood: Levenberg-Marquardt on the residual divided by the FRF's standard
   deviation (the ML estimate for a circular Gaussian FRF error);
3. Cramer-Rao standard errors from the Jacobian at the minimum (the delay's too), and the
   cost test (:mod:`frf_ident.core.fit.cost`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

from frf_ident.core.fit.cost import cost_test, CostTest, normalised_residual
from frf_ident.core.fit.cramer_rao import cramer_rao
from frf_ident.core.fit.delay import (delay_correction, delay_from_phase, DELAY_START_SHARE,
                                      delay_text)
from frf_ident.core.fit.levy import sanathanan_koerner
from frf_ident.core.fit.model_error import bound, shape_basis, shifts
from frf_ident.core.model.params import AxisParams
import numpy as np
from scipy import optimize

__all__ = ['DELAY_START_SHARE', 'PARAMETERS', 'PhysicalFit', 'UNITS', 'delay_from_phase',
           'delay_text', 'fit_two_mass', 'physical_from_rational', 'two_mass_jacobian',
           'two_mass_response']

#: the fitted parameters, in the order of every array of :class:`PhysicalFit`
PARAMETERS = ('motor_inertia', 'link_inertia', 'stiffness', 'damping', 'viscous_friction')
#: their units (those of the model file)
UNITS = {'motor_inertia': 'kg m^2', 'link_inertia': 'kg m^2', 'stiffness': 'N m/rad',
         'damping': 'N m s/rad', 'viscous_friction': 'N m s/rad'}

#: scale of the viscous friction when its start is about zero: this fraction of the total
#: inertia times the lowest measured angular frequency (friction that changes |P| there by
#: about 1 %); only the conditioning of the ML step depends on it, not its minimum
VISCOUS_SCALE_SHARE = 0.01


def _num_den(theta: np.ndarray, s: np.ndarray):
    jm, jo, k, d, bv = theta
    n = jo * s ** 2 + d * s + k
    dd = (jm * jo * s ** 3 + (jm * d + jo * d + bv * jo) * s ** 2
          + (jm * k + jo * k + bv * d) * s + bv * k)
    return n, dd


def two_mass_response(theta: np.ndarray, freq_hz: np.ndarray, delay_s: float = 0.0
                      ) -> np.ndarray:
    """
    Return the FRF dq_m / tau_m of the linear two-mass model.

    Parameters
    ----------
    theta : array_like, shape (5,)
        Jm, Jo, k, d, bv in the order of :data:`PARAMETERS` (SI units of the model file).
    freq_hz : ndarray, shape (n_freq,)
        Frequencies in Hz.
    delay_s : float, optional
        Known input delay [s].

    Returns
    -------
    ndarray of complex, shape (n_freq,)
        The response in rad/s per N m.

    """
    s = 2j * np.pi * np.asarray(freq_hz, dtype=float)
    n, d = _num_den(np.asarray(theta, dtype=float), s)
    return n / d * np.exp(-s * delay_s)


def two_mass_jacobian(theta: np.ndarray, freq_hz: np.ndarray, delay_s: float = 0.0
                      ) -> np.ndarray:
    """
    Return dP / dtheta of :func:`two_mass_response`.

    Parameters
    ----------
    theta : array_like, shape (5,)
        Parameters in the order of :data:`PARAMETERS`.
    freq_hz : ndarray, shape (n_freq,)
        Frequencies in Hz.
    delay_s : float, optional
        Known input delay [s].

    Returns
    -------
    ndarray of complex, shape (n_freq, 5)
        One column per parameter.

    """
    jm, jo, k, d, bv = np.asarray(theta, dtype=float)
    s = 2j * np.pi * np.asarray(freq_hz, dtype=float)
    n, dd = _num_den(theta, s)
    one, zero = np.ones_like(s), np.zeros_like(s)
    dn = [zero, s ** 2, one, s, zero]
    ddd = [jo * s ** 3 + d * s ** 2 + k * s,
           jm * s ** 3 + (bv + d) * s ** 2 + k * s,
           (jm + jo) * s + bv,
           (jm + jo) * s ** 2 + bv * s,
           n]
    cols = [(a * dd - n * b) / dd ** 2 for a, b in zip(dn, ddd)]
    return np.stack(cols, axis=1) * np.exp(-s * delay_s)[:, None]


def physical_from_rational(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """
    Map the coefficients of a 2/3 rational model to the five physical parameters.

    With D monic, N / D = (b2 s^2 + b1 s + b0) / (s^3 + a2 s^2 + a1 s + a0) and
    b2 = 1/Jm, b1 = d/(Jm Jo), b0 = k/(Jm Jo), a0 = bv k/(Jm Jo), a1 = k/Jo + k/Jm + bv d/(Jm Jo),
    so Jm = 1/b2, bv = a0/b0, k = Jm (a1 - bv b1 - b0/b2), Jo = k/(b0 Jm), d = b1 Jm Jo
    (a2 is not needed; its misfit goes to the ML step). Magnitudes are taken where noise
    made a start negative; the ML step does the rest.

    Parameters
    ----------
    num : array_like, shape (3,)
        b2, b1, b0 (descending powers).
    den : array_like, shape (4,)
        1, a2, a1, a0 (descending powers, monic).

    Returns
    -------
    ndarray, shape (5,)
        Jm, Jo, k, d, bv in the order of :data:`PARAMETERS`.

    """
    b2, b1, b0 = np.asarray(num, dtype=float) / float(den[0])
    _, _, a1, a0 = np.asarray(den, dtype=float) / float(den[0])
    jm = abs(1.0 / b2)
    bv = a0 / b0
    k = abs(jm * (a1 - bv * b1 - b0 / b2))
    jo = abs(k / (b0 * jm))
    d = abs(b1 * jm * jo)
    return np.array([jm, jo, k, d, bv])


@dataclass
class PhysicalFit:
    """
    The two-mass parameters of one axis fitted to its measured FRF.

    Attributes
    ----------
    name : str
        The axis (the FRF's input / output name).
    value : ndarray, shape (5,)
        ML estimate of Jm [kg m^2], Jo [kg m^2], k [N m/rad], d [N m s/rad], bv [N m s/rad]
        (order of :data:`PARAMETERS`).
    std : ndarray, shape (5,)
        Cramer-Rao standard errors (square roots of the diagonal of ``covariance``).
    covariance : ndarray, shape (5, 5)
        Inverse Fisher information at the estimate (from the residual's scale when the FRF
        had no variance).
    start : ndarray, shape (5,)
        The linear least-squares start.
    cost : CostTest
        The minimum cost against its chi-square expectation.
    freq_hz : ndarray, shape (n_freq,)
        The fitted lines [Hz].
    model : ndarray of complex, shape (n_freq,)
        The fitted model's FRF at ``freq_hz``.
    delay_s : float
        The delay the model included [s]: given, or fitted.
    evaluations : int
        Residual evaluations of the ML step.
    delay_std_s : float
        Cramer-Rao standard error of a fitted delay [s]; NaN when the delay was given.
    model_error : ndarray, shape (5,)
        Bound of the bias a missing structure can leave in each parameter
        (:mod:`frf_ident.core.fit.model_error`); zeros where the cost test passes.
    delay_model_error_s : float
        The same for a fitted delay [s] (0 otherwise).

    """

    name: str
    value: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    start: np.ndarray
    cost: CostTest
    freq_hz: np.ndarray
    model: np.ndarray
    delay_s: float = 0.0
    evaluations: int = 0
    names: tuple[str, ...] = field(default=PARAMETERS)
    delay_std_s: float = float('nan')
    model_error: np.ndarray = field(default_factory=lambda: np.zeros(5))
    delay_model_error_s: float = 0.0

    @property
    def reported_std(self) -> np.ndarray:
        """Return the standard errors to report: Cramer-Rao and model-error bound combined."""
        return np.hypot(self.std, self.model_error)

    @property
    def delay_reported_std_s(self) -> float:
        """Return the reported standard error of a fitted delay [s] (NaN when given)."""
        return float(np.hypot(self.delay_std_s, self.delay_model_error_s))

    @property
    def delay_fitted(self) -> bool:
        """Return True when the delay was estimated (it has a standard error)."""
        return bool(np.isfinite(self.delay_std_s))

    def parameters(self) -> dict[str, float]:
        """Return the estimate as {model-file key: value}."""
        return {k: float(v) for k, v in zip(self.names, self.value)}

    def standard_errors(self) -> dict[str, float]:
        """Return the Cramer-Rao standard errors as {model-file key: value}."""
        return {k: float(v) for k, v in zip(self.names, self.std)}

    def axis_params(self, base: AxisParams | None = None) -> AxisParams:
        """
        Return the axis of a model file with the fitted parameters.

        Parameters
        ----------
        base : AxisParams, optional
            The axis whose other keys (limits, nonlinear effects ...) are kept; default a
            fresh axis named ``name``.

        Returns
        -------
        AxisParams
            ``base`` with the five fitted keys replaced; a viscous friction estimated below
            zero (possible within its standard error when it is about zero) is written as 0.

        """
        base = base if base is not None else AxisParams(name=self.name)
        vals = self.parameters()
        vals['viscous_friction'] = max(vals['viscous_friction'], 0.0)
        return replace(base, **vals)

    def resonances_hz(self) -> tuple[float, float]:
        """Return the antiresonance sqrt(k/Jo) and resonance sqrt(k (1/Jm + 1/Jo)) in Hz."""
        jm, jo, k = self.value[:3]
        return (float(np.sqrt(k / jo) / (2 * np.pi)),
                float(np.sqrt(k * (1 / jm + 1 / jo)) / (2 * np.pi)))

    def summary(self, hold_s: float = 0.0) -> list[str]:
        """
        Return a few lines for people: parameters with units and errors, delay, cost, verdict.

        The errors are the reported ones (Cramer-Rao and the model-error bound); ``hold_s``
        is the zero-order hold's share of the delay (half a sample of the model file), shown
        apart so that the printed ``time_delay`` is the one model.yaml holds.
        """
        fa, fr = self.resonances_hz()
        parts = [f'{k} {v:.5g} +- {s:.2g} {UNITS[k]}'
                 for k, v, s in zip(self.names, self.value, self.reported_std)]
        delay = delay_text(self.delay_s, self.delay_reported_std_s, hold_s)
        return [f'{self.name}: ' + ', '.join(parts[:3]),
                f'{self.name}: ' + ', '.join(parts[3:])
                + f'; antiresonance {fa:.2f} Hz, resonance {fr:.2f} Hz',
                f'{self.name}: {delay}',
                f'{self.name}: {self.cost.summary()}',
                f'{self.name}: {self.cost.verdict}']


def fit_two_mass(freq_hz: np.ndarray, response: np.ndarray, variance: np.ndarray | None = None,
                 *, delay_s: float | None = 0.0, name: str = 'joint_1') -> PhysicalFit:
    """
    Fit the two-mass flexible joint to a measured FRF dq_m / tau_m by maximum likelihood.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Frequencies in Hz (at least 3 lines).
    response : ndarray of complex, shape (n_freq,)
        Measured FRF [rad/s per N m].
    variance : ndarray, shape (n_freq,), optional
        Its variance E|P_hat - P|^2. Without it the relative error is minimised and the
        standard errors come from the residual (the cost test cannot decide then).
    delay_s : float or None, optional
        Known input delay the model includes [s] (half a sample for a zero-order hold);
        None: fit the delay too (a sixth parameter, with its standard error).
    name : str, optional
        The axis name carried by the result.

    Returns
    -------
    PhysicalFit
        Estimate, Cramer-Rao standard errors, linear start and cost test.

    Raises
    ------
    ValueError
        Fewer than 3 lines, or a variance that is not positive and finite.

    """
    f = np.asarray(freq_hz, dtype=float)
    p = np.asarray(response, dtype=complex)
    if f.size < 3:
        raise ValueError(f'a physical fit needs at least 3 frequency lines, got {f.size}')
    if variance is not None:
        variance = np.asarray(variance, dtype=float)
        if not np.all(np.isfinite(variance) & (variance > 0)):
            raise ValueError('variance must be positive and finite on every line')
    sigma = np.sqrt(variance) if variance is not None else np.abs(p)
    fit_delay = delay_s is None
    # 1. linear starts on the delay-free response. A fitted delay starts from the phase
    #    slope and from that slope refined once by the phase the compensated start leaves;
    #    where the model misses part of the record (friction, a further mode) the
    #    refinement can overshoot, so both are tried and the ML fit of lower cost among the
    #    physical ones (positive inertias, stiffness, damping) is kept.
    tau = delay_from_phase(f, p) if fit_delay else float(delay_s)
    starts = [(_linear_start(f, p, sigma, tau), tau)]
    if fit_delay:
        refined = max(tau + delay_correction(f, p, two_mass_response(starts[0][0], f, tau),
                                             sigma), 0.0)
        starts.append((_linear_start(f, p, sigma, refined), refined))
    # 2. ML in scaled parameters x = theta / scale (and tau / tau_scale)
    fits = [_ml_fit(f, p, variance, sigma, start, t, fit_delay) for start, t in starts]
    sol, scale, start, tau0 = min(fits, key=lambda r: (not _physical(r[0].x * r[1]),
                                                       float(r[0].cost)))
    # 3. Cramer-Rao bound (unit-variance residual) and cost test
    jr = sol.jac
    cov_x = cramer_rao(jr)
    test = cost_test(sol.fun, sol.x.size, variance is not None)
    if variance is None:
        cov_x = cov_x * test.cost / max(test.dof, 1)
    th = sol.x * scale
    value, tau = (th[:5], th[5]) if fit_delay else (th, tau0)
    cov = cov_x * np.outer(scale, scale)
    tau_std = float(np.sqrt(cov[5, 5])) if fit_delay else float('nan')
    cov = cov[:5, :5]
    model = two_mass_response(value, f, tau)
    bias = _model_error(f, model, sigma, jr, scale, test) if variance is not None else None
    bias = np.zeros(scale.size) if bias is None else bias
    return PhysicalFit(name, value, np.sqrt(np.diag(cov)), cov, start, test, f, model,
                       float(tau), int(sol.nfev), delay_std_s=tau_std, model_error=bias[:5],
                       delay_model_error_s=float(bias[5]) if fit_delay else 0.0)


def _model_error(f: np.ndarray, model: np.ndarray, sigma: np.ndarray, jac: np.ndarray,
                 scale: np.ndarray, test: CostTest) -> np.ndarray | None:
    """Return the model-error bound of every fitted parameter (None: the cost test passes)."""
    if not test.structure_missing:
        return None
    basis = shape_basis(f, model[None], (np.sqrt(2.0) / sigma)[None])
    return bound(shifts(jac, basis, test.cost - test.dof)) * scale


def _physical(theta: np.ndarray) -> bool:
    """Return whether inertias, stiffness and damping are positive (the viscous may be 0)."""
    return bool(np.all(theta[:4] > 0))


def _ml_fit(f: np.ndarray, p: np.ndarray, variance: np.ndarray | None, sigma: np.ndarray,
            start: np.ndarray, tau: float, fit_delay: bool) -> tuple:
    """Return (LM solution, parameter scale, start, tau) of the ML fit from ``start``."""
    scale = np.abs(start)
    scale[4] = max(scale[4], VISCOUS_SCALE_SHARE * (start[0] + start[1]) * 2 * np.pi * f.min())
    if fit_delay:        # a delay that turns the phase at the highest line by 1 rad
        scale = np.append(scale, 1.0 / (2 * np.pi * f.max()))
    weight = np.sqrt(2.0) / sigma

    def split(x):
        th = x * scale
        return (th[:5], th[5]) if fit_delay else (th, tau)

    def resid(x):
        th, d = split(x)
        return normalised_residual(two_mass_response(th, f, d), p, variance)

    def jac(x):
        th, d = split(x)
        j = two_mass_jacobian(th, f, d)
        if fit_delay:
            j = np.hstack([j, (-2j * np.pi * f * two_mass_response(th, f, d))[:, None]])
        j = j * (weight[:, None] * scale[None, :])
        return np.vstack([j.real, j.imag])

    x0 = np.append(start, tau) / scale if fit_delay else start / scale
    return optimize.least_squares(resid, x0, jac=jac, method='lm', x_scale=1.0), scale, start, tau


def _linear_start(f: np.ndarray, p: np.ndarray, sigma: np.ndarray, tau: float) -> np.ndarray:
    """Return the five parameters of the Sanathanan-Koerner 2/3 fit of p exp(s tau)."""
    num, den = sanathanan_koerner(f, p * np.exp(2j * np.pi * f * tau), 2, 3, 1.0 / sigma)
    return physical_from_rational(num, den)
