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
The closed loop around MuJoCo compiled: numba calls MuJoCo's C ``mj_step`` itself.

A Python loop around ``mujoco.mj_step`` with the velocity PI in Python runs the iiwa 14 (3 axes,
1 kHz) at about 20x real time here; the MuJoCo step alone is a few microseconds. This kernel is
the sample loop of :func:`frf_ident.core.simulation.kernels.simulate` for MuJoCo: measure the axes
(position, velocity plus noise), the project's compiled loop step
(:func:`~frf_ident.core.simulation.controller.closed_loop_step`: plan feedback, filters and
the PI step :class:`~frf_ident.core.simulation.controller.PIVelocity` runs, the same as our
plant's), the torque limit, ``ctrl``, then
``substeps`` MuJoCo steps, all without Python per sample: MuJoCo's arrays are numpy views into
its mjData, and ``mj_step`` is called as a numba first-class function on the model's and
data's addresses (``MjModel._address``), so the kernel is cached on disk. MuJoCo's own
integrator, time step and everything else are untouched. ``python -m benchmarks --markdown
mujoco`` measures it against the Python loop.

Why not ``mujoco.rollout`` with the PI as an affine actuator (force = kp (r - v) + ki (q_ref - q)
with q_ref the integral of r, ctrl = kp r + ki q_ref precomputed): docs/mujoco.md, "Speed".
"""
from __future__ import annotations

import ctypes
import glob
import os

from frf_ident.core.simulation.controller import closed_loop_step
import mujoco
import numba
from numba.experimental.function_type import WrapperAddressProtocol
import numpy as np

__all__ = ['COMPILED', 'run_loop']


def _library():
    """Load MuJoCo's C library from the mujoco package (the one its bindings loaded)."""
    here = os.path.dirname(mujoco.__file__)
    for pattern in ('libmujoco.so*', 'libmujoco*.dylib', 'mujoco.dll'):
        found = sorted(glob.glob(os.path.join(here, pattern)))
        if found:
            try:
                return ctypes.CDLL(found[0])
            except OSError:
                return None
    return None


_LIB = _library()
#: whether the sample loop runs compiled (MuJoCo's C library found); else a Python loop
COMPILED = _LIB is not None


class _MjStep(WrapperAddressProtocol):
    """
    MuJoCo's C ``mj_step(const mjModel*, mjData*)`` as a numba first-class function.

    Passed to the kernel as an argument (not a global), so the kernel is cached on disk like
    the project's other kernels: the address is looked up in each process.
    """

    def __wrapper_address__(self) -> int:
        return ctypes.cast(_LIB.mj_step, ctypes.c_void_p).value

    def signature(self):
        # the two pointers as integers (MjModel._address, MjData._address): on x86-64 and
        # arm64 a pointer and an intp are passed alike
        return numba.types.void(numba.types.intp, numba.types.intp)


def _body(maddr, daddr, qpos, qvel, ctrl, qadr, vadr, act, gear, substeps, r, u_ext, closed,
          kp, ki, integ, sos, zf, ulim_ctrl, ulim, dt, enc, vn, tn, qplan, kpos, has_plan,
          out_q, out_v, out_u, out_r, step):
    """Run N samples (see :func:`run_loop`); ``step(maddr, daddr)`` is one MuJoCo step."""
    n = qadr.shape[0]
    e = np.empty(n)
    u = np.empty(n)
    q = np.empty(n)
    for k in range(r.shape[0]):
        for i in range(n):
            x = qpos[qadr[i]]
            if enc[i] > 0.0:
                x = enc[i] * np.floor(x / enc[i] + 0.5)
            q[i] = x
            out_q[k, i] = x
            out_v[k, i] = qvel[vadr[i]] + vn[k, i]
        if closed:
            closed_loop_step(r, k, q, out_v[k], has_plan, kpos, qplan, sos, zf, integ, kp, ki,
                             u_ext, ulim_ctrl, dt, e, u, out_r)
        else:
            for i in range(n):
                u[i] = u_ext[k, i]
        for i in range(n):
            a = min(max(u[i], -ulim[i]), ulim[i])
            out_u[k, i] = a + tn[k, i]
            ctrl[act[i]] = a / gear[i]
        for _ in range(substeps):
            step(maddr, daddr)


_kernel = numba.njit(cache=True, error_model='numpy')(_body)


def run_loop(model: mujoco.MjModel, data: mujoco.MjData, **kw) -> None:
    """
    Run samples of the plant in closed or open loop; the outputs are written in place.

    Keyword arguments as :func:`_body` names them (all arrays float64 or int64, C order).
    Compiled when :data:`COMPILED`, else the same loop in Python with ``mujoco.mj_step``.
    """
    args = dict(kw)
    if COMPILED:
        _kernel(model._address, data._address, data.qpos, data.qvel, data.ctrl, step=_MjStep(),
                **args)
    else:
        _body(0, 0, data.qpos, data.qvel, data.ctrl,
              step=lambda _m, _d: mujoco.mj_step(model, data), **args)
