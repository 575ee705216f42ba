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
The controller check on a measured (simulated, noisy) FRF against python-control's margins.

Truth: the Section 6 joint with viscous friction and a 3 ms delay as a python-control
transfer function (6th-order Pade delay), its margins by python-control's polynomial method;
the "measurement" is the exact FRF of the same plant on 200 lines with 3 % noise (30 dB).
"""
from __future__ import annotations

import control
from frf_ident.app.loop import loop_check, propose_gains
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.model.schema import default_robot
from frf_ident.core.simulation.analytic import robot_frf, two_mass_frf
import numpy as np

JM, JO, K, D, BV = 35.0, 150.0, 1.5e5, 400.0, 20.0
DELAY = 3e-3
FREQ = np.geomspace(0.2, 100.0, 200)
REL_SD = 0.03


def measured(p, seed):
    var = (REL_SD * np.abs(p)) ** 2
    rng = np.random.default_rng(seed)
    pn = p + np.sqrt(var / 2) * (rng.standard_normal(p.shape) + 1j * rng.standard_normal(p.shape))
    return pn, var


def plant_frf(f):
    return two_mass_frf(f, JM, JO, K, D, BV) * np.exp(-2j * np.pi * f * DELAY)


def test_margins_of_the_measured_loop_match_the_true_model_within_uncertainty():
    kp, ki = 6000.0, 60000.0
    p_tf = control.tf([JO, D, K], [JM * JO, JM * D + JO * D + BV * JO,
                                   JM * K + JO * K + BV * D, BV * K])
    loop = p_tf * control.tf(*control.pade(DELAY, 6)) * control.tf([kp, ki], [1, 0])
    gm, pm, sm, _, wgc, _ = control.stability_margins(loop)
    true = [20 * np.log10(gm), pm, wgc / (2 * np.pi), sm]
    pn, var = measured(plant_frf(FREQ), 11)
    frf = FrequencyResponse(FREQ, pn, ['joint_1'], ['joint_1'],
                            total_variance=var.reshape(1, 1, -1))
    check = loop_check(frf, [kp], [ki])
    print(check.summary(), 'true', np.round(true, 3))
    ax = check.axes[0]
    got = [ax.gain_margin_db, ax.phase_margin_deg, ax.crossover_hz, ax.modulus_margin]
    for g, t in zip(got, true):
        assert 0 < g.std and abs(g.value - t) <= 3 * g.std, (g, t)
    # the uncertainty is that of a 3 % FRF: not a wide net (PM within a few degrees)
    assert ax.phase_margin_deg.std < 5 and ax.gain_margin_db.std < 1


def test_pi_proposal_checked_on_the_measured_frf():
    """PI for 60 deg at 2 Hz read off the noisy FRF; the measured loop has what was asked."""
    f = FREQ[FREQ < 60]
    pn, var = measured(plant_frf(f), 12)
    frf = FrequencyResponse(f, pn, ['joint_1'], ['joint_1'], total_variance=var.reshape(1, 1, -1))
    (prop,) = propose_gains(frf, 2.0, 60.0)
    assert prop.feasible
    ax = loop_check(frf, [prop.kp], [prop.ki]).axes[0]
    print(prop, ax.summary())
    assert abs(ax.crossover_hz.value - 2.0) <= 3 * ax.crossover_hz.std + 0.02
    assert abs(ax.phase_margin_deg.value - 60.0) <= 3 * ax.phase_margin_deg.std + 1.0


def test_mimo_sensitivity_peak_of_the_coupled_robot():
    """The default robot with its PI: peak sigma_max(S) from the MIMO FRF vs python-control."""
    robot = default_robot()
    kp, ki = np.array([1500.0, 2000.0, 800.0]), np.array([6000.0, 8000.0, 3200.0])
    f = np.geomspace(0.2, 60.0, 150)
    p = robot_frf(robot, f)
    check = loop_check(FrequencyResponse(f, p, robot.joint_names, robot.joint_names), kp, ki,
                       draws=0)
    frd = control.frd(p, 2 * np.pi * f)
    c = control.tf([[[kp[i], ki[i]] if i == j else [0] for j in range(3)] for i in range(3)],
                   [[[1, 0] if i == j else [1] for j in range(3)] for i in range(3)])
    eye = control.frd(np.repeat(np.eye(3)[:, :, None], f.size, axis=2), 2 * np.pi * f)
    s = control.feedback(eye, frd * c).frequency_response(2 * np.pi * f).complex
    peak = np.linalg.svd(np.moveaxis(s, -1, 0), compute_uv=False)[:, 0].max()
    assert abs(check.peak_sensitivity.value / peak - 1) < 1e-6


def test_axis_channels_match_estimate_names_by_joint():
    """Match `estimate`'s names: inputs tau_m/<joint>, outputs dq_m/<joint> (any order)."""
    from frf_ident.app.frf_source import axis_channels
    frf = FrequencyResponse(FREQ[:5], np.ones((2, 2, 5)), ['tau_m/a', 'tau_m/b'],
                            ['dq_m/b', 'dq_m/a'])
    assert axis_channels(frf) == [('a', 1, 0), ('b', 0, 1)]


def test_margin_standard_deviations_match_repeated_measurements():
    """
    Compare the reported standard deviations with the spread over 16 measurements.

    16 independent 3 % measurements of the same loop: the spread of their phase, gain and
    modulus margins against the standard deviations each check reports (25 draws each). A
    16-sample spread is itself uncertain by about 18 %, hence 0.5-1.6. The modulus margin is
    a minimum over frequency: draws around an already noisy estimate carry the noise twice
    there, so its reported deviation runs high (1.36 with these seeds; up to 2 accepted).
    """
    kp, ki = 6000.0, 60000.0
    f = np.geomspace(0.2, 100.0, 120)
    nominal, reported = [], []
    for seed in range(16):
        pn, var = measured(plant_frf(f), 100 + seed)
        ax = loop_check(FrequencyResponse(f, pn, ['joint_1'], ['joint_1'],
                                          total_variance=var.reshape(1, 1, -1)),
                        [kp], [ki], draws=25, seed=seed).axes[0]
        got = (ax.phase_margin_deg, ax.gain_margin_db, ax.modulus_margin)
        nominal.append([g.value for g in got])
        reported.append([g.std for g in got])
    ratio = np.mean(reported, axis=0) / np.std(nominal, axis=0, ddof=1)
    print('reported SD / spread of 16 measurements (PM, GM, modulus):', np.round(ratio, 2))
    assert np.all((0.5 < ratio[:2]) & (ratio[:2] < 1.6)) and 0.5 < ratio[2] < 2.0, ratio
