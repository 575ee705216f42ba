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
Fit the robot's linear parameters, and a second link-side mode, to an FRF relative to a model's.

The data are the diagonal of a measured FRF divided by the same estimate of a nominal model's
simulation, R_i = P_meas,ii / P_sim,ii per axis i, with the standard deviation of R per line:
whatever the estimator and the sampling do alike to both (leakage, the hold, the controller's
share of the closed loop) cancels, and for the nominal model itself R = 1 up to the noise.
The model of R is the analytic continuous FRF of a changed model over the nominal's,
P_theta,ii / P_nom,ii (:func:`~frf_ident.core.simulation.analytic.link_chain_frf`, the coupled
robot with the axes' second modes), on every axis at once: a mode behind one link shows on the
coupled axes too.

- :func:`fit_linear_ratio`: log scale factors of every axis' motor inertia, link inertia,
  stiffness and damping (:data:`LINEAR`), maximum likelihood (Levenberg-Marquardt on the
  residual over its standard deviation). Its residual is what no linear parameter change
  explains (:mod:`frf_ident.core.fit.residual_whiteness` says where).
- :func:`fit_second_mode`: the same with one axis' second mode added (the keys of
  docs/model_file.md: the frequency tuned with the link held, the damping ratio, the share of
  the link's inertia on the spring) and every axis' linear scales; started from a grid around
  a band of the linear fit's residual, Cramer-Rao
  standard errors from the Jacobian at the minimum (widened by sqrt(cost / dof) above 1).
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from frf_ident.core.fit.cramer_rao import cramer_rao
from frf_ident.core.model.params import RobotParams
from frf_ident.core.simulation.analytic import link_chain_frf, second_mode_stiffness
import numpy as np
from scipy import optimize

__all__ = ['LINEAR', 'LinearRatioFit', 'ModeFit', 'RatioData', 'START_DAMPING',
           'START_FREQUENCY_SHARES', 'START_RATIOS', 'fit_linear_ratio', 'fit_second_mode']

#: the linear parameters each axis may scale (viscous friction: friction confounds it)
LINEAR = ('motor_inertia', 'link_inertia', 'stiffness', 'damping')
#: starts of a mode fit: its link-held frequency as these shares of the band's centre (the
#: resonance a mode adds lies above the frequency it has with the link held: 24.4 Hz for a
#: 22 Hz mode of 18 % of joint_3's link, 23.7 Hz for a 19.3 Hz mode of 24 % of joint_2's)
START_FREQUENCY_SHARES = (0.7, 0.85, 1.0)
#: ... the share of the link's inertia on the spring and the damping ratio
START_RATIOS = (0.1, 0.3)
START_DAMPING = (0.02,)
#: residual evaluations of one start of the grid and of the polish: a start heading for a
#: minimum converges in well under 100 (the grid's 12 starts then take about half a second);
#: one drifting to a vanishing damping ratio would take seconds
GRID_EVALUATIONS = 150
POLISH_EVALUATIONS = 600


@dataclass(frozen=True)
class RatioData:
    """The diagonal of a measured FRF over a nominal simulation's, with its noise."""

    #: the lines [Hz], shape (n_freq,)
    freq_hz: np.ndarray
    #: R = P_meas,ii / P_sim,ii, shape (n_axes, n_freq)
    ratio: np.ndarray
    #: standard deviation of R per line, shape (n_axes, n_freq)
    sigma: np.ndarray


@dataclass
class LinearRatioFit:
    """Every axis' linear parameters fitted to the ratio."""

    #: log scale factor per axis and parameter of :data:`LINEAR`, shape (n_axes, 4)
    log_scale: np.ndarray
    #: their Cramer-Rao standard errors, shape (n_axes, 4)
    log_scale_std: np.ndarray
    #: (model - R) / sigma per axis and line: unit variance under noise, shape (n_axes, n_freq)
    residual: np.ndarray
    #: sum of 2 |residual|^2 and its degrees of freedom (2 n_axes n_freq - parameters)
    cost: float
    dof: int


@dataclass
class ModeFit:
    """A second mode on one axis (and that axis' linear scales) fitted to the ratio."""

    axis: int
    #: the mode as the model file writes it (docs/model_file.md) and its standard errors
    frequency_hz: float
    damping_ratio: float
    inertia: float
    frequency_std: float
    damping_std: float
    inertia_std: float
    #: the axis' log scale factors of :data:`LINEAR` and their standard errors, shape (4,)
    log_scale: np.ndarray
    log_scale_std: np.ndarray
    #: (model - R) / sigma per axis and line, shape (n_axes, n_freq)
    residual: np.ndarray
    #: the fit's cost (sum of 2 |residual|^2 with the other axes' channels weighted down, see
    #: :func:`fit_second_mode`), its degrees of freedom, and the linear fit's cost weighted
    #: alike (what the mode is compared with)
    cost: float
    dof: int
    linear_cost: float

    def second_mode(self) -> dict[str, float]:
        """Return the model file's ``second_mode`` mapping."""
        return {'frequency_hz': self.frequency_hz, 'damping_ratio': self.damping_ratio,
                'inertia': self.inertia}

    def second_mode_std(self) -> dict[str, float]:
        """Return the standard errors of :meth:`second_mode`, same keys."""
        return {'frequency_hz': self.frequency_std, 'damping_ratio': self.damping_std,
                'inertia': self.inertia_std}


class _Model:
    """The ratio P_theta,ii / P_nom,ii of a robot whose linear arrays and a mode are changed."""

    def __init__(self, robot: RobotParams, data: RatioData) -> None:
        self.f = np.asarray(data.freq_hz, dtype=float)
        self.s = 2j * np.pi * self.f
        self.base = np.array([[getattr(a, k) for k in LINEAR] for a in robot.axes])
        self.bv = np.array([a.viscous_friction for a in robot.axes])
        self.coupling = robot.link_inertia_matrix() - np.diag(np.diag(robot.link_inertia_matrix()))
        self.n = robot.n_axes
        # the model's own second modes: their inertia leaves the rigid link, their dynamic
        # stiffness loads it (second_mode_stiffness)
        self.mode_inertia = np.diag(robot.link_inertia_matrix()
                                    - robot.rigid_link_inertia_matrix())
        self.mode_stiffness = second_mode_stiffness(robot, self.s)
        self.data = data
        self.nominal = self.diagonal(np.zeros((self.n, 4)))

    def diagonal(self, log_scale: np.ndarray, mode: tuple[int, float, float, float] | None = None
                 ) -> np.ndarray:
        """
        Return P_theta,ii (n, n_freq): the linear arrays scaled, ``mode`` in place.

        ``mode`` (axis, frequency, damping ratio, inertia) replaces that axis' own second mode
        (if any); the other axes keep theirs.
        """
        p = self.base * np.exp(log_scale)
        stiff = self.mode_stiffness.copy()
        rigid = np.diag(p[:, 1] - self.mode_inertia) + self.coupling
        if mode is not None:
            i, fe, ze, je = mode
            w = 2 * math.pi * fe
            ze_ = je * w * w + 2 * ze * je * w * self.s
            stiff[:, i] = je * self.s ** 2 * ze_ / (je * self.s ** 2 + ze_)
            rigid[i, i] += self.mode_inertia[i] - je
        full = link_chain_frf(p[:, 0], self.bv, p[:, 2], p[:, 3], rigid, stiff, self.f)
        idx = np.arange(self.n)
        return full[idx, idx]

    def residual(self, log_scale: np.ndarray, mode=None) -> np.ndarray:
        """Return (P_theta / P_nom - R) / sigma, shape (n, n_freq)."""
        d = self.data
        return (self.diagonal(log_scale, mode) / self.nominal - d.ratio) / d.sigma


def _real(e: np.ndarray) -> np.ndarray:
    """Return sqrt(2) [Re e, Im e] flattened: unit variance per entry under noise."""
    return math.sqrt(2.0) * np.concatenate([e.real.ravel(), e.imag.ravel()])


def _covariance(sol: optimize.OptimizeResult, dof: int) -> np.ndarray:
    """Return the Cramer-Rao covariance at the minimum, widened by cost / dof above 1."""
    return cramer_rao(sol.jac) * max(1.0, 2.0 * float(sol.cost) / max(dof, 1))


def fit_linear_ratio(robot: RobotParams, data: RatioData) -> LinearRatioFit:
    """
    Fit every axis' linear parameters to the ratio by maximum likelihood.

    Parameters
    ----------
    robot : RobotParams
        The nominal model the ratio was taken against.
    data : RatioData
        The ratio and its standard deviation.

    Returns
    -------
    LinearRatioFit
        The log scale factors, their standard errors and the normalised residual.

    """
    m = _Model(robot, data)
    n = m.n

    def res(x):
        return _real(m.residual(x.reshape(n, 4)))
    sol = optimize.least_squares(res, np.zeros(4 * n), method='lm', x_scale=0.1)
    dof = sol.fun.size - sol.x.size
    sd = np.sqrt(np.diag(_covariance(sol, dof))).reshape(n, 4)
    x = sol.x.reshape(n, 4)
    return LinearRatioFit(x, sd, m.residual(x), 2.0 * float(sol.cost), dof)


def fit_second_mode(robot: RobotParams, data: RatioData, axis: int, centre_hz: float,
                    linear: LinearRatioFit) -> ModeFit | None:
    """
    Fit a second mode on one axis, with that axis' linear scales, to the ratio.

    Levenberg-Marquardt from every start of the grid (:data:`START_FREQUENCY_SHARES` of
    ``centre_hz`` x :data:`START_RATIOS` x :data:`START_DAMPING`) in log frequency, log damping
    ratio and the logit of the share of the link's inertia on the spring, the other axes at
    the linear fit's scales; the best is polished with every axis' linear scales free. Every
    other axis'
    channel is weighted down by its own linear fit's cost per degree of freedom (where above
    1): what no linear change explains there (another axis' time delay, 39,000 times the
    noise) would otherwise drive the mode to mimic it through the link coupling, while a
    mode's coupled trace on a neighbour keeps the weight of its noise.

    Parameters
    ----------
    robot : RobotParams
        The nominal model the ratio was taken against.
    data : RatioData
        The ratio and its standard deviation.
    axis : int
        The axis whose link carries the mode.
    centre_hz : float
        The centre of the band of the linear fit's residual that asks for it [Hz].
    linear : LinearRatioFit
        The linear fit (its scales of the axis start the grid).

    Returns
    -------
    ModeFit or None
        The fit of lowest cost; None when no start converged to a finite cost.

    """
    n = robot.n_axes
    per_dof = np.sum(2.0 * np.abs(linear.residual) ** 2, axis=1) / max(
        2 * data.freq_hz.size - len(LINEAR), 1)
    inflate = np.where(np.arange(n) == axis, 1.0, np.sqrt(np.maximum(per_dof, 1.0)))
    weighted = RatioData(data.freq_hz, data.ratio, data.sigma * inflate[:, None])
    m = _Model(robot, weighted)
    linear_cost = float(np.sum(2.0 * np.abs(linear.residual / inflate[:, None]) ** 2))

    def split(x, ls):
        ls = ls.copy()
        ls[axis] = x[:4]
        r = 1.0 / (1.0 + math.exp(-x[6]))
        return ls, (axis, math.exp(x[4]), math.exp(x[5]), r * m.base[axis, 1] * math.exp(x[1]))

    # the grid with the other axes at the linear fit's scales (a neighbour's own linear
    # change, a stiffening gear's effective stiffness, moves this channel through the
    # coupling; a neighbour the mode bends weighs little, see above), then the best start
    # polished with every axis' linear scales free
    best = None
    for share in START_FREQUENCY_SHARES:
        for ratio in START_RATIOS:
            for zeta in START_DAMPING:
                x0 = np.concatenate([linear.log_scale[axis], [
                    math.log(share * centre_hz), math.log(zeta), math.log(ratio / (1 - ratio))]])
                sol = _solve(lambda x: _real(m.residual(*split(x, linear.log_scale))), x0,
                             np.r_[[0.1] * 4, 0.1, 0.5, 0.5], GRID_EVALUATIONS)
                if sol is not None and (best is None or sol.cost < best.cost):
                    best = sol
    if best is None:
        return None

    def full(x):
        ls = x[:4 * n].reshape(n, 4)
        return split(np.concatenate([ls[axis], x[4 * n:]]), ls)
    x0 = np.concatenate([np.where(np.arange(n)[:, None] == axis, best.x[:4],
                                  linear.log_scale).ravel(), best.x[4:]])
    sol = _solve(lambda x: _real(m.residual(*full(x))), x0, np.r_[[0.1] * 4 * n, 0.1, 0.5, 0.5],
                 POLISH_EVALUATIONS)
    sol = sol if sol is not None and sol.cost <= best.cost else None
    if sol is None:
        return None
    dof = sol.fun.size - sol.x.size
    cov = _covariance(sol, dof)
    sd = np.sqrt(np.diag(cov))
    ls, (_, fe, ze, je) = full(sol.x)
    r = 1.0 / (1.0 + math.exp(-sol.x[-1]))
    # log inertia = log r + log link scale + const: d/dlogit log r = 1 - r
    g = np.zeros(sol.x.size)
    g[-1], g[4 * axis + 1] = 1.0 - r, 1.0
    k = 4 * n
    inertia_sd = je * math.sqrt(max(float(g @ cov @ g), 0.0))
    return ModeFit(axis, float(fe), float(ze), float(je), float(fe * sd[k]), float(ze * sd[k + 1]),
                   float(inertia_sd), ls[axis], sd[4 * axis:4 * axis + 4],
                   m.residual(ls, (axis, fe, ze, je)) * inflate[:, None], 2.0 * float(sol.cost),
                   dof, linear_cost)


def _solve(res, x0: np.ndarray, x_scale: np.ndarray, max_nfev: int
           ) -> optimize.OptimizeResult | None:
    """Return Levenberg-Marquardt's minimum of sum res^2 from x0, None where it failed."""
    try:
        sol = optimize.least_squares(res, x0, method='lm', x_scale=x_scale, max_nfev=max_nfev)
    except (ValueError, np.linalg.LinAlgError, OverflowError):
        return None
    return sol if np.isfinite(sol.cost) else None
