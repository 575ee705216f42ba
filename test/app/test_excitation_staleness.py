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
The excitation session's watchdog in lockstep judges staleness in simulation time.

Issue 44: on a 2-core PC at load 4-12 the lockstep simulation stalled for 1.46 s of wall time
and the wall-time watchdog (0.5 s) aborted 3 of 4 multisine runs, although nothing was lost:
the simulated plant waits for its references, so a slow PC only slows the simulation. Here
the session runs a lockstep multisine against the simulated plant with a wall clock the test
controls: wall stalls of 2 s must not abort it, a plant clock that runs 0.6 s of simulation
time ahead of the newest joint state (measurements really missing) must, and so must a plant
silent for longer than ``plant_silent_s`` of wall time (a dead plant stops /clock too).
"""
from __future__ import annotations

from frf_ident.app import excitation
from frf_ident.app.excitation import ExcitationSession
from frf_ident.app.excitation_settings import SessionSettings
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.io.model_file import load_model
import numpy as np
from plants.session_outputs import RecordingOutputs
import pytest

SHORT = MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=2.0, compensate=False,
                        return_s=2.0, settle_s=0.3)


class _Wall:
    """time.monotonic of the session, advanced by the test."""

    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


@pytest.fixture
def wall(monkeypatch):
    w = _Wall()
    monkeypatch.setattr(excitation.time, 'monotonic', w)
    monkeypatch.setattr(excitation.time, 'sleep', lambda s: None)
    return w


def _lockstep(wall, steps=None, stall_every=2000, stall_s=2.0, lead_s=0.0):
    """
    Run a lockstep multisine; every ``stall_every`` samples the wall clock jumps ``stall_s``.

    The plant's clock is the newest sample it produced, plus ``lead_s`` once ``steps``
    samples ran (the plant went on while its joint states were lost). Returns the run and the
    sample count.
    """
    robot, ctrl = load_model(None)[1:]
    plant = FlexibleJointPlant(robot)
    lim = np.minimum(ctrl.torque_limit, robot.torque_limits())
    ctrl.torque_limit = lim
    out = RecordingOutputs()
    clock = {'ns': 0}
    settings = SessionSettings(lockstep=True, multisine=SHORT)
    sess = ExcitationSession(settings, robot.joint_names, robot.dt, lim, out,
                             sim_now_ns=lambda: clock['ns'])
    dt_ns = sess.dt_ns
    v = np.zeros(robot.n_axes)
    sess.on_state(0, plant.state[0].copy(), ctrl.integral.copy())
    run = sess.start_multisine()
    k = 0
    while not run.done.is_set() and k < 10 ** 6:
        if steps is not None and k >= steps:
            clock['ns'] = k * dt_ns + int(lead_s * 1e9)
            wall.t += 0.05
            sess.watch()
            continue
        r = out.refs.get(k)
        assert r is not None, f'no reference for sample {k}'
        u = np.clip(ctrl.step(r, v), -lim, lim)
        q, v, effort = plant.step(u)
        k += 1
        clock['ns'] = k * dt_ns
        sess.on_state(k, q.copy(), effort.copy())
        if k % stall_every == 0:
            wall.t += stall_s          # the PC stalled the simulation: no abort
            sess.watch()
        wall.t += 1e-5
    return run, k, out


def test_lockstep_run_survives_wall_stalls(wall):
    run, k, out = _lockstep(wall)
    assert run.done.is_set() and run.error is None, (run.error, out.logs[-3:])
    assert run.result is not None and k > 4000


def test_lockstep_stale_in_simulation_time_aborts(wall):
    run, k, out = _lockstep(wall, steps=3000, lead_s=0.6)
    assert run.error is not None and 'simulation time' in run.error, run.error
    # the ramp to zero went out after the newest joint state the node saw
    assert np.allclose(out.refs[max(out.refs)], 0.0)


def test_lockstep_silent_plant_aborts_in_wall_time(wall):
    # the plant died: no joint state and no /clock; wall time runs on
    run, k, _out = _lockstep(wall, steps=3000, lead_s=0.0)
    assert run.error is not None and 'plant_silent_s' in run.error, run.error
    assert k == 3000
