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
MuJoCo as the plant (section ``mujoco``): the iiwa 14 closed loop against our own plant.

The KUKA LBR iiwa 14 of the shared data set MuJoCo_iiwa14 identified on joints 1, 2 and 4 (the
other four welded at the home pose), the velocity PI at 1 kHz, 20 s of a two-sine reference.
Rows: simulated seconds per CPU second of this process (:data:`CLOCK`; best of 5) of
:class:`frf_ident.io.mjcf.plant.MujocoPlant` (numba calling MuJoCo's mj_step, the PI compiled)
beside our :class:`FlexibleJointPlant` of the same
robot (the MJCF read in our parameters at the pose) in the same run; the same with series
elasticity on joints 2 and 4; the Python loop (mj_step and PIVelocity.step per sample); MuJoCo's
step alone; and the option not taken: the PI as an affine actuator run by ``mujoco.rollout``
(speed, and how far its velocities are from the PIVelocity loop's, with the file's
implicitfast integrator and with Euler).
"""
from __future__ import annotations

from pathlib import Path
import tempfile
import time

import numpy as np

__all__ = ['rows']

SHARED = Path(__file__).resolve().parents[1].parent / 'shared' / 'data' / 'MuJoCo_iiwa14' \
    / 'iiwa14_dynamics.xml'
AXES = ['joint1', 'joint2', 'joint4']
KP, KI = [150.0, 150.0, 50.0], [1500.0, 1500.0, 500.0]
N = 20_000
DT = 1e-3


def _reference() -> np.ndarray:
    t = np.arange(N) * DT
    return (0.02 * np.sin(2 * np.pi * 3 * t) + 0.01 * np.sin(2 * np.pi * 17 * t))[:, None] \
        * np.ones(len(AXES))


def _model(xml: Path, pose: str | dict = 'home') -> dict:
    return {'frf_ident_model': 1, 'sample_rate': 1.0 / DT, 'mjcf': str(xml), 'pose': pose,
            'axes': [{'name': a} for a in AXES],
            'controller': {'kind': 'pi_velocity', 'kp': KP, 'ki': KI}}


#: the clock of every row: this process's CPU time. The machine is shared (load averages of
#: 10-16 on its 2 cores while this was written moved wall-time figures by 4x between runs);
#: for single-threaded code on an idle core CPU time and wall time agree
CLOCK = time.process_time


def _best(fn, repeat: int = 5) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = CLOCK()
        fn()
        best = min(best, CLOCK() - t0)
    return best


def _speeds(model_path: Path) -> tuple[float, float, object]:
    """(MuJoCo compiled, our plant of the same robot) in simulated s per wall s."""
    from frf_ident.core.simulation.controller import PIVelocity
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    from frf_ident.io.model_file import load_model, load_plant
    d, robot, ctrl = load_model(model_path)
    plant = load_plant('mujoco', d)
    r = _reference()

    def run_mj():
        plant.reset()
        plant.simulate(reference=r, controller=PIVelocity(KP, KI, plant.torque_limit, DT,
                                                          plant.hold.copy()))
    ours = FlexibleJointPlant(robot)

    def run_ours():
        ours.reset()
        ours.simulate(reference=r, controller=ctrl.copy(), keep_states=False)
    run_mj()
    run_ours()
    return N * DT / _best(run_mj), N * DT / _best(run_ours), plant


def _python_loop(plant) -> tuple[float, np.ndarray]:
    import mujoco

    from frf_ident.core.simulation.controller import PIVelocity
    r = _reference()
    plant.reset()
    pi = PIVelocity(KP, KI, plant.torque_limit, DT, plant.hold.copy())
    m, d, rb = plant.robot.model, plant.data, plant.robot
    v = np.empty((N, len(AXES)))
    t0 = CLOCK()
    for k in range(N):
        v[k] = d.qvel[rb.vadr]
        d.ctrl[rb.actuator] = pi.step(r[k], v[k])
        mujoco.mj_step(m, d)
    return N * DT / (CLOCK() - t0), v


def _affine_rollout(plant, integrator) -> tuple[float, np.ndarray]:
    """
    Run the PI as general actuators, open loop in ctrl, by mujoco.rollout.

    force = ctrl - ki q - kp v with ctrl_k = kp r_k + ki (q_0 + dt sum_{j<=k} r_j) + I_0: equal
    to PIVelocity's kp e_k + I_0 + ki dt sum_{j<=k} e_j where q_k - q_0 = dt sum_{j<=k} v_j,
    which Euler's position update makes exact (v_0 = 0 at rest); implicit integrators also
    integrate the -kp v term implicitly, which a sampled PI does not.
    """
    import mujoco
    from mujoco import rollout
    rb = plant.robot
    m = rb.model.__copy__()
    m.opt.integrator = integrator
    kp, ki = np.array(KP), np.array(KI)
    for i, a in enumerate(rb.actuator):
        m.actuator_biastype[a] = mujoco.mjtBias.mjBIAS_AFFINE
        m.actuator_biasprm[a, :3] = [0.0, -ki[i], -kp[i]]
        m.actuator_ctrllimited[a] = 0
        m.actuator_forcelimited[a] = 1
        m.actuator_forcerange[a] = [-rb.torque_limit[i], rb.torque_limit[i]]
    plant.reset()
    q0 = plant.data.qpos[rb.qadr].copy()
    r = _reference()
    full = np.zeros((N, m.nu))
    full[:, rb.actuator] = kp * r + ki * (q0 + DT * np.cumsum(r, axis=0)) + plant.hold
    d = mujoco.MjData(m)
    d.qpos[:] = plant.data.qpos
    mujoco.mj_forward(m, d)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.zeros(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, state, spec)
    t0 = CLOCK()
    out, _ = rollout.rollout(m, d, state[None], full[None])
    wall = CLOCK() - t0
    off = mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_TIME) + m.nq
    qvel = out[0, :, off:off + m.nv][:, rb.vadr]
    return N * DT / wall, np.vstack([np.zeros((1, len(AXES))), qvel[:-1]])


def _elastic(tmp: Path) -> Path:
    """Write the iiwa with series elasticity on joints 2 and 4 (test/plants/mujoco_iiwa.py)."""
    import sys
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'test'))
    from plants.mujoco_iiwa import elastic_xml
    path = tmp / 'iiwa_elastic.xml'
    path.write_text(elastic_xml())
    return path


def rows() -> list[tuple[str, str, str, str]]:
    import mujoco

    import yaml
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        rigid = Path(tmp) / 'rigid.yaml'
        rigid.write_text(yaml.safe_dump(_model(SHARED)))
        mj, ours, plant = _speeds(rigid)
        out.append(('iiwa 14, 3 of 7 axes, 1 kHz closed loop, per CPU s: MuJoCo plant',
                    f'{mj:,.0f}x real time', f'our plant {ours:,.0f}x', f'{mj / ours:.2f}'))
        py, v_py = _python_loop(plant)
        out.append(('  the same as a Python loop (mj_step, PIVelocity.step)',
                    f'{py:,.0f}x real time', f'compiled {mj:,.0f}x', f'{py / mj:.2f}'))
        m, d = plant.robot.model, mujoco.MjData(plant.robot.model)
        step = N * DT / _best(lambda: mujoco.mj_step(m, d, N))
        out.append(('  mujoco.mj_step(m, d, nstep) alone (no control)', f'{step:,.0f}x real time',
                    f'compiled loop {mj:,.0f}x', f'{mj / step:.2f}'))
        for name, integ in (("implicitfast (the file's)",
                             mujoco.mjtIntegrator.mjINT_IMPLICITFAST),
                            ('Euler', mujoco.mjtIntegrator.mjINT_EULER)):
            speed, v = _affine_rollout(plant, integ)
            dv = np.abs(v - v_py).max() / np.abs(v_py).max()
            out.append((f'  PI as affine actuator, mujoco.rollout, {name}',
                        f'{speed:,.0f}x real time', f'max |v - v_PIVelocity| {dv:.1e} of max |v|',
                        f'{speed / mj:.2f}'))
        elastic = Path(tmp) / 'elastic.yaml'
        pose = {'joint2': 0.785398, 'joint4': -1.5708}       # the home keyframe's
        elastic.write_text(yaml.safe_dump(_model(_elastic(Path(tmp)), pose)))
        mj, ours, _ = _speeds(elastic)
        out.append(('iiwa 14 with series elasticity on joints 2, 4 (5 dof): MuJoCo plant',
                    f'{mj:,.0f}x real time', f'our plant {ours:,.0f}x', f'{mj / ours:.2f}'))
    return out
