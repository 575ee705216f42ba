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

from types import SimpleNamespace

from frf_ident.app.excitation import ExcitationSession, SessionSettings
from frf_ident.core.excitation.procedures import MultisineConfig
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.errors import DesignError
from frf_ident.io.model_file import load_model
import numpy as np
import pytest

#: a short multisine (one realisation, two 1 s periods, no compensation run): about 35 s
SHORT = MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=1.0, compensate=False)


class _Out:
    def __init__(self) -> None:
        self.refs: list[tuple[int, np.ndarray]] = []
        self.events: list[str] = []

    def reference(self, k, r, x) -> None:
        self.refs.append((k, np.array(r, float)))

    def experiment(self, text) -> None:
        self.events.append(text)

    def progress(self, event) -> None:
        pass

    def log(self, level, text) -> None:
        pass


def _free_run(settings: SessionSettings, corrupt=None, after_s: float = 0.0):
    """
    Run a multisine on the free-running simulated robot.

    The controller holds the latest reference it got (controller_node's rule) and keeps
    running ``after_s`` seconds after the procedure ended; ``corrupt(k, q)`` may alter the
    measured position the session sees. Returns the run, the session's output, the
    positions from the operating point, the sample the run ended at and |torque| / limit.
    """
    robot, ctrl = load_model(None)[1:]
    plant = FlexibleJointPlant(robot)
    lim = np.minimum(ctrl.torque_limit, robot.torque_limits())
    ctrl.torque_limit = lim
    out = _Out()
    sess = ExcitationSession(settings, robot.joint_names, robot.dt, lim, out)
    q, v = plant.state[0].copy(), np.zeros(robot.n_axes)
    sess.on_state(0, q.copy(), ctrl.integral.copy())
    run = sess.start_multisine()
    positions, torques, k, end = [], [], 0, None
    while end is None or k < end + int(after_s / robot.dt):
        r = out.refs[-1][1] if out.refs else np.zeros(robot.n_axes)
        u = np.clip(ctrl.step(r, v), -lim, lim)
        q, v, effort = plant.step(u)
        k += 1
        positions.append(q.copy())
        torques.append(u / lim)
        sess.on_state(k, corrupt(k, q.copy()) if corrupt else q.copy(), effort.copy())
        if end is None and run.done.is_set():
            end = k
    return SimpleNamespace(run=run, out=out, dq=np.array(positions) - sess.q0, end=end,
                           share=np.abs(np.array(torques)))


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
    ({'live_position_bound_deg': 3.0}, 'below position_bound_deg=4.0'),
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
