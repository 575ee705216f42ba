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
The input delay fitted with the two-mass parameters, against analytic truth and Monte-Carlo.

Truth is :func:`frf_ident.core.simulation.analytic.two_mass_frf` times exp(-s tau) with
tau = 1.5 sample periods at 1 kHz (a zero-order hold's half sample plus one sample of
computation), and the exact sampled FRF of a zero-order-hold loop, whose delay the continuous
model sees as half a sample.
"""
from __future__ import annotations

from frf_ident.core.fit.physical import delay_from_phase, fit_two_mass, PARAMETERS
from frf_ident.core.model.params import AxisParams, RobotParams
from frf_ident.core.model.schema import DEFAULT_MODEL
from frf_ident.core.simulation.analytic import robot_frf_sampled, two_mass_frf
import numpy as np
import pytest

SECTION6 = {'motor_inertia': 35.0, 'link_inertia': 150.0, 'stiffness': 1.5e5,
            'damping': 400.0, 'viscous_friction': 0.0}
CASES = {'section6': SECTION6,
         **{a['name']: {k: a[k] for k in PARAMETERS} for a in DEFAULT_MODEL['axes']}}
FREQ = np.geomspace(0.5, 60.0, 60)
TAU = 1.5e-3          # 1.5 sample periods at 1 kHz


def delayed(p: dict) -> np.ndarray:
    return (two_mass_frf(FREQ, *[p[k] for k in PARAMETERS])
            * np.exp(-2j * np.pi * FREQ * TAU))


@pytest.mark.parametrize('case', list(CASES))
def test_noise_free_delay_within_one_percent(case):
    true = np.array([CASES[case][k] for k in PARAMETERS])
    fit = fit_two_mass(FREQ, delayed(CASES[case]), delay_s=None)
    assert abs(fit.delay_s / TAU - 1) < 0.01, fit.delay_s
    assert fit.delay_fitted
    big = true != 0
    assert np.all(np.abs(fit.value[big] / true[big] - 1) < 0.005), fit.value
    # the phase-slope start alone is only the right size (the resonance's phase tail biases
    # it upward by up to 80 % on these axes): the refinement and the LM do the rest
    assert TAU <= delay_from_phase(FREQ, delayed(CASES[case])) < 2 * TAU


def test_delay_at_40_db_within_two_standard_errors_and_the_bound_is_the_spread():
    """100 noisy FRFs at 40 dB: Cramer-Rao SE of the delay vs its Monte-Carlo spread."""
    p0 = delayed(SECTION6)
    sigma = np.abs(p0) * 1e-2
    rng = np.random.default_rng(15)
    est, se = np.empty(100), np.empty(100)
    for r in range(est.size):
        noise = sigma / np.sqrt(2) * (rng.standard_normal(FREQ.size)
                                      + 1j * rng.standard_normal(FREQ.size))
        fit = fit_two_mass(FREQ, p0 + noise, sigma ** 2, delay_s=None)
        est[r], se[r] = fit.delay_s, fit.delay_std_s
        if r == 0:
            assert abs(fit.delay_s - TAU) <= 2 * fit.delay_std_s, fit.summary()
            assert not fit.cost.structure_missing
            assert fit.cost.dof == 2 * FREQ.size - 6          # the delay is a parameter
    assert np.mean(np.abs(est - TAU) <= 2 * se) >= 0.90
    assert abs(se.mean() / est.std(ddof=1) - 1) < 0.25, (se.mean(), est.std(ddof=1))


def test_a_given_delay_is_kept_and_a_wrong_one_fails_the_cost_test():
    p0 = delayed(SECTION6)
    sigma = np.abs(p0) * 1e-2
    right = fit_two_mass(FREQ, p0, sigma ** 2, delay_s=TAU)
    assert right.delay_s == TAU and not right.delay_fitted
    assert not right.cost.structure_missing
    wrong = fit_two_mass(FREQ, p0, sigma ** 2, delay_s=0.0)
    assert wrong.cost.structure_missing, wrong.cost.summary()


def test_the_zero_order_holds_half_sample_is_found_in_a_sampled_frf():
    """The exact FRF of the joint under a 1 kHz zero-order hold: 0.5 ms within 1 %."""
    axis = dict(SECTION6, viscous_friction=20.0)
    f = np.arange(0.5, 40.01, 0.5)
    p = robot_frf_sampled(RobotParams([AxisParams(**axis)]), f)[0, 0]
    fit = fit_two_mass(f, p, (0.01 * np.abs(p)) ** 2, delay_s=None)
    assert abs(fit.delay_s / 0.5e-3 - 1) < 0.01, fit.delay_s
    true = np.array([axis[k] for k in PARAMETERS])
    assert np.all(np.abs(fit.value - true) <= 2 * fit.std), (fit.value, fit.std)


def test_coupled_robot_fits_one_delay_for_all_axes():
    """The default 3-axis robot's 3x3 FRF delayed by 1.5 samples: noise-free, then 1 % noise."""
    from frf_ident.core.fit.coupled import fit_coupled
    from frf_ident.core.model.schema import default_robot
    from frf_ident.core.simulation.analytic import robot_frf
    robot = default_robot()
    f = np.geomspace(0.5, 60.0, 60)
    p = robot_frf(robot, f) * np.exp(-2j * np.pi * f * TAU)
    assert abs(fit_coupled(f, p, delay_s=None).delay_s / TAU - 1) < 0.01
    rng = np.random.default_rng(4)
    sigma = 0.01 * np.abs(p)
    pn = p + sigma / np.sqrt(2) * (rng.standard_normal(p.shape)
                                   + 1j * rng.standard_normal(p.shape))
    fit = fit_coupled(f, pn, sigma ** 2, delay_s=None)
    assert abs(fit.delay_s - TAU) <= 2 * fit.delay_std_s, (fit.delay_s, fit.delay_std_s)
    assert not fit.cost.structure_missing
