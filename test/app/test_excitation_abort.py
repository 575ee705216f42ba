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
An abort on request (the ``/frf/abort`` service) stops a lockstep run at once.

The session runs a multisine against the simulated plant; after 4000 samples (inside the
first segment) the abort comes: the reference ramps to zero over the samples of
``abort_ramp_s`` after those already published, no step of it larger than the run's own, an
``aborted`` descriptor and a ``finished`` progress event with ``aborted`` go out, and the
descriptors declare the effort lag of the lockstep plant (1 sample, bag/pairing.py).
"""
from __future__ import annotations

import json

from frf_ident.app.excitation import ExcitationSession
from frf_ident.app.excitation_settings import abort_ramp_steps, SessionSettings
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.io.model_file import load_model
import numpy as np

SHORT = MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=2.0, compensate=False,
                        return_s=2.0, settle_s=0.3)


class _Out:
    def __init__(self) -> None:
        self.refs: dict[int, np.ndarray] = {}
        self.events: list[dict] = []
        self.progress_events: list[dict] = []

    def reference(self, k, r, x) -> None:
        self.refs[k] = np.array(r, float)

    def experiment(self, text) -> None:
        self.events.append(json.loads(text))

    def progress(self, event) -> None:
        self.progress_events.append(event)

    def log(self, level, text) -> None:
        pass


def test_abort_on_request_ramps_to_zero_and_reports():
    robot, ctrl = load_model(None)[1:]
    plant = FlexibleJointPlant(robot)
    lim = np.minimum(ctrl.torque_limit, robot.torque_limits())
    ctrl.torque_limit = lim
    out = _Out()
    sess = ExcitationSession(SessionSettings(lockstep=True, multisine=SHORT), robot.joint_names,
                             robot.dt, lim, out, sim_now_ns=lambda: 0)
    assert sess.abort('nothing runs') is None
    v = np.zeros(robot.n_axes)
    sess.on_state(0, plant.state[0].copy(), ctrl.integral.copy())
    run = sess.start_multisine()
    for k in range(4000):
        u = np.clip(ctrl.step(out.refs[k], v), -lim, lim)
        q, v, effort = plant.step(u)
        sess.on_state(k + 1, q.copy(), effort.copy())
    before = max(out.refs)
    r0 = out.refs[before]
    assert np.any(r0 != 0)
    assert sess.abort('abort requested (/frf/abort)') is run
    assert run.done.is_set() and 'abort requested' in run.error
    # lockstep: the ramp follows the references already published ahead (lookahead)
    ramp = [out.refs[k] for k in range(before + 1, max(out.refs) + 1)]
    assert len(ramp) == abort_ramp_steps(sess.s.abort_ramp_s, robot.dt) == 10
    assert np.allclose(ramp[-1], 0.0)
    assert np.all(np.abs(ramp[0]) <= np.abs(r0) + 1e-12)
    run_step = np.abs(np.diff([out.refs[k] for k in range(before + 1)], axis=0)).max()
    assert np.abs(np.diff([r0] + ramp, axis=0)).max() <= run_step
    assert out.events[-1]['event'] == 'aborted'
    end = out.progress_events[-1]
    assert end['event'] == 'finished' and end['aborted'] and not end['success']
    assert sess.abort('again') is None
    lags = {e.get('effort_lag') for e in out.events if e.get('event') in ('start', 'end')}
    assert lags == {1}
