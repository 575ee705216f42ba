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
MuJoCo as the plant: a docs/CONTRACT.md §4 plug-in with the batch ``simulate`` of our own plant.

``frf-ident identify --plant mujoco`` (the model file's ``mjcf``) or ``--plant mujoco:FILE.xml``
(another MJCF, the model's axes by joint name), ``demo --plant`` and the plant node's ``plant``
parameter construct :class:`MujocoPlant` with the model mapping. Torque in through each axis'
motor (our u [N m] = gear x ctrl, clipped at gear x ctrlrange), the motor-side joints'
positions and velocities out once per sample (the model file's ``sample_rate``; MuJoCo's own
integrator and ``timestep``, several steps per sample when it is finer), gravity on, the start
at rest at the pose (:meth:`~frf_ident.io.mjcf.robot.MjcfRobot.rest`); joints not identified
are welded at the pose (:func:`~frf_ident.io.mjcf.robot.load_robot`). Measurement noise and
encoder resolution come from the model file's axes, as for our own plant.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from frf_ident.core.model.params import MjcfSource
from frf_ident.core.model.schema import default_model_dict, mjcf_source_from_dict
from frf_ident.core.simulation.plant import SimResult
from frf_ident.errors import MjcfError
from frf_ident.io.mjcf.loop import run_loop
from frf_ident.io.mjcf.robot import load_robot
import mujoco
import numpy as np

__all__ = ['MujocoPlant']


class MujocoPlant:
    """
    An MJCF simulated by MuJoCo, identified on the model file's axes.

    Parameters
    ----------
    config : dict, optional
        The model mapping (docs/CONTRACT.md §5): axis names (the MJCF's joints), sample rate,
        noise, seed, and ``mjcf``/``pose`` unless ``mjcf`` is given. Default: the embedded
        model (whose axes are not an MJCF's: give ``mjcf`` and a model naming its joints).
    mjcf : str or Path, optional
        The MJCF to simulate instead of the model's (``--plant mujoco:FILE.xml``); it starts at
        the model's pose (every joint the model's MJCF poses must be in it), else at its first
        keyframe or ``qpos0``.

    Raises
    ------
    MjcfError
        No MJCF named, or it does not fit the axes (:func:`~frf_ident.io.mjcf.robot.load_robot`).

    """

    def __init__(self, config: dict[str, Any] | None = None, *,
                 mjcf: str | Path | None = None) -> None:
        d = config if config is not None else default_model_dict()
        src = mjcf_source_from_dict(d) if 'mjcf' in d else None
        if mjcf is not None:      # the model's pose, joint by joint (not its keyframe's name)
            src = MjcfSource(str(mjcf), None, src.pose if src else {})
        if src is None:
            raise MjcfError('--plant mujoco: the model file names no mjcf; give one in the '
                            'model (mjcf: robot.xml) or as --plant mujoco:FILE.xml')
        axes = d.get('axes') or []
        names = [str(a.get('name', f'joint_{i + 1}')) for i, a in enumerate(axes)]
        self.robot = load_robot(src, names)
        self.sample_rate = float(d.get('sample_rate', 1000.0))
        self.substeps = self.robot.substeps(1.0 / self.sample_rate)
        n = len(names)

        def per_axis(key):
            return np.array([float(a.get(key, 0.0) or 0.0) for a in axes]) if axes \
                else np.zeros(n)
        self.enc, self.vnoise, self.tnoise = (per_axis(k) for k in (
            'encoder_resolution', 'velocity_noise', 'torque_noise'))
        self.seed = int((d.get('simulation') or {}).get('seed', 0))
        self.data = mujoco.MjData(self.robot.model)
        self.reset(seed=self.seed)

    @property
    def dt(self) -> float:
        """Return the sample time [s]."""
        return 1.0 / self.sample_rate

    @property
    def joint_names(self) -> list[str]:
        """Return the identified joints."""
        return list(self.robot.axes)

    @property
    def n_axes(self) -> int:
        """Return the number of identified joints."""
        return self.robot.n_axes

    @property
    def torque_limit(self) -> np.ndarray:
        """Return the torque limit of every axis [N m] (gear x ctrlrange)."""
        return self.robot.torque_limit

    @property
    def state(self) -> np.ndarray:
        """Return (2, n): the axes' motor-side positions [rad] and velocities [rad/s]."""
        d, r = self.data, self.robot
        return np.vstack([d.qpos[r.qadr], d.qvel[r.vadr]])

    def equilibrium_torque(self, position: np.ndarray | None = None) -> np.ndarray:
        """Return the torque [N m] that holds the links at ``position`` (default the pose)."""
        return self.robot.rest(position).hold

    def reset(self, seed: int | None = None, position: np.ndarray | None = None) -> None:
        """
        Back to rest at the pose (or the axes' link ``position`` [rad]), holding torque applied.

        The noise generator continues unless ``seed`` is given.
        """
        rest = self.robot.rest(position)
        mujoco.mj_resetData(self.robot.model, self.data)
        self.data.qpos[:] = rest.qpos
        self.data.ctrl[self.robot.actuator] = rest.hold / self.robot.gear
        mujoco.mj_forward(self.robot.model, self.data)
        self.hold = rest.hold
        if seed is not None or not hasattr(self, 'rng'):
            self.rng = np.random.default_rng(self.seed if seed is None else seed)

    def _noise(self, n_samples: int) -> tuple[np.ndarray, np.ndarray]:
        n = self.n_axes
        vn = self.rng.standard_normal((n_samples, n)) * self.vnoise if self.vnoise.any() \
            else np.zeros((n_samples, n))
        tn = self.rng.standard_normal((n_samples, n)) * self.tnoise if self.tnoise.any() \
            else np.zeros((n_samples, n))
        return vn, tn

    def simulate(self, *, reference: np.ndarray | None = None, torque: np.ndarray | None = None,
                 controller: Any = None, n_samples: int | None = None,
                 position_plan: np.ndarray | None = None,
                 position_gain: float | np.ndarray = 0.0, keep_states: bool = False
                 ) -> SimResult:
        """
        Run samples from the current state, as :meth:`FlexibleJointPlant.simulate` does.

        Closed loop (``controller``, a PIVelocity, its integral updated): u = PI(reference -
        y) + torque, the reference with position feedback ``position_gain (plan - q)`` where
        ``position_plan`` is given; open loop: u = torque. The measurement of sample k is taken
        before its torque is applied. ``SimResult.states`` is None (MuJoCo's state is its own).
        """
        n = self.n_axes
        lengths = [a.shape[0] for a in (reference, torque) if a is not None]
        N = n_samples if n_samples is not None else (lengths[0] if lengths else 0)
        if any(L != N for L in lengths):
            raise ValueError(f'input lengths {lengths} differ from {N=}')
        r = np.zeros((N, n)) if reference is None else np.ascontiguousarray(reference, float)
        u_ext = np.zeros((N, n)) if torque is None else np.ascontiguousarray(torque, float)
        has_plan = position_plan is not None
        qplan = np.ascontiguousarray(position_plan, float) if has_plan else np.zeros((1, n))
        kpos = np.broadcast_to(np.asarray(position_gain, float), (n,)).copy()
        lim = np.ascontiguousarray(self.robot.torque_limit, float)
        if controller is not None:
            kp, ki, integ = controller.kp, controller.ki, controller.integral
            ulim_ctrl = np.minimum(controller.torque_limit, lim)
            sos, zf = controller.sos, controller.filter_state
        else:
            kp = ki = np.zeros(n)
            integ, ulim_ctrl = np.zeros(n), lim
            sos, zf = np.zeros((n, 0, 6)), np.zeros((n, 0, 2))
        vn, tn = self._noise(N)
        out_q, out_v, out_u = np.empty((N, n)), np.empty((N, n)), np.empty((N, n))
        out_r = r.copy()
        rb = self.robot
        run_loop(rb.model, self.data, qadr=rb.qadr, vadr=rb.vadr, act=rb.actuator,
                 gear=np.ascontiguousarray(rb.gear, float), substeps=self.substeps, r=r,
                 u_ext=u_ext, closed=controller is not None, kp=kp, ki=ki, integ=integ,
                 sos=sos, zf=zf, ulim_ctrl=ulim_ctrl, ulim=lim, dt=self.dt, enc=self.enc, vn=vn,
                 tn=tn, qplan=qplan, kpos=kpos, has_plan=has_plan, out_q=out_q, out_v=out_v,
                 out_u=out_u, out_r=out_r)
        t0 = self.data.time - N * self.dt
        return SimResult(t0 + np.arange(N) * self.dt, out_q, out_v, out_u, None, out_r)

    def step(self, torque: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Apply motor torque [N m] for one sample; return (position, velocity, effort).

        docs/CONTRACT.md §4: the measurement at the end of the sample; the effort is the
        torque applied (clipped at the limit) plus torque noise.
        """
        res = self.simulate(torque=np.asarray(torque, float).reshape(1, self.n_axes))
        vn, _ = self._noise(1)
        d, r = self.data, self.robot
        q = d.qpos[r.qadr].copy()
        if self.enc.any():
            enc = np.where(self.enc > 0, self.enc, 1.0)
            q = np.where(self.enc > 0, enc * np.floor(q / enc + 0.5), q)
        return q, d.qvel[r.vadr] + vn[0], res.effort[0]
