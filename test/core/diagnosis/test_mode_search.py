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
The simulation search of a second mode (frf_ident/core/diagnosis/experiments/mode_search.py).

Its start (the axis' first resonance) and its coordinates (inertia over frequency squared)
against the analytic FRF of the flexible joint (frf_ident/core/simulation/analytic.py). The
search itself is held end to end by test/app/test_diagnose_modes.py (scenes 6588470, 6588469
and 4173340).
"""
import math

from frf_ident.core.diagnosis.experiments.mode_search import (first_resonance_hz, mode_of,
                                                              PROFILE_Z)
from frf_ident.core.diagnosis.experiments.noise_gain import paired
from frf_ident.core.model.params import AxisParams, RobotParams
from frf_ident.core.simulation.analytic import robot_frf
import numpy as np
import pytest
from scipy import stats

AXIS = {'motor_inertia': 35.0, 'link_inertia': 150.0, 'stiffness': 1.5e5, 'damping': 5.0,
        'viscous_friction': 0.0}


def _axis_robot(**mode):
    return RobotParams([AxisParams(**AXIS, second_mode=mode or None)])


def test_search_starts_at_the_axis_first_resonance():
    f = np.linspace(2.0, 30.0, 28001)
    mag = np.abs(robot_frf(_axis_robot(), f)[0, 0])
    peak = f[np.argmax(mag)]
    assert first_resonance_hz(_axis_robot(), 0) == pytest.approx(peak, rel=1e-3)


def test_inertia_over_frequency_squared_sets_the_change_below_the_mode():
    """Two modes of one inertia / frequency^2 change the FRF alike far below them."""
    f = np.linspace(3.0, 8.0, 51)             # around joint_1's antiresonance (5.1 Hz)
    base = robot_frf(_axis_robot(), f)[0, 0]

    def change(hz, inertia):
        m = _axis_robot(frequency_hz=hz, damping_ratio=0.02, inertia=inertia)
        return np.abs(robot_frf(m, f)[0, 0] / base - 1)
    same = change(35.0, 27.0), change(48.0, 27.0 * (48.0 / 35.0) ** 2)
    other = change(48.0, 27.0)
    assert np.max(np.abs(same[1] - same[0])) < 0.1 * np.max(same[0])
    assert np.max(np.abs(other - same[0])) > 0.3 * np.max(same[0])


def test_mode_of_reads_its_coordinates_and_caps_the_inertia():
    x = np.log([35.6, 0.0057, 27.4 / 35.6 ** 2])
    m = mode_of(x, 100.0)
    assert m == pytest.approx({'frequency_hz': 35.6, 'damping_ratio': 0.0057, 'inertia': 27.4})
    assert mode_of(x, 20.0)['inertia'] == 20.0
    assert math.isfinite(m['inertia'])


@pytest.mark.parametrize('size', [0.05, 0.2])
def test_profile_z_is_the_likelihood_ratio_of_the_paired_test(size):
    """
    The determination threshold: a likelihood ratio of 4 z^2 of the paired test's z.

    Monte Carlo, written here: N pieces of Gaussian noise of variance v, a model at the truth
    and one off by d per piece (drawn, of mean square ``size`` v). The likelihood ratio of
    the two (the sum of their squared-error difference over v) and 4 z^2 of the paired z
    (mean over its standard error, noise_gain.paired) agree within 10 % in the median, so a
    z of PROFILE_Z is a ratio at the chi-square(1) quantile of MODE_PROFILE_ALPHA.
    """
    rng = np.random.default_rng(7)
    n, v = 400, 2.5
    ratio, z2 = [], []
    for _ in range(400):
        noise = rng.normal(scale=math.sqrt(v), size=n)
        d = rng.normal(scale=math.sqrt(size * v), size=n)
        diff = (d + noise) ** 2 - noise ** 2
        mean, se = paired(diff, lags=0)
        ratio.append(diff.sum() / v)
        z2.append(4 * (mean / se) ** 2)
    assert np.median(z2) == pytest.approx(np.median(ratio), rel=0.1)
    assert 4 * PROFILE_Z ** 2 == pytest.approx(stats.chi2.isf(1e-3, 1))
