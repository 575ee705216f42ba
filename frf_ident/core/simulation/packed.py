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
The plant's parameters packed as arrays for the compiled kernels.

:func:`pack` turns a :class:`~frf_ident.core.model.params.RobotParams` into a
:class:`Packed`: the per-axis parameter matrix (columns named by the constants below), the
discretisation matrices of :mod:`frf_ident.core.simulation.linear`, ripple and gravity terms,
and the measurement's resolution and noise levels, as :mod:`frf_ident.core.simulation.kernels`
reads them.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.model.params import RobotParams
from frf_ident.core.simulation.linear import delayed_hold_matrices, substep_matrices
import numpy as np

# columns of the per-axis parameter matrix used by the kernels
JM, K1, K2, BS, DAMP, BV, FC, BL, GRAV, ULIM, NPARAM = range(11)


@dataclass
class Packed:
    prm: np.ndarray       # (n, NPARAM)
    ad: np.ndarray        # (nx, nx) state transition over one substep (nx = 4n + 2 modes)
    ga: np.ndarray        # (nx, n) input matrices for the stage values at start,
    gm: np.ndarray        # ... middle and end of a substep (quadratic interpolation)
    gb: np.ndarray
    gw: np.ndarray        # (nx, 2n) residual torques (motor side, link side), held
    cg: np.ndarray        # (nx,) effect of the constant gravity torque over one substep
    nonlinear: bool       # any residual torque (nonlinear spring, backlash, ripple)
    gold: np.ndarray      # (m, nx, n) held command, delayed: part of substep s under the older
    gnew: np.ndarray      # ... command u[k + offsets[s, 0, i]] and under the newer one
    ra: np.ndarray        # (n, R) ripple amplitudes
    rs: np.ndarray        # (n, R) spatial frequencies
    rp: np.ndarray        # (n, R) phases
    gamp: np.ndarray      # (n, G) gravity amplitudes G
    gph: np.ndarray       # (n, G) gravity phases phi
    gsel: np.ndarray      # (n, G, n) 1 where joint j's link position enters term g of axis i
    offsets: np.ndarray   # (m, 2, n) int: sample offsets of the older / newer command
    nbuf: int
    enc: np.ndarray       # (n,) encoder resolution
    vnoise: np.ndarray    # (n,)
    tnoise: np.ndarray    # (n,)


def pack(params: RobotParams) -> Packed:
    params.refuse_urdf_terms('the simulation')
    n = params.n_axes
    prm = np.zeros((n, NPARAM))
    n_rip = max([len(a.torque_ripple) for a in params.axes] + [1])
    ra, rs, rp = np.zeros((n, n_rip)), np.zeros((n, n_rip)), np.zeros((n, n_rip))
    dt, m = params.dt, int(params.substeps)
    n_g = max([len(a.gravity) for a in params.axes] + [1])
    gamp, gph, gsel = np.zeros((n, n_g)), np.zeros((n, n_g)), np.zeros((n, n_g, n))
    for i, a in enumerate(params.axes):
        for j, g in enumerate(a.gravity):
            gamp[i, j] = float(g['amplitude'])
            gph[i, j] = float(g.get('phase', 0.0))
            gsel[i, j, a.gravity_joints(params.joint_names, j)] = 1.0
        prm[i, JM] = a.motor_inertia
        prm[i, K1] = a.stiffness
        nonlinear = a.stiffness_k2 is not None and a.stiffness_breakpoint is not None
        prm[i, K2] = a.stiffness_k2 if nonlinear else a.stiffness
        prm[i, BS] = a.stiffness_breakpoint if nonlinear else 0.0
        prm[i, DAMP] = a.damping
        prm[i, BV] = a.viscous_friction
        prm[i, FC] = a.coulomb_friction
        prm[i, BL] = a.backlash
        prm[i, GRAV] = a.gravity_torque
        prm[i, ULIM] = a.torque_limit
        for j, rip in enumerate(a.torque_ripple):
            ra[i, j] = float(rip['amplitude'])
            rs[i, j] = float(rip['spatial_frequency'])
            rp[i, j] = float(rip.get('phase', 0.0))
    ad, ga, gm, gb, gw = substep_matrices(params, dt / m)
    offsets, gold, gnew = delayed_hold_matrices(params)
    nbuf = int(-offsets.min()) + 2
    nonlinear = bool(np.any(ra != 0) or np.any(prm[:, BL] > 0) or np.any(gamp != 0)
                     or np.any((prm[:, BS] > 0) & (prm[:, K2] != prm[:, K1])))
    cg = gw[:, n:] @ (-prm[:, GRAV])
    return Packed(prm, ad, ga, gm, gb, gw, cg, nonlinear, gold, gnew, ra, rs, rp, gamp, gph,
                  gsel, offsets, nbuf,
                  np.array([a.encoder_resolution for a in params.axes]),
                  np.array([a.velocity_noise for a in params.axes]),
                  np.array([a.torque_noise for a in params.axes]))
