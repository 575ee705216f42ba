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
Discretisation error of the simulated plant per effect, against a converged simulation.

The plant integrates its linear part exactly; each nonlinear effect adds an error that falls
with the model file's ``simulation.substeps`` m as the effect's order says: smooth residual
torques (stiffening spring, ripple) by the exponential Heun rule, second order; Coulomb
friction's stick-slip transitions and backlash contacts, switching inside a substep, first
order. The diagnosis simulates at the model file's substeps, so the error is part of every
misfit it computes: compare it with the effort noise of the record.

Run: ``python -m benchmarks discretisation``.
"""
from __future__ import annotations

from dataclasses import replace
import math

import numpy as np

#: one effect at a time on every axis of the default model (model-file keys); sizes in the
#: middle of the realistic ranges of benchmarks/diagnosis_scenes.py (stiffening: k2 = 1.5 k1)
EFFECTS = {
    'none (linear)': {},
    'Coulomb friction 15 N m': {'coulomb_friction': 15.0},
    'backlash 5e-5 rad': {'backlash': 5e-5},
    'stiffening k2 = 1.5 k1 beyond 2.5e-4 rad': {'stiffness_breakpoint': 2.5e-4},
    'torque ripple 4 N m at 120 /rad': {
        'torque_ripple': [{'amplitude': 4.0, 'spatial_frequency': 120.0, 'phase': 0.0}]},
}
SUBSTEPS = (1, 2, 4, 8)
REFERENCE = 64                # substeps of the converged simulation the others are scored on
VELOCITY_NOISE = 2e-5         # [rad/s], config/robot_3axis_demo.yaml and the diagnosis scenes


def discretisation_error(changes: dict, substeps: int, *, seconds: float = 20.0,
                         reference_substeps: int = REFERENCE,
                         velocity_noise: float = 0.0) -> float:
    """
    Return the plant's effort error at ``substeps`` against a converged simulation.

    The default 3-axis model with ``changes`` on every axis, in closed loop at 1 kHz, follows
    a reference that reverses every second (0.05 rad/s at 0.5 Hz) plus a 2-60 Hz odd
    multisine: the motion of an identification run, with a stick-slip transition at each
    reversal.

    Parameters
    ----------
    changes : dict
        Model-file keys of one effect, set on every axis; ``stiffness_breakpoint`` comes with
        ``stiffness_k2`` = 1.5 x the axis' stiffness.
    substeps : int
        Integrator substeps per sample of the run scored.
    seconds : float, optional
        Duration of the run [s].
    reference_substeps : int, optional
        Substeps of the converged run.
    velocity_noise : float, optional
        Velocity noise [rad/s] on the run scored: for a linear model the result is then the
        effort noise that sensor noise causes through the controller, the scale the
        discretisation error is to be compared with.

    Returns
    -------
    float
        RMS of the effort difference to the converged, noise-free run [N m], all axes.

    """
    from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
    from frf_ident.core.model.schema import default_model_dict, robot_from_dict
    from frf_ident.core.simulation.controller import controller_from_dict
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    d = default_model_dict()
    base = robot_from_dict(d).linear()
    axes = [replace(a, **changes, **({'stiffness_k2': 1.5 * a.stiffness}
                                     if 'stiffness_breakpoint' in changes else {}))
            for a in base.axes]
    fs = base.sample_rate
    des = design_odd_multisine(2.0, 60.0, bound=0.01, resolution_hz=0.5, fs=fs)
    real = multisine_realisation(des, 3, np.random.default_rng(0), fs=fs)
    t = np.arange(int(seconds * fs)) / fs
    r = 0.05 * np.sin(np.pi * t)[:, None] + real.evaluate(t)[0]

    def run(m: int, noise: float) -> np.ndarray:
        rob = replace(base, substeps=m, axes=[replace(a, velocity_noise=noise) for a in axes])
        return FlexibleJointPlant(rob).simulate(
            reference=r, controller=controller_from_dict(d, rob)).effort
    ref = run(reference_substeps, 0.0)
    return float(np.sqrt(np.mean((run(substeps, velocity_noise) - ref) ** 2)))


def orders(err: list[float]) -> list[float]:
    """Return the observed orders log2(e(m) / e(2 m)) of errors at doubling substeps."""
    return [math.log2(a / b) for a, b in zip(err, err[1:]) if a > 0 and b > 0]


def rows() -> list[tuple[str, str, str, str]]:
    """Return the bench rows: per effect the error at each substeps, the noise, the order."""
    noise = discretisation_error({}, 1, velocity_noise=VELOCITY_NOISE)
    out = []
    for name, changes in EFFECTS.items():
        err = [discretisation_error(changes, m) for m in SUBSTEPS]
        cells = ', '.join(f'{m}: {e:.2g}' for m, e in zip(SUBSTEPS, err))
        ords = orders(err)
        out.append((f'plant effort error [N m RMS] vs {REFERENCE} substeps, {name}',
                    f'substeps {cells}',
                    f'effort noise {noise:.2g} (velocity noise {VELOCITY_NOISE:g} rad/s)',
                    'order ' + ' / '.join(f'{o:.1f}' for o in ords) if ords else '-'))
    return out
