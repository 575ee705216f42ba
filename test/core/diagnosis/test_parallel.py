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
"""The diagnosis' parallel parts give what running them one after the other gives."""
from dataclasses import replace
import os
from pathlib import Path

from frf_ident.core.diagnosis.common import simulate_like
from frf_ident.core.diagnosis.experiments.evaluator import Evaluator
from frf_ident.core.diagnosis.experiments.parallel import can_fork, WorkerPool
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.analytic import robot_frf, robot_frf_sampled
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.io.model_file import load_model
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]


def test_worker_pool_forks_once_and_keeps_the_order():
    seen = []

    def part(x):
        seen.append(x)          # the worker's copy only
        return x + 1, os.getpid()
    with WorkerPool(part, 2) as pool:
        first = pool.run([1, 2, 3])
        second = pool.run([10, 20])
    assert [v for v, _ in first] == [2, 3, 4] and [v for v, _ in second] == [11, 21]
    if can_fork():
        pids = {p for _, p in first + second}
        # the same workers served both batches: no fork per batch
        assert seen == [] and os.getpid() not in pids and len(pids) <= 2
    assert WorkerPool(part, 1).run([5, 6]) == [(6, os.getpid()), (7, os.getpid())]


def test_worker_pool_returns_large_arrays_through_shared_memory_as_copies():
    def part(x):
        rng = np.random.default_rng(x)
        # two arrays past the pickling size, a small one and a scalar
        return rng.standard_normal((x * 1000, 3)), rng.integers(0, 9, 20_000), np.ones(3), x
    items = [20, 30, 40, 5]
    want = [part(x) for x in items]
    # room for the first item's arrays only in each slot, and slots for two items
    with WorkerPool(part, 2, shared_bytes=700_000, max_items=2) as pool:
        got = pool.run(items)
        again = pool.run(items[::-1])
    for w, g in zip(want + want[::-1], got + again):
        assert len(g) == 4 and g[3] == w[3]
        for a, b in zip(w[:3], g[:3]):
            assert a.dtype == b.dtype and np.array_equal(a, b)
    if can_fork():
        # copied out of the shared memory (own data) or unpickled (a view of the bytes): the
        # first two items' large arrays that fit their slot, the rest pickled
        shared = [[b.flags.owndata for b in g[:2]] for g in got + again]
        assert shared == [[True, True], [False, True], [False] * 2, [False] * 2,
                          [True, True], [False, True], [False] * 2, [False] * 2]
    # the copies are the caller's: a later batch writing the same slots leaves them alone
    assert np.array_equal(got[0][0], want[0][0])


def test_parallel_simulations_equal_the_serial_ones():
    model, robot, ctrl = load_model(ROOT / 'config' / 'model_3axis.yaml')
    plant = FlexibleJointPlant(robot)
    c = ctrl.copy()
    c.reset(plant.equilibrium_torque())
    n = 1500
    r = np.tile([0.05, -0.04, 0.08], (n, 1)) * np.sin(np.arange(n) / 200)[:, None]
    res = plant.simulate(reference=r, controller=c)
    rec = Recording(res.t, robot.joint_names, res.position, res.velocity, res.effort, r)
    models = [robot.with_axes(coulomb_friction=x) for x in (0.0, 5.0, 20.0)]
    models.append(replace(robot, axes=[replace(robot.axes[0], stiffness=0.5
                                               * robot.axes[0].stiffness)] + robot.axes[1:]))

    def run(m):
        sim = simulate_like(rec, m, ctrl)
        return sim, float(sim.effort.sum())
    with WorkerPool(run, 2) as pool:
        par = pool.run(models)
    # the evaluator's own path: a batch simulated ahead, then each model taken from it
    ev = Evaluator(rec, ctrl, jobs=2)
    ev.prefetch(models)
    ahead = [ev.simulate(m) for m in models]
    ev.close()
    assert ev.n_sims == len(models)
    for m, (p, total), e in zip(models, par, ahead):
        s = simulate_like(rec, m, ctrl)
        for k in ('position', 'velocity', 'effort'):
            assert np.array_equal(getattr(s, k), getattr(p, k)), k
            assert np.array_equal(getattr(s, k), getattr(e, k)), k
        assert total == float(s.effort.sum())
    # the models differ, so equal arrays are no accident of one model simulated four times
    assert not np.array_equal(par[0][0].effort, par[2][0].effort)


@pytest.mark.parametrize('delay', [0.0, 0.0013])
def test_sampled_frf_of_some_inputs_is_their_column_and_near_the_continuous_one(delay):
    _, robot, _ = load_model(ROOT / 'config' / 'model_3axis.yaml')
    robot = robot.with_axes(time_delay=delay)
    f = np.geomspace(0.5, 5.0, 12)              # far below the 1 kHz sampling
    full = robot_frf_sampled(robot, f)
    one = robot_frf_sampled(robot, f, inputs=[2, 0])
    assert np.allclose(one[:, 0], full[:, 2], rtol=1e-12) and \
        np.allclose(one[:, 1], full[:, 0], rtol=1e-12)
    # zero-order hold: half a sample of delay besides the input delay, sampled velocity
    cont = robot_frf(robot, f) * np.exp(-2j * np.pi * f * (delay + 0.5 * robot.dt))
    assert np.allclose(full, cont, rtol=2e-3, atol=2e-3 * np.abs(cont).max())
