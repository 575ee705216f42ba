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
"""The simulated plant against analytic truth (eqs. 20-22 in closed form)."""
from frf_ident.core.estimation.spectra import periodic_spectra
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.core.model.params import AxisParams, RobotParams
from frf_ident.core.model.schema import default_robot
from frf_ident.core.simulation.analytic import robot_frf, robot_frf_sampled, two_mass_frf
from frf_ident.core.simulation.open_loop import stage_grid
from frf_ident.core.simulation.plant import FlexibleJointPlant
import numpy as np
import pytest

FS = 1000.0


def _design():
    return design_odd_multisine(1.0, 60.0, bound=100.0, resolution_hz=0.5, fs=FS)


def _run_siso(plant, design, fine, transient_periods=1):
    n = design.period_samples(FS)
    nt = transient_periods + 1
    real = multisine_realisation(design, plant.n_axes, np.random.default_rng(3), fs=FS)
    if fine:
        sig = real.evaluate(stage_grid(nt * n, FS, plant.params.substeps))[0]
        res = plant.simulate(torque_fine=sig)
    else:
        res = plant.simulate(torque=real.evaluate(np.arange(nt * n) / FS)[0])
    U = periodic_spectra(res.effort[-n:], design.harmonics, axis=0)
    Y = periodic_spectra(res.velocity[-n:], design.harmonics, axis=0)
    return Y[:, 0] / U[:, 0]


def test_continuous_input_matches_two_mass_closed_form():
    d = _design()
    plant = FlexibleJointPlant(RobotParams([AxisParams()], sample_rate=FS, substeps=2))
    P = _run_siso(plant, d, fine=True)
    Pa = two_mass_frf(d.freq_hz, 35, 150, 1.5e5, 400)
    assert np.max(np.abs(P / Pa - 1)) < 1e-5


def test_zoh_input_matches_exact_sampled_frf_with_delay_and_viscous():
    d = _design()
    ax = AxisParams(viscous_friction=100.0, time_delay=0.0023)
    rob = RobotParams([ax], sample_rate=FS, substeps=1)
    # viscous friction: the rigid mode decays with (Jm + Jo)/bv = 1.85 s; wait it out
    P = _run_siso(FlexibleJointPlant(rob), d, fine=False, transient_periods=20)
    assert np.max(np.abs(P / robot_frf_sampled(rob, d.freq_hz)[0, 0] - 1)) < 1e-6
    # the continuous model differs by the hold and the delay: phase error linear in f
    Pc = two_mass_frf(d.freq_hz, 35, 150, 1.5e5, 400, 100.0)
    ph = np.unwrap(np.angle(P / Pc))
    slope = np.polyfit(d.freq_hz, ph, 1)[0]
    assert slope == pytest.approx(-2 * np.pi * (0.0023 + 0.5 / FS), rel=0.02)


def test_mimo_closed_form_is_reciprocal_and_matches_siso():
    rob = default_robot()
    f = np.geomspace(1, 60, 50)
    P = robot_frf(rob, f)
    assert np.allclose(P, np.swapaxes(P, 0, 1), rtol=1e-10, atol=0)
    single = RobotParams([rob.axes[0]])
    a = rob.axes[0]
    assert np.allclose(robot_frf(single, f)[0, 0],
                       two_mass_frf(f, a.motor_inertia, a.link_inertia, a.stiffness, a.damping,
                                    a.viscous_friction))


def _chain_frf(f, jm, jo, k, d, je, fe, ze):
    """dq_m / tau_m of the free chain motor - k, d - rigid link - k_e, d_e - mode, by hand."""
    s = 2j * np.pi * np.asarray(f)
    we = 2 * np.pi * fe
    ke, de = je * we ** 2, 2 * ze * je * we
    # nodal dynamic stiffness matrix of the three inertias, solved for the motor's response
    kk = np.zeros((s.size, 3, 3), complex)
    kk[:, 0, 0] = jm * s ** 2 + d * s + k
    kk[:, 0, 1] = kk[:, 1, 0] = -(d * s + k)
    kk[:, 1, 1] = (jo - je) * s ** 2 + d * s + k + de * s + ke
    kk[:, 1, 2] = kk[:, 2, 1] = -(de * s + ke)
    kk[:, 2, 2] = je * s ** 2 + de * s + ke
    return s * np.linalg.inv(kk)[:, 0, 0]


def test_second_mode_frf_is_the_three_mass_chain_and_the_plant_realises_it():
    """The model-file second mode is a share of the link on a spring (docs/model_file.md)."""
    mode = {'frequency_hz': 22.0, 'damping_ratio': 0.02, 'inertia': 30.0}
    ax = AxisParams(second_mode=mode)
    rob = RobotParams([ax], sample_rate=FS, substeps=1)
    d = _design()
    hand = _chain_frf(d.freq_hz, 35, 150, 1.5e5, 400, 30.0, 22.0, 0.02)
    assert np.max(np.abs(robot_frf(rob, d.freq_hz)[0, 0] / hand - 1)) < 1e-10
    # at low frequency the link weighs its whole inertia: the mode adds nothing there
    assert robot_frf(rob, [0.2])[0, 0, 0] == pytest.approx(
        two_mass_frf([0.2], 35, 150, 1.5e5, 400)[0], rel=1e-4)
    # the plant's linear run is the exact sampled FRF, which has the chain's resonances
    P = _run_siso(FlexibleJointPlant(rob), d, fine=False, transient_periods=6)
    assert np.max(np.abs(P / robot_frf_sampled(rob, d.freq_hz)[0, 0] - 1)) < 1e-6
    Pc = two_mass_frf(d.freq_hz, 35, 150, 1.5e5, 400)
    assert np.max(np.abs(np.log(np.abs(P / Pc)))) > 0.03     # the mode changes the FRF


