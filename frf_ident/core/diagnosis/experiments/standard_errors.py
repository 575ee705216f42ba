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
Give the simulation fits of an axis' effects their standard errors.

The experiments route fits effects by closed-loop simulation: their values minimise the axis'
misfit, the sum of squares of the residual of :mod:`.residuals`. At that optimum the Jacobian
of the residual (forward differences: one simulation per parameter, in the evaluator's
workers) linearises the fit, and the covariance of the values is the block-robust (CR2)
sandwich over the residual's blocks (:func:`..selection.cluster_covariance`): the residual is
taken as it is, coloured, with whatever misfit the model still has within a block. The same
linearisation gives the refit on the multisine alone and on the chirp alone (two independent
experiments of one record) without further simulation: where they disagree beyond their
errors, the parameter has not settled (:mod:`.settle`).

The sandwich covers the record's noise, not what our simulator does differently from the plant:
a stiffening gear found within 0.05 % of the truth lay 25 of its errors off (pair seed 5804).
The part of that the simulator's own step causes is measured on the record: the model simulated
once more at twice its substeps moves the residual by d, and the linearised refit of d is the
change of the values a finer simulator would give; extrapolated to an infinitely fine step
(STEP_BIAS_FACTOR) it is the values' step bias, added to their errors in quadrature where the
finer simulation fits the record at least as well (:func:`step_bias`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Any

from frf_ident.core.model.params import RobotParams
import numpy as np

from .evaluator import Evaluator
from .refit import rebuild
from .residuals import axis_residual, layout
from ..common import Effect
from ..selection import cluster_covariance
from ..thresholds import REFITS_AGREE_Z, SE_STEP, SIM_CACHE, STEP_BIAS_FACTOR

__all__ = ['AxisFit', 'axis_fit', 'effects_with', 'gauss_newton_step', 'model_with', 'Slot',
           'slots_of', 'step_bias']

#: term fields with a standard error: (field, moved in radians of phase)
_TERM_FIELDS = (('amplitude', False), ('spatial_frequency', True), ('phase', True))


@dataclass(frozen=True)
class Slot:
    """One parameter of a kept effect of the axis, as the Jacobian moves it."""

    effect: Effect
    #: the parameter key; for a list-valued one (ripple, gravity) its last term's ``field``
    key: str
    field: str | None
    value: float
    #: the finite-difference step (model units)
    step: float

    @property
    def label(self) -> str:
        """Return 'key' or 'key field' (how the report names it)."""
        return self.key if self.field is None else f'{self.key} {self.field}'

    @property
    def magnitude(self) -> bool:
        """Return whether it is a scale (a share of its value means something)."""
        return self.field in (None, 'amplitude')


@dataclass
class AxisFit:
    """The linearised simulation fit of one axis' effects at the values the search found."""

    slots: list[Slot]
    #: standard error of each slot (inf: the record leaves the direction free): the largest of
    #: the sandwich's (:attr:`within`), the one the experiments' spread implies where they
    #: disagree beyond REFITS_AGREE_Z, and the distance to the linearised optimum; with the
    #: step bias (:attr:`step_bias`) added in quadrature
    se: np.ndarray
    #: covariance of the slots' values
    cov: np.ndarray
    #: per experiment ('multisine', 'chirp') the linearised refit on it alone: (values, se)
    alone: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    #: the Jacobian of the residual per finite-difference step and the residual itself
    jacobian: np.ndarray | None = None
    residual: np.ndarray | None = None
    #: the block-robust sandwich's standard errors (the record's noise and misfit alone)
    within: np.ndarray | None = None
    #: per slot the step bias: STEP_BIAS_FACTOR times the change of the value that the
    #: model simulated at twice its substeps asks for (in ``se``, in quadrature)
    step_bias: np.ndarray | None = None
    #: the values of the linearised refit of all slots together (where the search stopped,
    #: were it the optimum)
    optimum: np.ndarray | None = None

    def values(self) -> np.ndarray:
        """Return the slots' values."""
        return np.array([s.value for s in self.slots])

    def correlation(self) -> np.ndarray:
        """Return the correlation matrix of the slots' values (0 where an error is not finite)."""
        d = np.where(np.isfinite(self.se) & (self.se > 0), self.se, np.inf)
        with np.errstate(invalid='ignore'):     # an infinite variance over an infinite error
            return np.nan_to_num(self.cov / np.outer(d, d), nan=0.0, posinf=0.0, neginf=0.0)

    def disagreement(self) -> np.ndarray:
        """Return per slot |multisine alone - chirp alone| / combined standard error (0: none)."""
        if len(self.alone) < 2:
            return np.zeros(len(self.slots))
        (a, sa), (b, sb) = self.alone.values()
        comb = np.hypot(sa, sb)
        ok = np.isfinite(comb) & (comb > 0) & np.isfinite(a) & np.isfinite(b)
        return np.where(ok, np.abs(a - b) / np.where(ok, comb, 1.0), 0.0)


def slots_of(ev: Evaluator, kept: list[Effect], axis: int) -> list[Slot]:
    """
    Return the parameters of the axis' kept effects the Jacobian moves.

    Every scalar parameter other than 0 (a scale: step SE_STEP of its value) and, of a ripple
    or gravity term the diagnosis added (the last), the amplitude (a scale), the phase (SE_STEP
    radians) and a ripple's spatial frequency (the step that drifts its phase by SE_STEP
    radians over the largest motor angle of the fit part).
    """
    q = float(np.max(np.abs(ev.rec.position[ev.fit_mask, axis]))) if ev.fit_mask.any() else 1.0
    out = []
    for c in kept:
        if c.axis_index != axis:
            continue
        for key, v in c.parameters.items():
            if isinstance(v, (list, tuple)) and v:
                for fld, phase in _TERM_FIELDS:
                    if fld in v[-1]:
                        x = float(v[-1][fld])
                        step = (SE_STEP / max(q, 1e-9) if fld == 'spatial_frequency'
                                else SE_STEP if phase else SE_STEP * abs(x))
                        if step > 0:
                            out.append(Slot(c, key, fld, x, step))
            elif isinstance(v, (int, float)) and not isinstance(v, bool) and v != 0:
                out.append(Slot(c, key, None, float(v), SE_STEP * abs(float(v))))
    return out


def effects_with(slots: list[Slot], x: np.ndarray) -> dict[int, dict[str, Any]]:
    """Return per effect (by id) its parameters with the slots set to ``x``."""
    out: dict[int, dict[str, Any]] = {}
    for s, v in zip(slots, x):
        p = out.setdefault(id(s.effect), dict(s.effect.parameters))
        if s.field is None:
            p[s.key] = float(v)
        else:
            if p[s.key] is s.effect.parameters[s.key]:     # the terms are copied, never edited
                p[s.key] = [dict(t) for t in p[s.key]]
            p[s.key][-1][s.field] = float(v)
    return out


def model_with(base: RobotParams, kept: list[Effect], slots: list[Slot], x: np.ndarray
               ) -> RobotParams:
    """Return the model of ``kept`` with the slots set to ``x``."""
    p = effects_with(slots, x)
    return rebuild(base, [replace(c, parameters=p[id(c)]) if id(c) in p else c for c in kept])


def residuals_of(ev: Evaluator, axis: int, models: list[RobotParams]) -> list[np.ndarray]:
    """Return :func:`.residuals.axis_residual` of each model, simulated a batch at a time."""
    out = []
    batch = SIM_CACHE - 4
    for k in range(0, len(models), batch):
        chunk = models[k:k + batch]
        ev.prefetch(chunk)
        out += [axis_residual(ev, m, axis) for m in chunk]
    return out


def axis_fit(ev: Evaluator, base: RobotParams, kept: list[Effect], axis: int) -> AxisFit | None:
    """
    Return the linearised simulation fit of the axis' kept effects (None: no parameter).

    Parameters
    ----------
    ev : Evaluator
        The recording's evaluator.
    base : RobotParams
        The nominal model.
    kept : list of Effect
        The kept effects (the model is the nominal one with all of them).
    axis : int
        The axis.

    Returns
    -------
    AxisFit or None
        Standard errors, covariance and the refits on each experiment alone.

    """
    slots = slots_of(ev, kept, axis)
    if not slots:
        return None
    x0 = np.array([s.value for s in slots])
    h = np.array([s.step for s in slots])
    model = rebuild(base, kept)
    models = [model_with(base, kept, slots, x0 + h[j] * np.eye(len(slots))[j])
              for j in range(len(slots))] + [replace(model, substeps=2 * int(model.substeps))]
    r0 = axis_residual(ev, model, axis)
    *moved, r_fine = residuals_of(ev, axis, models)
    # the Jacobian per step (columns of one scale), then back to model units
    J = np.column_stack([r - r0 for r in moved])
    lay = layout(ev, r0)
    cov_s, dx = sandwich(J, r0, lay.blocks)
    cov = cov_s * np.outer(h, h)
    fit = AxisFit(slots, _errors(cov), cov, jacobian=J, residual=r0, optimum=x0 + h * dx,
                  step_bias=h * step_bias(J, r0, r_fine))
    for exp in ('multisine', 'chirp'):
        rows = lay.experiment == exp
        if np.unique(lay.blocks[rows]).size >= 3:
            c, dx = sandwich(J[rows], r0[rows], lay.blocks[rows])
            fit.alone[exp] = (x0 + h * dx, _errors(c * np.outer(h, h)))
    # two experiments that disagree beyond their errors (the model misses something one of
    # them shows): their spread is part of the value's error; and a value the search left
    # short of the fit's optimum (a spatial frequency from the scan's grid, a simplex stopped
    # at its tolerance) is at least that far from it
    between = np.where(fit.disagreement() > REFITS_AGREE_Z, between_experiments(fit.alone), 0.0)
    se = np.hypot(np.maximum.reduce([fit.se, between, np.abs(fit.optimum - x0)]), fit.step_bias)
    with np.errstate(invalid='ignore'):         # 0 correlation times an infinite error
        fit.cov = fit.correlation() * np.outer(se, se)
    fit.cov[~np.isfinite(se), :] = fit.cov[:, ~np.isfinite(se)] = 0.0
    fit.cov[np.diag_indices_from(fit.cov)] = se ** 2
    fit.within, fit.se = fit.se, se
    return fit


def between_experiments(alone: dict[str, tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """
    Return the standard error of the values that the spread between experiments implies.

    The random-effects combination of the refits on each experiment alone (DerSimonian and
    Laird 1986): the heterogeneity tau^2 = max(0, (Q - (k - 1)) / (sum w - sum w^2 / sum w))
    with w = 1 / se^2 and Q the weighted sum of squared deviations, and the combined value's
    error 1 / sqrt(sum 1 / (se^2 + tau^2)). 0 where fewer than two experiments give a finite
    refit.
    """
    if len(alone) < 2:
        return np.zeros(next(iter(alone.values()))[0].size) if alone else np.zeros(0)
    x = np.array([a for a, _ in alone.values()])
    s = np.array([e for _, e in alone.values()])
    ok = np.all(np.isfinite(x) & np.isfinite(s) & (s > 0), axis=0)
    x, s = np.where(ok, x, 0.0), np.where(ok, s, 1.0)
    # errors so small that their weights overflow leave tau^2 undefined (nan): a value with
    # such an error is labelled not determined (:mod:`.settle`), as without this guard
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        w = 1.0 / s ** 2
        mean = (w * x).sum(0) / w.sum(0)
        q = (w * (x - mean) ** 2).sum(0)
        tau2 = np.maximum(0.0, (q - (x.shape[0] - 1)) / (w.sum(0) - (w ** 2).sum(0) / w.sum(0)))
        return np.where(ok, 1.0 / np.sqrt((1.0 / (s ** 2 + tau2)).sum(0)), 0.0)


def step_bias(J: np.ndarray, r: np.ndarray, r_fine: np.ndarray) -> np.ndarray:
    """
    Return the values' step bias (in steps): how far a finer simulator would move them.

    ``r`` is the residual of the model, ``r_fine`` that of the model simulated at twice its
    substeps. Where the finer simulation, refitted (linearised), fits the record at least as
    well, the record is nearer a continuous plant than our step: the bias is STEP_BIAS_FACTOR
    times the refit's change of the values. Where it fits worse, the record is as coarse as
    our simulator (a record our own plant simulated at the model's step): 0.

    >>> J = np.array([[1.0], [0.0]])
    >>> step_bias(J, np.array([0.0, 0.1]), np.array([-0.5, 0.1]))
    array([1.])
    >>> step_bias(J, np.array([0.0, 0.1]), np.array([-0.5, 0.3]))
    array([0.])
    """
    dx, dx_fine = gauss_newton_step(J, r), gauss_newton_step(J, r_fine)
    left, left_fine = (float(np.sum((x + J @ d) ** 2)) for x, d in ((r, dx), (r_fine, dx_fine)))
    if not left_fine <= left:
        return np.zeros(J.shape[1])
    return STEP_BIAS_FACTOR * np.abs(dx_fine - dx)


def gauss_newton_step(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    """
    Return the step dx that minimises |r + J dx|^2 (0 along the directions the rows leave free).

    >>> gauss_newton_step(np.array([[1.0, 0.0], [0.0, 0.0]]), np.array([2.0, 1.0]))
    array([-2.,  0.])
    """
    return -_bread(J)[0] @ (J.T @ r)


def _bread(J: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Return the pseudo-inverse of J'J, its eigenvectors and which of them are free.

    A direction is free where its eigenvalue is below 1e-10 of the largest.
    """
    lam, vec = np.linalg.eigh(J.T @ J)
    free = lam <= 1e-10 * max(float(lam.max()), 1e-300)
    inv = np.where(free, 0.0, 1.0 / np.where(free, 1.0, lam))
    return (vec * inv) @ vec.T, vec, free


def sandwich(J: np.ndarray, r: np.ndarray, blocks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the CR2 covariance of the Gauss-Newton fit of ``r`` by ``J`` and its step.

    The step dx minimises |r + J dx|^2 (the linearised refit from where the search stopped);
    directions the rows leave free (eigenvalues of J'J below 1e-10 of the largest) get an
    infinite variance instead of the zero a pseudo-inverse would give them.
    """
    bread, vec, free = _bread(J)
    dx = -bread @ (J.T @ r)
    cov = cluster_covariance(J, r + J @ dx, blocks, bread)
    loose = (vec[:, free] ** 2).sum(axis=1) > 1e-6
    cov[loose, :] = cov[:, loose] = 0.0
    cov[loose, loose] = math.inf
    return cov, dx


def _errors(cov: np.ndarray) -> np.ndarray:
    """Return the standard errors on the diagonal of a covariance."""
    return np.sqrt(np.maximum(np.diag(cov), 0.0))
