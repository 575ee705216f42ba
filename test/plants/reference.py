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
Independent reference plant for diagnosis tests and the bench sweep (docs/CONTRACT.md §4).

Written without :class:`frf_ident.core.simulation.plant.FlexibleJointPlant`: its own state
layout, its own fixed-step Runge-Kutta (RK4) integrator on a fine substep grid, its own
Karnopp stick-slip friction, torque ripple, backlash dead zone, stiffening spring, input delay
(command history), configuration-dependent gravity and an optional extra link-side mode (a
second mass on a spring behind each link: the unmodelled second resonance). It reads the
nominal model mapping (the §5 model file) for the linear part and adds the hidden scene:

``SCENE`` (module level) or the JSON in the environment variable ``FRF_REF_SCENE``::

    {"axes": {"0": {"coulomb_friction": 12.0, "torque_ripple": [...], ...}},   # §5 keys
     "extra_mode": {"1": {"frequency_hz": 35.0, "mass_ratio": 0.3, "damping_ratio": 0.03}},
     "velocity_noise": 2e-5, "torque_noise": 0.0, "seed": 3,
     "encoder_resolution": 2e-6, "velocity_from_encoder": true}

The sensor (issue 55), written here and not taken from the package: the motor position is
read by an encoder of ``encoder_resolution`` [rad per count] (one number for every axis or a
list per axis; 0: ideal), rounded to the nearest count; with ``velocity_from_encoder`` the
velocity is the difference of two successive readings over the sample time (what a drive
without a velocity sensor measures: the mean velocity of the last sample, half a sample late,
and the quantisation's noise 2 q^2 / 12 / dt^2 in its variance), else the true motor velocity;
``velocity_noise`` is added either way.

Use (with test/ on PYTHONPATH, as under pytest):
``frf-ident identify --model M.yaml --plant plants.reference:ReferencePlant``.
"""
from __future__ import annotations

import json
import math
import os
from typing import Any

import numba
import numpy as np

__all__ = ['SCENE', 'ReferencePlant', 'scene_axes']

SCENE: dict[str, Any] = {}
SUBSTEPS = 8          # RK4 steps per sample


def scene_axes(model: dict[str, Any], scene: dict[str, Any]) -> list[dict[str, Any]]:
    """Return the model's axes with the scene's hidden changes (plain dicts, §5 keys)."""
    axes = [dict(a) for a in model['axes']]
    for k, ch in (scene.get('axes') or {}).items():
        axes[int(k)].update(ch)
    return axes


@numba.njit(cache=True)
def _spring(e, k1, k2, bs, gap):
    """Spring torque behind a dead zone of total width gap, stiffening beyond bs (eq. 2)."""
    half = 0.5 * gap
    if e > half:
        x = e - half
    elif e < -half:
        x = e + half
    else:
        return 0.0, False
    ax = abs(x)
    if bs > 0.0 and ax > bs:
        t = k1 * bs + k2 * (ax - bs)
    else:
        t = k1 * ax
    return (t if x > 0 else -t), True


@numba.njit(cache=True)
def _rhs(s, u, p, minv, gamp, gph, gsel, mode, out):
    """Time derivative of s = [qm, vm, qo, vo, qe, ve] (blocks of n) for held torque u."""
    n = u.shape[0]
    tl = np.zeros(n)
    for i in range(n):
        qm, vm, qo, vo = s[i], s[n + i], s[2 * n + i], s[3 * n + i]
        ts, contact = _spring(qm - qo, p[i, 1], p[i, 2], p[i, 3], p[i, 7])
        td = p[i, 4] * (vm - vo) if contact else 0.0
        # motor side: torque, ripple, viscous, spring, damper; Coulomb handled by Karnopp
        rip = p[i, 9] * math.sin(p[i, 10] * qm + p[i, 11])
        drive = u[i] + rip - p[i, 5] * vm - ts - td
        fc = p[i, 6]
        if fc > 0.0:
            vst = p[i, 8]
            if abs(vm) < vst and abs(drive) <= fc:
                # Karnopp stick band: friction balances the drive and brings vm to rest
                out[n + i] = -vm * fc / (4 * vst * p[i, 0])
            elif abs(vm) < vst:
                out[n + i] = (drive - math.copysign(fc, drive)) / p[i, 0]
            else:
                out[n + i] = (drive - math.copysign(fc, vm)) / p[i, 0]
        else:
            out[n + i] = drive / p[i, 0]
        out[i] = vm
        g = 0.0
        for j in range(gamp.shape[1]):
            if gamp[i, j] != 0.0:
                arg = gph[i, j]
                for c in range(n):
                    arg += gsel[i, j, c] * s[2 * n + c]
                g += gamp[i, j] * math.sin(arg)
        te = 0.0
        if mode[i, 0] > 0.0:
            te = mode[i, 1] * (qo - s[4 * n + i]) + mode[i, 2] * (vo - s[5 * n + i])
            out[4 * n + i] = s[5 * n + i]
            out[5 * n + i] = te / mode[i, 0]
        else:
            out[4 * n + i] = 0.0
            out[5 * n + i] = 0.0
        tl[i] = ts + td - g - p[i, 12] - te
        out[2 * n + i] = vo
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += minv[i, j] * tl[j]
        out[3 * n + i] = acc


@numba.njit(cache=True)
def _advance(s, hist, k, delay_steps, frac, dt, p, minv, gamp, gph, gsel, mode, m):
    """
    Integrate one sample with RK4 in m substeps.

    RK4 over one sample in m substeps; the command each axis sees at time t is the held
    sample u[floor((t - delay) / dt)] from ``hist`` (ring of past commands, index k = now).
    """
    n = p.shape[0]
    h = dt / m
    nb = hist.shape[0]
    k1 = np.empty_like(s)
    k2 = np.empty_like(s)
    k3 = np.empty_like(s)
    k4 = np.empty_like(s)
    tmp = np.empty_like(s)
    u = np.empty(n)
    for sub in range(m):
        t0 = sub * h
        for i in range(n):
            # delayed zero-order hold: which sample's command acts at mid-substep
            tau = t0 + 0.5 * h - delay_steps[i] * dt - frac[i] * dt
            idx = int(math.floor(tau / dt + 1e-9))
            u[i] = hist[(k + idx) % nb, i]
        _rhs(s, u, p, minv, gamp, gph, gsel, mode, k1)
        for r in range(s.shape[0]):
            tmp[r] = s[r] + 0.5 * h * k1[r]
        _rhs(tmp, u, p, minv, gamp, gph, gsel, mode, k2)
        for r in range(s.shape[0]):
            tmp[r] = s[r] + 0.5 * h * k2[r]
        _rhs(tmp, u, p, minv, gamp, gph, gsel, mode, k3)
        for r in range(s.shape[0]):
            tmp[r] = s[r] + h * k3[r]
        _rhs(tmp, u, p, minv, gamp, gph, gsel, mode, k4)
        for r in range(s.shape[0]):
            s[r] += h / 6.0 * (k1[r] + 2 * k2[r] + 2 * k3[r] + k4[r])


class ReferencePlant:
    """Reference flexible-joint robot (see module docstring); §4 plug-in interface."""

    def __init__(self, config: dict | None = None) -> None:
        scene = SCENE or json.loads(os.environ.get('FRF_REF_SCENE', '{}'))
        model = config
        if not model:
            raise ValueError('ReferencePlant needs the model mapping (docs/CONTRACT.md §5)')
        axes = scene_axes(model, scene)
        n = len(axes)
        self.joint_names = [a.get('name', f'joint_{i + 1}') for i, a in enumerate(axes)]
        self.dt = 1.0 / float(model.get('sample_rate', 1000.0))
        p = np.zeros((n, 13))
        self.limit = np.zeros(n)
        delay = np.zeros(n)
        for i, a in enumerate(axes):
            k1 = float(a['stiffness'])
            k2 = a.get('stiffness_k2')
            bs = a.get('stiffness_breakpoint')
            rip = (a.get('torque_ripple') or [])
            if len(rip) > 1:
                raise ValueError('ReferencePlant models one ripple harmonic per axis')
            r0 = rip[0] if rip else {'amplitude': 0.0, 'spatial_frequency': 0.0}
            p[i] = [float(a['motor_inertia']), k1, float(k2) if k2 else k1,
                    float(bs) if bs else 0.0, float(a.get('damping', 0.0)),
                    float(a.get('viscous_friction', 0.0)), float(a.get('coulomb_friction', 0.0)),
                    float(a.get('backlash', 0.0)), 0.0, float(r0['amplitude']),
                    float(r0['spatial_frequency']), float(r0.get('phase', 0.0)),
                    float(a.get('gravity_torque', 0.0))]
            # stick band: twice the velocity change friction causes in one substep
            p[i, 8] = 2.0 * max(p[i, 6], 1e-9) * self.dt / SUBSTEPS / p[i, 0]
            self.limit[i] = float(a.get('torque_limit', 150.0))
            delay[i] = float(a.get('time_delay', 0.0))
        mo = np.diag([float(a['link_inertia']) for a in axes])
        if model.get('link_coupling') is not None:
            c = np.asarray(model['link_coupling'], float)
            mo = mo + c - np.diag(np.diag(c))
        self.minv = np.linalg.inv(mo)
        ng = max([len(a.get('gravity') or []) for a in axes] + [1])
        self.gamp, self.gph = np.zeros((n, ng)), np.zeros((n, ng))
        self.gsel = np.zeros((n, ng, n))
        for i, a in enumerate(axes):
            for j, g in enumerate(a.get('gravity') or []):
                self.gamp[i, j] = float(g['amplitude'])
                self.gph[i, j] = float(g.get('phase', 0.0))
                for name in g.get('joints') or [self.joint_names[i]]:
                    self.gsel[i, j, self.joint_names.index(name)] = 1.0
        # extra link-side mode: a share mass_ratio of the link inertia sits on a spring tuned to
        # frequency_hz (as seen with the link held), damping_ratio of critical; the rigid part
        # keeps the rest, so at low frequency the link weighs what the model says and only
        # the second resonance is new
        self.mode = np.zeros((n, 3))
        for k, em in (scene.get('extra_mode') or {}).items():
            i = int(k)
            me = float(em.get('mass_ratio', 0.3)) * float(axes[i]['link_inertia'])
            w = 2 * math.pi * float(em['frequency_hz'])
            self.mode[i] = [me, me * w * w, 2 * float(em.get('damping_ratio', 0.03)) * me * w]
            mo[i, i] -= me
        self.minv = np.linalg.inv(mo)
        self.p = p
        self.delay_steps = np.floor(delay / self.dt)
        self.frac = delay / self.dt - self.delay_steps
        self.nbuf = int(self.delay_steps.max()) + 4
        res = scene.get('encoder_resolution', 0.0)
        self.encoder = np.broadcast_to(np.asarray(res, float), (n,)).copy()
        self.differenced = bool(scene.get('velocity_from_encoder', False))
        self.vnoise = float(scene.get('velocity_noise', 0.0))
        self.tnoise = float(scene.get('torque_noise', 0.0))
        self.seed = int(scene.get('seed', 0))
        self.n = n
        self.reset()

    def _static_load(self) -> np.ndarray:
        """Link-side load at q_o = 0 (constant plus gravity terms)."""
        return self.p[:, 12] + (self.gamp * np.sin(self.gph)).sum(axis=1)

    def equilibrium_torque(self) -> np.ndarray:
        """Motor torque that holds the robot at rest (links at zero)."""
        return self._static_load()

    def reset(self) -> None:
        """Rest at the static equilibrium (links at zero, springs carrying the load)."""
        n = self.n
        self.s = np.zeros(6 * n)
        g = self._static_load()
        for i in range(n):
            k1, k2, bs, gap = self.p[i, 1], self.p[i, 2], self.p[i, 3], self.p[i, 7]
            x = abs(g[i]) / k1
            if bs > 0 and x > bs:
                x = bs + (abs(g[i]) - k1 * bs) / k2
            self.s[i] = math.copysign(x + 0.5 * gap, g[i]) if g[i] else 0.0
        self.hist = np.tile(g, (self.nbuf, 1))
        self.k = 0
        self.rng = np.random.default_rng(self.seed)
        self.q_read = self._encoder(self.s[:n])

    def _encoder(self, q: np.ndarray) -> np.ndarray:
        """Return the encoder's reading of motor positions q (nearest count)."""
        step = np.where(self.encoder > 0, self.encoder, 1.0)
        return np.where(self.encoder > 0, np.round(q / step) * step, q)

    def step(self, torque: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Apply motor torque for one sample; return (position, velocity, effort) at its end."""
        n = self.n
        u = np.clip(np.asarray(torque, float).reshape(n), -self.limit, self.limit)
        self.hist[self.k % self.nbuf] = u
        _advance(self.s, self.hist, self.k, self.delay_steps, self.frac, self.dt, self.p,
                 self.minv, self.gamp, self.gph, self.gsel, self.mode, SUBSTEPS)
        self.k += 1
        q = self._encoder(self.s[:n])
        v = (q - self.q_read) / self.dt if self.differenced else self.s[n:2 * n].copy()
        self.q_read = q
        v = v + self.vnoise * self.rng.standard_normal(n)
        e = u + self.tnoise * self.rng.standard_normal(n)
        return q, v, e