def test_coulomb_friction_sticks_below_fc_and_slides_above():
    rob = RobotParams([AxisParams(coulomb_friction=50.0)], sample_rate=FS, substeps=2)
    plant = FlexibleJointPlant(rob)
    res = plant.simulate(torque=np.full((500, 1), 40.0))
    assert np.max(np.abs(res.velocity)) == 0.0
    plant.reset()
    res = plant.simulate(torque=np.full((2000, 1), 60.0))
    # rigid-body acceleration (60 - 50) / (Jm + Jo) after the transmission settles
    acc = np.polyfit(res.t[1000:], res.velocity[1000:, 0], 1)[0]
    assert acc == pytest.approx(10.0 / 185.0, rel=0.02)


def test_torque_limit_and_quantised_encoder_velocity():
    ax = AxisParams(torque_limit=20.0, encoder_resolution=1e-5)
    rob = RobotParams([ax], sample_rate=FS, velocity_from_encoder=True)
    plant = FlexibleJointPlant(rob)
    res = plant.simulate(torque=np.full((300, 1), 500.0))
    assert np.max(res.effort) == 20.0
    q = res.position[:, 0]
    assert np.allclose(q / 1e-5, np.round(q / 1e-5))
    assert np.allclose(res.velocity[1:, 0], np.diff(q) * FS)


def test_step_api_matches_batch_and_is_seeded():
    rob = default_robot()
    rob.axes[0].velocity_noise = 1e-3
    u = np.random.default_rng(0).normal(0, 20, (200, 3)) + [0, 120, 40]
    a = FlexibleJointPlant(rob)
    batch = a.simulate(torque=u)
    b = FlexibleJointPlant(rob)
    pos = np.array([b.step(row)[0] for row in u])
    assert np.allclose(pos[:-1], batch.position[1:], atol=1e-12)
    c = FlexibleJointPlant(rob)
    assert np.array_equal(c.simulate(torque=u).velocity, batch.velocity)  # same seed


def test_gravity_equilibrium_holds_at_rest():
    rob = default_robot()
    plant = FlexibleJointPlant(rob)
    res = plant.simulate(torque=np.tile(plant.equilibrium_torque(), (1000, 1)))
    assert np.max(np.abs(res.velocity)) < 1e-9


def test_rest_at_a_configuration_with_its_gravity_load():
    """reset(position=q) rests there: sin(q2 + phi) and sin(q2 + q3 + phi) loads held, no drift."""
    rob = default_robot()
    rob.axes[1].gravity = [{'amplitude': 300.0, 'phase': 0.2},
                           {'amplitude': 90.0, 'phase': -0.4, 'joints': ['joint_2', 'joint_3']}]
    rob.axes[2].gravity = [{'amplitude': 90.0, 'phase': -0.4, 'joints': ['joint_2', 'joint_3']}]
    q = np.array([0.3, 0.7, -1.1])
    plant = FlexibleJointPlant(rob)
    plant.reset(position=q)
    hold = plant.equilibrium_torque(q)
    expect = [0.0, 120 + 300 * np.sin(0.9) + 90 * np.sin(-0.8), 40 + 90 * np.sin(-0.8)]
    np.testing.assert_allclose(hold, expect, rtol=1e-12)
    np.testing.assert_allclose(plant.state[2], q, rtol=0, atol=0)          # links at q
    res = plant.simulate(torque=np.tile(hold, (2000, 1)))
    assert np.max(np.abs(res.velocity)) < 1e-9
    np.testing.assert_allclose(res.position[-1], plant.state[0], atol=1e-12)
    np.testing.assert_allclose(plant.state[2], q, atol=1e-12)


@pytest.mark.parametrize('name, order', [
    ('Coulomb friction 15 N m', 1.0), ('backlash 5e-5 rad', 1.0),
    ('stiffening k2 = 1.5 k1 beyond 2.5e-4 rad', 2.0), ('torque ripple 4 N m at 120 /rad', 2.0)])
def test_discretisation_error_falls_with_the_order_of_each_effect(name, order):
    # truth: the same closed-loop run at 32 substeps; the linear part is exact, a switching
    # nonlinearity (stick-slip, backlash contact) first order, a smooth one second order
    from benchmarks.discretisation import discretisation_error, EFFECTS, orders
    assert discretisation_error({}, 1, seconds=4.0, reference_substeps=32) < 1e-8
    err = [discretisation_error(EFFECTS[name], m, seconds=4.0, reference_substeps=32)
           for m in (1, 2, 4)]
    assert err[0] > 1e-7
    assert all(abs(o - order) < 0.35 for o in orders(err)), (err, orders(err))
