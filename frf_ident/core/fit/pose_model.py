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
One model across the workspace from physical fits at several poses.

At each pose the coupled physical fit (:func:`~frf_ident.core.fit.coupled.fit_coupled`) gives
the drive side of every axis (motor inertia, stiffness, damping, viscous friction) and the
link inertia matrix M(q) seen there (diagonal: ``link_inertia``, off-diagonal:
``link_coupling``), each with its Cramer-Rao standard error. The drive side does not depend
on the pose, so :func:`pool_drive` combines it over the poses (inverse-variance weighted
means). M(q) is linear in the links' inertial parameters pi (the kinematics give the
regressor Y(q), M(q) = Y(q) pi; Wernholt & Moberg, Automatica 47(4) 2011, fit the same way),
so :func:`fit_inertial_parameters` solves the weighted least-squares problem over all poses
for the correction of a prior pi (the URDF's): the smallest correction, in units of the
prior's own magnitudes, that explains the fitted M(q). Directions of pi the poses do not
see (M(q) does not depend on them there) keep the prior. :func:`median_db_error` scores a
predicted FRF against a measured one.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ['IDENTIFIABLE_RCOND', 'InertialFit', 'PRIOR_SCALE_FLOOR', 'fit_inertial_parameters',
           'median_db_error', 'pool_drive']

#: singular values of the weighted, prior-scaled regressor below this share of the largest are
#: combinations of inertial parameters the poses do not determine (their correction would be
#: noise amplified by more than 1e4): they keep the prior. The demo robot's 9-pose campaign has
#: singular values spanning 1e1 in the determined block and < 1e-12 beyond it, so any value
#: between 1e-10 and 1e-2 gives the same rank
IDENTIFIABLE_RCOND = 1e-4

#: a prior parameter of (about) zero is scaled by this share of the largest magnitude among
#: the same link's parameters of its kind (mass; first moments; inertia entries), so a product
#: of inertia the URDF sets to 0 can still be corrected, by amounts the size of its neighbours'
PRIOR_SCALE_FLOOR = 0.1

#: pinocchio's 10 parameters per link in kinds: mass, first moments m c, inertia entries
#: (another number of parameters per link is one kind)
_KINDS = (slice(0, 1), slice(1, 4), slice(4, 10))


@dataclass(frozen=True)
class InertialFit:
    """
    Inertial parameters fitted to link inertia matrices seen at several poses.

    Attributes
    ----------
    value : ndarray, shape (n_par,)
        The fitted parameters (prior plus correction).
    prior : ndarray, shape (n_par,)
        The prior they started from.
    std : ndarray, shape (n_par,)
        Standard errors of ``value`` (0 in directions the poses do not determine).
    rank : int
        Number of parameter combinations the poses determine.
    n_obs : int
        Number of link-inertia entries fitted.
    rms_before : float
        RMS of the normalised residual (entry error / its standard error) with the prior.
    rms_after : float
        The same with the fitted parameters.

    """

    value: np.ndarray
    prior: np.ndarray
    std: np.ndarray
    rank: int
    n_obs: int
    rms_before: float
    rms_after: float


def _prior_scale(prior: np.ndarray, per_link: int) -> np.ndarray:
    p = np.abs(np.asarray(prior, dtype=float)).reshape(-1, per_link)
    scale = np.empty_like(p)
    for sl in (_KINDS if per_link == 10 else (slice(0, per_link),)):
        top = p[:, sl].max(axis=1, keepdims=True)
        floor = np.where(top > 0, PRIOR_SCALE_FLOOR * top, 1.0)
        scale[:, sl] = np.maximum(p[:, sl], floor)
    return scale.reshape(-1)


def fit_inertial_parameters(regressors: np.ndarray, observed: np.ndarray, std: np.ndarray,
                            prior: np.ndarray, *, per_link: int = 10) -> InertialFit:
    """
    Fit inertial parameters to link-inertia entries seen at several poses.

    Minimises sum ((Y_k pi - m_k) / s_k)^2 over all poses k and entries, with the smallest
    correction pi - prior (each parameter in units of its prior magnitude, see
    :data:`PRIOR_SCALE_FLOOR`) among the minimisers; directions below
    :data:`IDENTIFIABLE_RCOND` keep the prior.

    Parameters
    ----------
    regressors : ndarray, shape (n_pose, n_obs, n_par)
        Y(q_k): entries of M(q_k) as linear functions of the parameters.
    observed : ndarray, shape (n_pose, n_obs)
        The fitted entries m_k [kg m^2]; NaN where a pose did not fit one (left out).
    std : ndarray, shape (n_pose, n_obs)
        Their standard errors (> 0).
    prior : ndarray, shape (n_par,)
        The start (the URDF's parameters).
    per_link : int, optional
        Parameters per link (pinocchio: 10), for the prior scaling.

    Returns
    -------
    InertialFit
        The fitted parameters, their standard errors and rank.

    Raises
    ------
    ValueError
        Shapes that do not match, or a standard error that is not positive.

    """
    y = np.asarray(regressors, dtype=float)
    m = np.asarray(observed, dtype=float)
    s = np.asarray(std, dtype=float)
    pi0 = np.asarray(prior, dtype=float)
    if y.ndim != 3 or m.shape != y.shape[:2] or s.shape != m.shape or pi0.shape != y.shape[2:]:
        raise ValueError(f'regressors {y.shape}, observed {m.shape}, std {s.shape}, prior '
                         f'{pi0.shape}: expected (K, N, P), (K, N), (K, N), (P,)')
    keep = np.isfinite(m)
    if not np.all(s[keep] > 0):
        raise ValueError('every standard error of a fitted entry must be positive')
    a = y[keep] / s[keep][:, None]
    b = (m[keep] - y[keep] @ pi0) / s[keep]
    scale = _prior_scale(pi0, per_link)
    u, sv, vt = np.linalg.svd(a * scale[None, :], full_matrices=False)
    rank = int(np.sum(sv > IDENTIFIABLE_RCOND * sv[0])) if sv.size else 0
    u, sv, vt = u[:, :rank], sv[:rank], vt[:rank]
    x = vt.T @ ((u.T @ b) / sv)
    value = pi0 + scale * x
    cov = (vt.T / sv ** 2) @ vt * np.outer(scale, scale)
    rms = [float(np.sqrt(np.mean(r ** 2))) if r.size else 0.0 for r in (b, b - a @ (scale * x))]
    return InertialFit(value, pi0, np.sqrt(np.clip(np.diag(cov), 0, None)), rank,
                       int(keep.sum()), rms[0], rms[1])


def pool_drive(values: np.ndarray, std: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Combine pose-independent parameters fitted at several poses (inverse-variance weights).

    Parameters
    ----------
    values : ndarray, shape (n_pose, ...)
        One fit per pose.
    std : ndarray, same shape
        Their standard errors (> 0).

    Returns
    -------
    mean : ndarray, shape (...)
        The weighted means.
    std : ndarray, shape (...)
        Their standard errors, 1 / sqrt(sum of weights), times sqrt(chi^2 / dof) where the
        poses scatter more than their errors say (Birge ratio above 1).

    """
    v = np.asarray(values, dtype=float)
    w = 1.0 / np.asarray(std, dtype=float) ** 2
    mean = (w * v).sum(axis=0) / w.sum(axis=0)
    sd = 1.0 / np.sqrt(w.sum(axis=0))
    if v.shape[0] > 1:
        birge = np.sqrt((w * (v - mean) ** 2).sum(axis=0) / (v.shape[0] - 1))
        sd = sd * np.maximum(birge, 1.0)
    return mean, sd


def median_db_error(predicted: np.ndarray, measured: np.ndarray, quantile: float = 0.5
                    ) -> float:
    """
    Return the median (or another quantile) over all entries of |20 log10 |predicted / measured||.

    Parameters
    ----------
    predicted, measured : ndarray of complex, same shape
        FRFs (any channels and lines); entries where either is zero or not finite are left
        out.
    quantile : float, optional
        Which quantile of the errors (0.5: the median; 0.95 shows the lines near the modes,
        where a pose-independent model misses).

    Returns
    -------
    float
        The error in dB (NaN when nothing is left).

    """
    p, m = np.abs(np.asarray(predicted)), np.abs(np.asarray(measured))
    ok = np.isfinite(p) & np.isfinite(m) & (p > 0) & (m > 0)
    if not ok.any():
        return float('nan')
    return float(np.quantile(np.abs(20 * np.log10(p[ok] / m[ok])), quantile))
