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
Safety of the excitation session and the PI on a free-running robot (no ROS).

The session (frf_ident/app/excitation.py, what excitation_node runs) streams references to a
controller that holds the latest one, as controller_node does on a real robot; the robot is
the simulated model, stepped one sample per joint state.
"""
from __future__ import annotations

import json
from types import SimpleNamespace

from frf_ident.app.excitation import ExcitationSession
from frf_ident.app.excitation_settings import SessionSettings
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.errors import DesignError, SafetyError
from frf_ident.io.model_file import load_model
import numpy as np
import pytest

#: a short multisine (one realisation, two 1 s periods, no compensation run): about 35 s
SHORT = MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=1.0, compensate=False)


class _Out:
    def __init__(self) -> None:
        self.refs: list[tuple[int, np.ndarray]] = []
        self.events: list[str] = []
        self.logs: list[str] = []

    def reference(self, k, r, x) -> None:
        self.refs.append((k, np.array(r, float)))

    def experiment(self, text) -> None:
        self.events.append(text)

    def progress(self, event) -> None:
        pass

    def log(self, level, text) -> None:
        self.logs.append(text)


def _free_run(settings: SessionSettings, corrupt=None, after_s: float = 0.0,
              predict: bool = False, hide=None, model=None, moved=None, chirp: bool = False):
    """
    Run a multisine on the free-running simulated robot.

    The controller holds the latest reference it got (controller_node's rule) and keeps
    running ``after_s`` seconds after the procedure ended; ``corrupt(k, q)`` may alter the
    measured position the session sees; ``predict`` gives the session the model (its plans'
    torque predicted before they run); the session never sees joint state k when ``hide(k)``
    (its executor was busy); ``model`` (robot, controller) replaces the default one; with
    ``moved`` (link positions) the robot rests there when the run starts, away from the
    operating point the session saw first; ``chirp`` runs the first chirp-iteration step
    instead of the multisine. Returns the run, the session's output, the
    positions from the operating point, the sample the run ended at and |torque| / limit.
    """
    robot, ctrl = model or load_model(None)[1:]
    plant = FlexibleJointPlant(robot)
    lim = np.minimum(ctrl.torque_limit, robot.torque_limits())
    ctrl.torque_limit = lim
    out = _Out()
    sess = ExcitationSession(settings, robot.joint_names, robot.dt, lim, out,
                             model=(robot, ctrl.copy()) if predict else None)
    q, v = plant.state[0].copy(), np.zeros(robot.n_axes)
    sess.on_state(0, q.copy(), ctrl.integral.copy())
    k = 0
    if moved is not None:
        plant.reset(position=moved)
        ctrl.reset(plant.equilibrium_torque(moved))
        q, k = plant.state[0].copy(), 1
        sess.on_state(k, q.copy(), ctrl.integral.copy())
    run = sess.start_chirp_iteration() if chirp else sess.start_multisine()
    positions, torques, end = [], [], None
    while end is None or k < end + int(after_s / robot.dt):
        r = out.refs[-1][1] if out.refs else np.zeros(robot.n_axes)
        u = np.clip(ctrl.step(r, v), -lim, lim)
        q, v, effort = plant.step(u)
        k += 1
        positions.append(q.copy())
        torques.append(u / lim)
        if hide is None or not hide(k):
            sess.on_state(k, corrupt(k, q.copy()) if corrupt else q.copy(), effort.copy())
        if end is None and run.done.is_set():
            end = k
    return SimpleNamespace(run=run, out=out, dq=np.array(positions) - sess.q0, end=end,
                           share=np.abs(np.array(torques)), session=sess)


def test_pi_holds_its_integral_torque_when_the_measured_velocity_is_not_finite():
    """A NaN velocity (the PI is compiled with fastmath) gave -torque_limit on that axis."""
    robot, ctrl = load_model(None)[1:]
    ctrl.integral = np.array([0.0, 120.0, 40.0])        # holding the links' load
    u = ctrl.step(np.zeros(3), np.array([0.0, np.nan, np.inf]))
    np.testing.assert_array_equal(u, [0.0, 120.0, 40.0])
    np.testing.assert_array_equal(ctrl.integral, [0.0, 120.0, 40.0])
    u = ctrl.step(np.zeros(3), np.array([0.0, 0.01, 0.0]))       # and goes on from there
    assert np.all(np.isfinite(u)) and np.all(np.isfinite(ctrl.integral))
    assert u[1] == pytest.approx(120.0 - ctrl.kp[1] * 0.01 - ctrl.ki[1] * 0.01 * ctrl.dt)


def test_free_running_run_ends_on_a_zero_reference_and_the_robot_stays():
    """The last settle sample is a position correction; after it the controller got zero."""
    res = _free_run(SessionSettings(stale_samples=10 ** 9, multisine=SHORT), after_s=20.0)
    assert res.run.error is None and res.run.result is not None
    np.testing.assert_array_equal(res.out.refs[-1][1], np.zeros(3))
    drift = np.degrees(np.abs(res.dq[-1] - res.dq[res.end - 1]))
    assert np.all(drift < 0.01), drift                  # 1.5 deg after 60 s without the zero


def test_a_non_finite_measured_position_aborts_the_run():
    """A NaN position never exceeds a bound: unchecked, the run went on blind (18.9 deg off)."""
    def corrupt(k, q):
        if k >= 4500:
            q[0] = np.nan
        return q
    res = _free_run(SessionSettings(stale_samples=10 ** 9, multisine=SHORT), corrupt)
    assert res.end == 4500 and 'not finite' in res.run.error
    assert any('"aborted"' in e for e in res.out.events)
    np.testing.assert_array_equal(res.out.refs[-1][1], np.zeros(3))


@pytest.mark.parametrize('kw, match', [
    ({'live_position_bound_deg': float('nan')}, 'live_position_bound_deg=nan'),
    ({'live_position_bound_deg': 3.0}, 'below plan_bound_deg=4.0'),
    ({'abort_ramp_s': -0.01}, 'abort_ramp_s=-0.01 must be a positive'),
    ({'abort_ramp_s': 8.0}, 'must stop the robot within 0.1 s'),
    ({'stale_samples': 0}, 'stale_samples=0'),
    ({'stale_s': float('inf')}, 'stale_s=inf'),
])
def test_settings_that_switch_a_safety_check_off_are_refused(kw, match):
    with pytest.raises(DesignError, match=match):
        SessionSettings(**kw)


def test_a_saturating_drive_aborts_the_run():
    """
    A multisine that drives joint 2 into its torque limit stops at once.

    4 Hz resolution, one period without a transient period: the ramp onto the constant
    velocity and the multisine need more than joint 2's limit (checked only against the
    position bound before the run). Before this check the run ran to its end with joint 2 at
    the limit, 'successful'.
    """
    ms = MultisineConfig(n_realisations=1, n_periods=1, transient_periods=0, resolution_hz=4.0,
                         compensate=False)
    res = _free_run(SessionSettings(stale_samples=10 ** 9, multisine=ms))
    assert 'the drives saturate' in res.run.error
    assert np.sum(res.share >= 0.995) <= 2 and res.share.max() >= 0.995
    np.testing.assert_array_equal(res.out.refs[-1][1], np.zeros(3))


def test_a_plan_predicted_to_saturate_is_refused_before_it_runs():
    """
    With the model, the saturating plan above is refused at its start: nothing is sent.

    The dry run on the nominal model from the operating point predicts joint 2 at its limit;
    the default plan passes, and the free-running robot (here the model itself) then needs
    what was predicted: the prediction replays the session's plan, moves included.
    """
    robot, ctrl = load_model(None)[1:]
    lim = np.minimum(ctrl.torque_limit, robot.torque_limits())
    ms = MultisineConfig(n_realisations=1, n_periods=1, transient_periods=0, resolution_hz=4.0,
                         compensate=False)
    out = _Out()
    sess = ExcitationSession(SessionSettings(multisine=ms), robot.joint_names, robot.dt, lim,
                             out, model=(robot, ctrl))
    sess.on_state(0, FlexibleJointPlant(robot).state[0].copy(), None)
    with pytest.raises(SafetyError, match=r'multisine: the peak torque predicted .* joint_2 '
                                          r'\d+\.\d of 400 N m') as exc:
        sess.start_multisine()
    assert float(str(exc.value).split('joint_2 ')[1].split(' of')[0]) >= 0.95 * 400
    assert out.refs == [] and out.events == [] and sess.run is None
    res = _free_run(SessionSettings(stale_samples=10 ** 9, multisine=SHORT), predict=True)
    assert res.run.error is None
    lines = [t for t in res.out.logs if 'predicted peak torque' in t]
    assert len(lines) == 1
    predicted = np.array(json.loads(lines[0].split('torque ')[1].split(' N m')[0]))
    measured = res.share.max(axis=0) * lim
    print(f'measured peak {measured.round(2).tolist()}, predicted {predicted.tolist()} N m')
    np.testing.assert_allclose(measured, predicted, rtol=0.02)


@pytest.mark.parametrize('f_hz', [3.0, 17.0, 45.0])
def test_predicted_peak_torque_of_a_sine_is_the_analytic_closed_loop_amplitude(f_hz):
    """
    Truth written here, not by the simulator: u = (I + C P)^-1 C r for the linear 3-axis robot.

    P: motors (J_m, viscous b) on springs (k, d) to links coupled through the link inertia
    matrix, states (v_m, v_o, deflection), sampled with a zero-order hold (scipy);
    C(z) = kp + ki dt / (1 - 1/z) per axis (the PI's accumulation). The sines' amplitude fades
    in smoothly over 2 s, so each peak is the steady amplitude of the torque samples (measured
    within 0.08 %: over 6 s the samples come close to a crest) on top of the constant load the
    axis holds.
    """
    from scipy.signal import cont2discrete

    from frf_ident.core.excitation.procedures import Phase
    from frf_ident.core.simulation.runner import predict_peak_torque
    robot, ctrl = load_model(None)[1:]
    dt, n_ax = robot.dt, robot.n_axes
    n = int(8 / dt)
    t = np.arange(n) * dt
    amp = np.array([0.02, 0.01, 0.03])
    fade = np.sin(0.5 * np.pi * np.minimum(t / 2.0, 1.0)) ** 2
    ref = amp * (fade * np.sin(2 * np.pi * f_hz * t))[:, None]
    peak = predict_peak_torque([Phase('excite', n, reference=ref, excitation=ref)], robot, ctrl)
    for ax in robot.axes:
        assert ax.coulomb_friction == 0 and not ax.torque_ripple and ax.time_delay == 0
        assert not ax.gravity and ax.backlash == 0 and ax.stiffness_k2 is None

    def diag(key):
        return np.diag([getattr(ax, key) for ax in robot.axes])
    jm_inv = np.linalg.inv(diag('motor_inertia'))
    m_inv = np.linalg.inv(robot.link_inertia_matrix())
    k, d, b = diag('stiffness'), diag('damping'), diag('viscous_friction')
    zero, eye = np.zeros((n_ax, n_ax)), np.eye(n_ax)
    a = np.block([[-jm_inv @ (b + d), jm_inv @ d, -jm_inv @ k],     # J_m v_m' = u - b v_m - f
                  [m_inv @ d, -m_inv @ d, m_inv @ k],               # M v_o' = f
                  [eye, -eye, zero]])                               # f = k e + d e'
    ad, bd, cv, _dd, _ = cont2discrete((a, np.vstack([jm_inv, zero, zero]),
                                        np.hstack([eye, zero, zero]), zero), dt)
    z = np.exp(2j * np.pi * f_hz * dt)
    p = cv @ np.linalg.solve(z * np.eye(3 * n_ax) - ad, bd)
    c = np.diag(ctrl.kp + ctrl.ki * dt / (1 - 1 / z))
    u = np.linalg.solve(np.eye(n_ax) + c @ p, c @ amp)
    hold = np.abs([ax.gravity_torque for ax in robot.axes])
    print(f'{f_hz:g} Hz: dry run / analytic - 1 = {(peak / (hold + np.abs(u)) - 1).tolist()}')
    np.testing.assert_allclose(peak, hold + np.abs(u), rtol=0.003)


def test_a_first_chirp_step_predicted_to_need_95_percent_of_a_limit_is_refused():
    """
    r_initial 0.08 rad/s on joint 2 needs about 300 N m there: refused against a 300 N m limit.

    The default 0.006 rad/s (134 N m predicted) starts; only the first step is predicted on
    the model, later ones from what the earlier steps measured.
    """
    from frf_ident.core.excitation.chirp_iteration import ChirpConfig
    robot, ctrl = load_model(None)[1:]
    lim = np.array([300.0, 300.0, 300.0])
    q0 = FlexibleJointPlant(robot).state[0].copy()
    for r2, refused in ((0.08, True), (0.006, False)):
        out = _Out()
        cfg = ChirpConfig(r_initial=np.array([0.006, r2, 0.012]))
        sess = ExcitationSession(SessionSettings(chirp=cfg), robot.joint_names, robot.dt, lim,
                                 out, model=(robot, ctrl))
        sess.on_state(0, q0, None)
        if refused:
            with pytest.raises(SafetyError, match=r'chirp_iteration_1: .* joint_2 '):
                sess.start_chirp_iteration()
            assert out.refs == [] and sess.run is None
        else:
            sess.start_chirp_iteration()
            sess.on_state(1, q0, None)      # free-running: the run starts at this one
            assert out.refs and any('chirp_iteration_1: predicted peak torque' in t
                                    for t in out.logs)


def test_a_held_reference_drops_to_zero_when_not_renewed():
    """controller_node's free-running rule, in joint-state time (the robot's clock)."""
    from frf_ident.errors import FrfIdentInputError
    from frf_ident.nodes.controller_node import HeldReference
    held = HeldReference(3, 0.1)
    r = np.array([0.01, -0.02, 0.0])
    held.renew(r, -1)                       # before the first joint state: held from it
    t0 = 5_000_000_000
    for dt_ns, expect, dropped in ((0, r, None), (100_000_000, r, None),
                                   (100_000_001, 0 * r, r), (200_000_000, 0 * r, None)):
        got, gone = held.at(t0 + dt_ns)
        np.testing.assert_array_equal(got, expect)
        assert gone is dropped
    held.renew(r, t0 + 300_000_000)         # renewed: held again from then
    assert held.at(t0 + 390_000_000)[0] is r
    held.renew(0 * r, t0 + 400_000_000)     # a zero reference never expires (nothing logged)
    assert held.at(t0 + 10 ** 10)[1] is None
    # renewed with every joint state, a single late one (stamps jump 150 ms) keeps it
    held.renew(r, t0 + 10 ** 10)
    assert held.at(t0 + 10 ** 10 + 150_000_000) == (r, None)
    held.renew(r, t0 + 10 ** 10 + 150_000_000)
    assert held.at(t0 + 10 ** 10 + 151_000_000) == (r, None)
    for bad in (0.0, -1.0, float('nan'), float('inf')):
        with pytest.raises(FrfIdentInputError, match='reference_timeout_s='):
            HeldReference(3, bad)


def test_a_run_starts_at_the_first_joint_state_after_its_start():
    """
    The service call blocks the node's executor (plan and dry run: seconds): no burst after it.

    Free-running, the run was placed at the newest joint state known when the service came;
    the robot's next joint state, 1000 samples later, then released 1000 references at once,
    the move to the start position among them: the joints went 7.6 deg from the operating
    point instead of within the plan's 4 deg. Now the stream starts at that next joint state.
    """
    res = _free_run(SessionSettings(stale_samples=10 ** 9, multisine=SHORT), predict=True,
                    hide=lambda k: k <= 1000)
    assert res.run.error is None and res.run.start_k == 1002
    sent = [k for k, _r in res.out.refs]
    assert sent[0] == 1002 and np.all(np.diff(sent) == 1)
    peak_deg = np.degrees(np.abs(res.dq).max())
    print(f'largest excursion {peak_deg:.2f} deg')
    assert peak_deg < 4.2


def test_joint_states_jumping_past_the_stream_abort_the_run():
    """A stall of the node mid-run (50 samples unseen, limit 10): abort, not a burst."""
    res = _free_run(SessionSettings(stale_samples=10, multisine=SHORT),
                    hide=lambda k: 6000 <= k < 6050)
    assert res.end == 6050 and 'did not see 50 joint states' in res.run.error
    np.testing.assert_array_equal(res.out.refs[-1][1], np.zeros(3))
    # the ramp to zero is dated after the newest joint state, not back in the stall: the
    # samples of abort_ramp_s (10 at the model's 1 kHz)
    assert [k for k, _r in res.out.refs[-10:]] == list(range(6051, 6061))
    aborted = json.loads(res.out.events[-1])
    assert aborted['event'] == 'aborted' and aborted['t_end'] == pytest.approx(6.061)


def test_the_dry_run_starts_where_the_robot_is_now():
    """
    With gravity, a run started 7.5 deg away from the operating point needs other torques.

    Joint 2 carries 300 N m sin(q2 + 0.2) beside its constant 120 N m; the robot rests 7.5 deg
    from where the session first saw it. The prediction from the operating point was 10 % low
    on joint 2 (more than the 5 % margin); from the current position it is what the run needs.
    """
    from frf_ident.core.excitation.multisine_procedure import multisine_procedure
    from frf_ident.core.simulation.runner import predict_peak_torque
    robot, ctrl = load_model(None)[1:]
    robot.axes[1].gravity = [{'amplitude': 300.0, 'phase': 0.2}]
    ctrl.reset(robot.gravity_load(np.zeros(3)))
    moved = np.radians([0.0, 7.5, 0.0])
    res = _free_run(SessionSettings(stale_samples=10 ** 9, multisine=SHORT), predict=True,
                    model=(robot, ctrl), moved=moved)
    assert res.run.error is None
    line, = [t for t in res.out.logs if 'predicted peak torque' in t]
    predicted = np.array(json.loads(line.split('torque ')[1].split(' N m')[0]))
    measured = res.share.max(axis=0) * np.minimum(ctrl.torque_limit, robot.torque_limits())
    phases, _ = multisine_procedure(SHORT, 3, 1.0 / robot.dt)
    at_origin = predict_peak_torque(phases, robot, ctrl, np.zeros(3))
    print(f'joint 2: measured {measured[1]:.1f}, predicted {predicted[1]:.1f}, from the '
          f'operating point {at_origin[1]:.1f} N m')
    np.testing.assert_allclose(measured, predicted, rtol=0.02)
    assert measured[1] > 1.04 * at_origin[1]


@pytest.mark.parametrize('every, rate, jitter',
                         [(10, 100, 0.0), (5, 200, 0.0), (100, 10, 4.0)])
def test_joint_states_far_slower_than_the_model_are_refused(every, rate, jitter):
    """
    One reference goes out per joint state: most would never reach the robot.

    A joint_state_broadcaster at 100 or 200 Hz beside a model sampled at 1 kHz: the start is
    refused, naming the rate; nothing is sent. So at 10 Hz with stamps jittered by up to 4 ms
    (regular within 15 % of the step; within one sample it passed as a busy node).
    """
    robot, ctrl = load_model(None)[1:]
    assert robot.dt == pytest.approx(1e-3)
    out = _Out()
    sess = ExcitationSession(SessionSettings(multisine=SHORT), robot.joint_names, robot.dt,
                             ctrl.torque_limit, out)
    q = FlexibleJointPlant(robot).state[0].copy()
    wobble = np.random.default_rng(2).uniform(-jitter, jitter, 20)
    for j in range(20):
        sess.on_state(int(round(j * every + wobble[j])), q, None)
    with pytest.raises(SafetyError, match=rf'/joint_states come every {every}(\.5)? samples of '
                                          rf"the model's sample_rate 1000 Hz \(about {rate} Hz"):
        sess.start_multisine()
    assert out.refs == [] and sess.run is None


def test_joint_states_with_jitter_and_drops_pass():
    """Stamps jittered by up to 0.45 samples and every 7th state lost: the run starts."""
    robot, ctrl = load_model(None)[1:]
    out = _Out()
    sess = ExcitationSession(SessionSettings(multisine=SHORT), robot.joint_names, robot.dt,
                             ctrl.torque_limit, out)
    q = FlexibleJointPlant(robot).state[0].copy()
    jitter = np.random.default_rng(3).uniform(-0.45, 0.45, 40)
    for j in range(40):
        if j % 7 != 6:
            sess.on_state(int(round(j + jitter[j])), q, None)
    assert sess.start_multisine().error is None


def test_a_busy_node_missing_most_joint_states_is_left_to_the_watchdog():
    """
    Irregular steps of 2-10 samples (median 7): the node, not the robot, is slow; it starts.

    A busy node's misses are irregular; the multisine's FRF stays unbiased then
    (test/nodes/test_free_running.py runs the free-running graph on a loaded machine).
    """
    robot, ctrl = load_model(None)[1:]
    sess = ExcitationSession(SessionSettings(multisine=SHORT), robot.joint_names, robot.dt,
                             ctrl.torque_limit, _Out())
    q = FlexibleJointPlant(robot).state[0].copy()
    steps = np.random.default_rng(0).integers(2, 11, 20)
    assert np.median(steps[-16:]) >= 5
    for k in np.cumsum(steps):
        sess.on_state(int(k), q, None)
    assert sess.start_multisine().error is None


def test_joint_states_slowing_down_mid_run_abort_it():
    """From sample 3000 the session sees every sixth joint state: the run aborts."""
    res = _free_run(SessionSettings(stale_samples=10 ** 9, multisine=SHORT),
                    hide=lambda k: k > 3000 and k % 6)
    print(f'aborted at sample {res.end}: {res.run.error}')
    assert 3000 < res.end <= 3000 + 6 * 16
    assert '/joint_states come every 6 samples' in res.run.error and '167 Hz' in res.run.error
    np.testing.assert_array_equal(res.out.refs[-1][1], np.zeros(3))


def test_a_chirp_step_fills_the_torque_of_missed_joint_states():
    """
    A busy node misses joint states: their torque is filled, the step's result unchanged.

    One chirp step on the free-running robot with every joint state seen, then with every
    third one missed (one-sample gaps, 33 % of the torque samples): the measured peak torque
    and the step's error in dB agree within 1 % and 0.1 dB. With gaps of 4 samples the step
    fails naming what is missing, instead of updating from holes.
    """
    from frf_ident.app.excitation_torque import fill_torque_gaps
    from frf_ident.core.excitation.chirp_iteration import ChirpConfig
    cfg = ChirpConfig(duration=3.0, lead_s=0.2, settle_s=0.3)
    full = _free_run(SessionSettings(stale_samples=10 ** 9, chirp=cfg), chirp=True)
    holes = _free_run(SessionSettings(stale_samples=10 ** 9, chirp=cfg), chirp=True,
                      hide=lambda k: k % 3 == 0)
    a, b = full.run.result, holes.run.result
    peaks = [np.round(r['max_abs_torque'], 2).tolist() for r in (a, b)]
    print(f'peak torque {peaks[0]} / {peaks[1]} N m, error {a["error_db"]:.3f} / '
          f'{b["error_db"]:.3f} dB')
    np.testing.assert_allclose(b['max_abs_torque'], a['max_abs_torque'], rtol=0.01)
    assert abs(b['error_db'] - a['error_db']) < 0.1
    gaps = _free_run(SessionSettings(stale_samples=10 ** 9, chirp=cfg), chirp=True,
                     hide=lambda k: k % 10 >= 6)
    assert gaps.run.result is None and 'longest gap 4 samples' in gaps.run.error
    u = np.sin(np.arange(200.0))[:, None]
    u[50] = np.nan
    with pytest.raises(RuntimeError, match='1 of 200 torque samples missing'):
        fill_torque_gaps(u, max_gap=0)


def test_a_start_during_a_run_is_refused_before_planning_and_the_run_goes_on(monkeypatch):
    """
    A start during a run is refused before planning: the run is untouched.

    A second start came, planned for seconds on the node's executor, and the run's own
    watchdog aborted it for stale joint states, after which "still running" passed and a
    second run began.
    """
    robot, ctrl = load_model(None)[1:]
    out = _Out()
    sess = ExcitationSession(SessionSettings(multisine=SHORT), robot.joint_names, robot.dt,
                             ctrl.torque_limit, out)
    q = FlexibleJointPlant(robot).state[0].copy()
    sess.on_state(0, q, None)
    run = sess.start_multisine()
    sess.on_state(1, q, None)

    def no_plan(*args, **kw):
        raise AssertionError('planned while a run was running')
    monkeypatch.setattr('frf_ident.app.excitation_plan.multisine_procedure', no_plan)
    monkeypatch.setattr('frf_ident.app.excitation_plan.ChirpIteration', no_plan)
    for start in (sess.start_multisine, sess.start_chirp_iteration):
        with pytest.raises(RuntimeError, match="experiment 'multisine' is still running"):
            start()
    sess.watch()
    assert sess.run is run and not run.done.is_set() and run.error is None


def test_the_chirp_iteration_stops_at_max_iterations():
    """max_iterations=1: a second step is refused (the node ran a fourth of three before)."""
    from frf_ident.core.excitation.chirp_iteration import ChirpConfig
    cfg = ChirpConfig(duration=3.0, lead_s=0.2, settle_s=0.3, max_iterations=1)
    res = _free_run(SessionSettings(stale_samples=10 ** 9, chirp=cfg), chirp=True)
    assert res.run.result['iteration'] == 1 and not res.run.result['converged']
    with pytest.raises(RuntimeError, match=r'ran its max_iterations=1 steps without '
                                           r'converging \(last error 33\.\d+ dB\)'):
        res.session.start_chirp_iteration()
