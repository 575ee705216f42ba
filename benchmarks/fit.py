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
Fit timing (section ``fit``): the parametric fits on a 3x3 FRF of 100 lines.

- rational: common-denominator ML fit of order 9 (the robot's 9 states) of the default 3-axis
  robot's FRF with 1 % noise, beside its own linear start alone (Sanathanan-Koerner); both
  with their largest relative error against the analytic FRF (goal: < 1 s for the ML fit).
- physical: the two-mass fit of the 3 axes' own FRFs, beside scipy's plain least_squares
  (finite-difference Jacobian) on the same ML cost from the nominal parameters 30 % off
  (what a user without the linear start would do): time and the worst parameter error.
- coupled: all axes plus the link coupling from the noisy 3x3 FRF: time, cost ratio (about 1
  when the residual is the noise) and the worst error in standard errors, beside the per-axis
  fits of the diagonal alone (their worst cost ratio: what ignoring the coupling leaves).
"""
from __future__ import annotations

import timeit

import numpy as np

__all__ = ['rows']


def _noisy(p, rng, rel=0.01):
    var = (rel * np.abs(p)) ** 2
    return p + np.sqrt(var / 2) * (rng.standard_normal(p.shape)
                                   + 1j * rng.standard_normal(p.shape)), var


def _best(fn, repeat=3):
    """Return (best wall time of ``repeat`` calls [s], the result of one more call)."""
    return min(timeit.repeat(fn, number=1, repeat=repeat)), fn()


def rows() -> list[tuple[str, str, str, str]]:
    from frf_ident.core.fit.cost import normalised_residual
    from frf_ident.core.fit.coupled import fit_coupled
    from frf_ident.core.fit.levy import sk_common_denominator
    from frf_ident.core.fit.physical import fit_two_mass, PARAMETERS, two_mass_response
    from frf_ident.core.fit.rational import fit_rational
    from frf_ident.core.model.schema import default_robot
    from frf_ident.core.simulation.analytic import robot_frf, two_mass_frf
    from scipy import optimize
    robot = default_robot()
    f = np.geomspace(0.5, 60.0, 100)
    rng = np.random.default_rng(0)
    truth = robot_frf(robot, f)
    p, var = _noisy(truth, rng)
    t_ml, fit = _best(lambda: fit_rational(f, p, var, 9, 8))
    s = 2j * np.pi * f / (2 * np.pi * f.max())
    t_sk, (b, a) = _best(lambda: sk_common_denominator(s, p.reshape(9, -1),
                                                       1 / np.sqrt(var).reshape(9, -1), 8, 9))
    sk = ((b @ (s[:, None] ** np.arange(9)).T) / (s[:, None] ** np.arange(10) @ a))
    err_ml = np.max(np.abs(fit.model - truth) / np.abs(truth))
    err_sk = np.max(np.abs(sk.reshape(truth.shape) - truth) / np.abs(truth))
    out = [('fit: rational ML 3x3, 100 lines, order 9',
            f'{t_ml:.2f} s, err {100 * err_ml:.2f} %', f'SK alone {t_sk:.2f} s, '
            f'err {100 * err_sk:.2f} %', f'{t_ml / t_sk:.1f}x time')]
    t_phys, t_plain, e_phys, e_plain = 0.0, 0.0, 0.0, 0.0
    for ax in robot.axes:
        true = np.array([getattr(ax, k) for k in PARAMETERS])
        pa, va = _noisy(two_mass_frf(f, *true), rng)
        t, res = _best(lambda: fit_two_mass(f, pa, va))
        t_phys += t
        e_phys = max(e_phys, np.max(np.abs(res.value[:4] / true[:4] - 1)))
        start = true * 1.3

        def resid(x):
            return normalised_residual(two_mass_response(x * start, f), pa, va)
        t, sol = _best(lambda: optimize.least_squares(resid, np.ones(5)))
        t_plain += t
        e_plain = max(e_plain, np.max(np.abs(sol.x[:4] * start[:4] / true[:4] - 1)))
    t_c, coupled = _best(lambda: fit_coupled(f, p, var), repeat=1)
    true = np.concatenate([[getattr(a, k) for a in robot.axes] for k in PARAMETERS]
                          + [robot.link_coupling[np.triu_indices(3, 1)]])
    z = np.max(np.abs(coupled.value - true) / coupled.std)
    t_d = min(timeit.repeat(lambda: [fit_two_mass(f, p[i, i], var[i, i]) for i in range(3)],
                            number=1, repeat=3))
    worst = max(a.cost.ratio for a in coupled.per_axis)
    out.append(('fit: coupled physical 3x3 (18 parameters)',
                f'{t_c:.2f} s, cost ratio {coupled.cost.ratio:.2f}, worst {z:.1f} SE',
                f'diagonal only {t_d:.2f} s, ratio {worst:.2f}', f'{t_c / t_d:.1f}x time'))
    out.append(('fit: physical two-mass, 3 axes x 100 lines',
                f'{t_phys:.3f} s, worst err {100 * e_phys:.2f} %',
                f'plain LS {t_plain:.3f} s, {100 * e_plain:.1f} %', f'{t_plain / t_phys:.1f}x'))
    return out
