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
Nelder-Mead that evaluates its next trial point beside the reflection.

The diagnosis refines a few parameters at a time by Nelder-Mead on simulated misfits; each
step waits for one simulation, so a second core stays idle. Every point a step may evaluate
is known before the step starts: the reflection x_r, the expansion x_e, the outside and the
inside contraction x_c, x_cc (all on the line through the centroid and the worst vertex).
:func:`nelder_mead` hands the reflection and the one of the others the previous step needed
(the inside contraction after a plain reflection) to ``prefetch`` (the evaluator simulates
them on two processes), then takes the step exactly
as ``scipy.optimize.minimize(method='Nelder-Mead')`` does with the standard coefficients
(reflection 1, expansion 2, contraction 1/2, shrink 1/2), the same termination rules and the
same count of function evaluations: the same points in the same order, hence the same result
(test/core/diagnosis/test_simplex.py), in fewer rounds of simulation wherever the guess was
right. A prefetched point the step did not use costs a core that was idle, not wall time, and
is not counted as an evaluation.
"""
from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

__all__ = ['nelder_mead']

#: step kinds: which point besides the reflection a step evaluated (guess for the next step)
_REFLECT, _EXPAND, _OUTSIDE, _INSIDE = range(4)


class _Budget(Exception):
    """The evaluation budget is spent (scipy's _MaxFuncCallError)."""


def nelder_mead(fn: Callable[[np.ndarray], float], simplex: np.ndarray, *,
                bounds: Sequence[tuple[float, float]] | None = None, xatol: float = 1e-4,
                fatol: float = 1e-4, maxfev: int | None = None,
                prefetch: Callable[[list[np.ndarray]], None] | None = None) -> np.ndarray:
    """
    Minimise ``fn`` from an initial simplex; return the best vertex.

    Parameters
    ----------
    fn : callable
        The objective of a point (ndarray of n).
    simplex : ndarray, shape (n + 1, n)
        The initial simplex (scipy's ``initial_simplex``).
    bounds : sequence of (low, high), optional
        Box bounds; the simplex is reflected into them and every trial point clipped.
    xatol, fatol : float
        Stop when all vertices lie within ``xatol`` of the best in every coordinate and their
        values within ``fatol`` of its value.
    maxfev : int, optional
        Evaluations of ``fn`` at most (default 200 n).
    prefetch : callable, optional
        Called with the points a step evaluates next (the reflection and the guess), so that
        ``fn`` finds them computed; it must not change what ``fn`` returns.

    Returns
    -------
    ndarray, shape (n,)
        The best vertex.

    """
    sim = np.asarray(simplex, dtype=float).copy()
    n = sim.shape[1]
    maxfev = 200 * n if maxfev is None else maxfev
    lo = hi = None
    if bounds is not None:
        lo, hi = (np.array([b[k] for b in bounds], dtype=float) for k in (0, 1))
        sim = np.clip(np.where(sim > hi, 2 * hi - sim, sim), lo, hi)
    calls = [0]

    def f(x: np.ndarray) -> float:
        if calls[0] >= maxfev:
            raise _Budget
        calls[0] += 1
        return float(fn(np.copy(x)))

    def clip(x: np.ndarray) -> np.ndarray:
        return x if lo is None else np.clip(x, lo, hi)

    fsim = np.full(n + 1, np.inf)
    try:
        for k in range(n + 1):
            fsim[k] = f(sim[k])
    except _Budget:
        pass
    for _ in range(2):                       # as scipy: sorted after the loop and again
        ind = np.argsort(fsim)
        sim, fsim = np.take(sim, ind, 0), np.take(fsim, ind, 0)
    last = _INSIDE
    while calls[0] < maxfev:
        try:
            if (np.max(np.ravel(np.abs(sim[1:] - sim[0]))) <= xatol
                    and np.max(np.abs(fsim[0] - fsim[1:])) <= fatol):
                break
            xbar = np.add.reduce(sim[:-1], 0) / n
            xr = clip(2 * xbar - sim[-1])
            trial = {_EXPAND: lambda: clip(3 * xbar - 2 * sim[-1]),
                     _OUTSIDE: lambda: clip(1.5 * xbar - 0.5 * sim[-1]),
                     _INSIDE: lambda: clip(0.5 * xbar + 0.5 * sim[-1])}
            if prefetch is not None:
                # after a reflection the guess is the inside contraction, the commonest step
                prefetch([xr, trial[_INSIDE if last == _REFLECT else last]()])
            last = _step(f, sim, fsim, xr, trial, clip)
        except _Budget:
            pass
        ind = np.argsort(fsim)
        sim, fsim = np.take(sim, ind, 0), np.take(fsim, ind, 0)
    return sim[0]


def _step(f, sim: np.ndarray, fsim: np.ndarray, xr: np.ndarray, trial: dict,
          clip: Callable) -> int:
    """Take one Nelder-Mead step in place (scipy's order); return which trial it needed."""
    fxr = f(xr)
    if fxr < fsim[0]:
        xe = trial[_EXPAND]()
        fxe = f(xe)
        sim[-1], fsim[-1] = (xe, fxe) if fxe < fxr else (xr, fxr)
        return _EXPAND
    if fxr < fsim[-2]:
        sim[-1], fsim[-1] = xr, fxr
        return _REFLECT
    kind = _OUTSIDE if fxr < fsim[-1] else _INSIDE
    xc = trial[kind]()
    fxc = f(xc)
    if (fxc <= fxr) if kind == _OUTSIDE else (fxc < fsim[-1]):
        sim[-1], fsim[-1] = xc, fxc
        return kind
    for j in range(1, sim.shape[0]):         # shrink towards the best vertex
        sim[j] = clip(sim[0] + 0.5 * (sim[j] - sim[0]))
        fsim[j] = f(sim[j])
    return kind
