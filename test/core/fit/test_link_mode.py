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
The second-mode fit against analytic truth: the three-mass chain written out by hand.

The "measured" ratio is the FRF of the 3-axis model with a mode behind one link, divided by the
nominal's, computed here from the nodal stiffness matrix of the chain (not with the analytic
module the fit uses), with complex noise of the relative size the diagnosis' multisine
estimates carry (1e-3). Monte Carlo over noise draws: the truth within 3 standard errors, the
linear fit's residual not white where the mode is and white where there is none.
"""
from dataclasses import replace

from frf_ident.core.fit.link_mode import fit_linear_ratio, fit_second_mode, RatioData
from frf_ident.core.fit.residual_whiteness import residual_test
from frf_ident.core.model.schema import default_robot
import numpy as np
import pytest

F = np.geomspace(2.0, 60.0, 53)
SIGMA = 1e-3


def _robot_by_hand(robot, axis=None, mode=None) -> np.ndarray:
    """Return the diagonal of tau_m -> dq_m of the coupled robot, a mode on ``axis``, by hand."""
    n = robot.n_axes
    mo = robot.link_inertia_matrix()
    extra = 1 if mode is not None else 0
    out = np.empty((n, F.size), complex)
    for j, f in enumerate(F):
        s = 2j * np.pi * f
        kk = np.zeros((2 * n + extra, 2 * n + extra), complex)     # motors, links, mode
        for i, a in enumerate(robot.axes):
            z = a.stiffness + a.damping * s
            kk[i, i] = a.motor_inertia * s ** 2 + a.viscous_friction * s + z
            kk[i, n + i] = kk[n + i, i] = -z
            kk[n + i, n + i] = z
        kk[n:2 * n, n:2 * n] += mo * s ** 2
        if mode is not None:
            fe, ze, je = mode
            w = 2 * np.pi * fe
            zm = je * w * w + 2 * ze * je * w * s
            m = 2 * n
            kk[n + axis, n + axis] += zm - je * s ** 2            # its inertia leaves the link
            kk[n + axis, m] = kk[m, n + axis] = -zm
            kk[m, m] = je * s ** 2 + zm
        out[:, j] = s * np.diag(np.linalg.inv(kk))[:n]
    return out


@pytest.mark.parametrize('axis, mode', [(2, (22.0, 0.005, 10.8)), (1, (30.0, 0.05, 45.0)),
                                        (0, (25.0, 0.02, 20.0))])
def test_a_mode_is_fitted_within_its_standard_errors(axis, mode):
    robot = default_robot()
    nominal = _robot_by_hand(robot)
    truth = _robot_by_hand(robot, axis, mode) / nominal
    rng = np.random.default_rng(axis)
    z_all = []
    for _ in range(8):
        noise = SIGMA * (rng.standard_normal(truth.shape) + 1j * rng.standard_normal(truth.shape))
        data = RatioData(F, truth * (1 + noise / np.sqrt(2)), SIGMA * np.abs(truth))
        lin = fit_linear_ratio(robot, data)
        test = residual_test(F, lin.residual[axis])
        assert test.bands, test.summary()                     # no linear change explains it
        band = test.bands[0]
        fit = fit_second_mode(robot, data, axis, band.centre_hz, lin)
        assert fit is not None and fit.axis == axis
        got = (fit.frequency_hz, fit.damping_ratio, fit.inertia)
        se = (fit.frequency_std, fit.damping_std, fit.inertia_std)
        z_all.append([(g - t) / s for g, t, s in zip(got, mode, se)])
        assert residual_test(F, fit.residual[axis]).white or fit.cost < 1.3 * fit.dof
    z = np.array(z_all)
    print(f'mode on axis {axis} {mode}: z of frequency, damping ratio, inertia: '
          f'{np.round(z, 2).tolist()}')
    assert np.all(np.abs(z) < 4)
    assert np.mean(np.abs(z) < 2) >= 0.8


def test_without_a_mode_the_linear_fit_leaves_white_residuals():
    """A stiffness 10 % off is a parameter: the linear fit takes it, the residual is white."""
    robot = default_robot()
    nominal = _robot_by_hand(robot)
    axes = list(robot.axes)
    axes[1] = replace(axes[1], stiffness=1.1 * axes[1].stiffness)
    truth = _robot_by_hand(replace(robot, axes=axes)) / nominal
    rng = np.random.default_rng(5)
    white = 0
    for _ in range(20):
        noise = SIGMA * (rng.standard_normal(truth.shape) + 1j * rng.standard_normal(truth.shape))
        lin = fit_linear_ratio(robot, RatioData(F, truth * (1 + noise / np.sqrt(2)),
                                                SIGMA * np.abs(truth)))
        assert np.exp(lin.log_scale[1, 2]) == pytest.approx(1.1, rel=3e-3)
        white += all(residual_test(F, e).white for e in lin.residual)
    assert white >= 18


@pytest.mark.parametrize('axis, mode', [(1, (35.3, 0.037, 48.3)), (0, (25.0, 0.02, 20.0)),
                                        (2, (18.2, 0.0086, 6.06))])
def test_stage_0_offers_the_mode_on_its_axis_and_nothing_without_one(axis, mode):
    """
    The diagnosis' stage-0 candidates (experiments/second_mode.py) on the analytic chain.

    The modes of sweep scenes 6587472 and 6587468 of benchmarks/second_mode.py and one of
    joint_1: the first candidate offered is on the mode's axis, its frequency within 5 % and
    its damping ratio within 30 %; with a stiffness 10 % off and no mode, none is offered.
    (The 37.4 Hz mode of damping ratio 0.07 and 20.5 kg m^2 on joint_1 of scene 6588469 leaves
    this chain's residual white at this noise: it is not seen in stage 0.)
    """
    from frf_ident.core.diagnosis.experiments.second_mode import second_mode_candidates
    from frf_ident.core.diagnosis.experiments.structure import StructureReading
    robot = default_robot()
    nominal = _robot_by_hand(robot)
    axes = list(robot.axes)
    axes[1] = replace(axes[1], stiffness=1.1 * axes[1].stiffness)
    rng = np.random.default_rng(axis)
    for truth, want in ((_robot_by_hand(robot, axis, mode) / nominal, mode),
                        (_robot_by_hand(replace(robot, axes=axes)) / nominal, None)):
        noise = SIGMA * (rng.standard_normal(truth.shape) + 1j * rng.standard_normal(truth.shape))
        data = RatioData(F, truth * (1 + noise / np.sqrt(2)), SIGMA * np.abs(truth))
        lin = fit_linear_ratio(robot, data)
        reading = StructureReading(data, lin, [residual_test(F, e) for e in lin.residual])
        trace = []
        found = list(second_mode_candidates(reading, robot, trace.append))
        print('\n'.join(trace))
        if want is None:
            assert found == []
            continue
        assert [c.axis_index for c in found][:1] == [axis]
        got = found[0].parameters['second_mode']
        assert got['frequency_hz'] == pytest.approx(want[0], rel=0.05)
        assert got['damping_ratio'] == pytest.approx(want[1], rel=0.3)


def test_stage_0_leaves_a_rigid_joints_resonance_to_the_spring_reading():
    """
    A joint the model holds rigid lacks its spring, not a second mode (experiments/second_mode.py).

    The nominal holds joint_2 rigid (its antiresonance 20 Nyquist frequencies up, as the view of
    an MJCF joint without the series-elastic hinge pair has it); the truth puts 30 % of its link
    inertia behind a 15 Hz spring: a two-mass joint whose motor side holds the rest, the same
    physics as a second mode behind a rigid joint. Stage 0's residual shows the band; its
    candidates offered the second mode there before (the demo's MuJoCo iiwa 14 had both joint
    springs read as second modes), now none on the rigid axis: it is the joint spring the
    model lacks, which stage 0b reads (experiments/rigid_axes.py).
    """
    from frf_ident.core.diagnosis.experiments.second_mode import second_mode_candidates
    from frf_ident.core.diagnosis.experiments.structure import StructureReading
    robot = default_robot()
    axes = list(robot.axes)
    a = axes[1]
    w = 2 * np.pi * 20 * robot.sample_rate / 2
    axes[1] = replace(a, stiffness=a.link_inertia * w * w)
    robot = replace(robot, axes=axes)
    nominal = _robot_by_hand(robot)
    truth = _robot_by_hand(robot, 1, (15.0, 0.03, 0.3 * a.link_inertia)) / nominal
    rng = np.random.default_rng(7)
    noise = SIGMA * (rng.standard_normal(truth.shape) + 1j * rng.standard_normal(truth.shape))
    data = RatioData(F, truth * (1 + noise / np.sqrt(2)), SIGMA * np.abs(truth))
    lin = fit_linear_ratio(robot, data)
    reading = StructureReading(data, lin, [residual_test(F, e) for e in lin.residual])
    assert reading.bands(1), 'the missing spring leaves no band: the test would show nothing'
    trace = []
    found = list(second_mode_candidates(reading, robot, trace.append))
    print('\n'.join(trace))
    assert 1 not in [c.axis_index for c in found]
    assert any('joint_2: rigid in the model' in t for t in trace)
