"""Hit-rate sweep of the diagnosis (for `make bench`): one random hidden effect per seed in a
1-axis plant, short identification, diagnosis against the nominal model.

hit_rate(n_seeds) -> {'n': .., 'hits': .., 'rate': .., 'param_ok': .., 'gain_ok': ..,
'per_effect': {name: [hit, ...]}, 'runs': [...]}.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from frf_ident.core.diagnosis import EFFECTS, diagnose_experiments
from frf_ident.core.model.schema import controller_from_dict, robot_from_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.core.excitation.procedures import ChirpConfig, MultisineConfig
from frf_ident.core.simulation.runner import IdentificationConfig, run_identification

NOMINAL_1AXIS = {'frf_ident_model': 1, 'sample_rate': 1000.0, 'axes': [dict(
    name='joint_1', motor_inertia=35.0, link_inertia=150.0, stiffness=1.5e5, damping=400.0,
    viscous_friction=20.0, torque_limit=300.0)],
    'controller': {'kind': 'pi_velocity', 'kp': [1500.0], 'ki': [6000.0]}}

CHECK_KEY = {'coulomb_friction': 'coulomb_friction', 'viscous_friction': 'viscous_friction',
             'stiffness_nonlinearity': 'stiffness_k2', 'backlash': 'backlash',
             'torque_ripple': 'amplitude', 'time_delay': 'time_delay'}


def draw_effect(name: str, rng: np.random.Generator, axis) -> dict[str, Any]:
    """Random plausible change of one axis for effect ``name`` (model-file keys)."""
    if name == 'coulomb_friction':
        return {'coulomb_friction': float(rng.uniform(8, 30))}
    if name == 'viscous_friction':
        return {'viscous_friction': axis.viscous_friction + float(rng.uniform(40, 120))}
    if name == 'stiffness_nonlinearity':
        return {'stiffness_k2': axis.stiffness * float(rng.uniform(1.4, 1.9)),
                'stiffness_breakpoint': float(rng.uniform(1.0, 2.0)) * 1e-4}
    if name == 'backlash':
        return {'backlash': float(rng.uniform(2e-5, 8e-5))}
    if name == 'torque_ripple':
        return {'torque_ripple': [{'amplitude': float(rng.uniform(3, 10)),
                                   'spatial_frequency': float(rng.uniform(300, 1500)),
                                   'phase': float(rng.uniform(-3, 3))}]}
    if name == 'time_delay':
        return {'time_delay': float(rng.uniform(1.5e-3, 4e-3))}
    if name == 'parameter_mismatch':
        key = ['stiffness', 'link_inertia', 'motor_inertia'][int(rng.integers(3))]
        f = float(rng.choice([-1, 1]) * rng.uniform(0.15, 0.35))
        return {key: getattr(axis, key) * (1 + f)}
    raise ValueError(f'{name=} is not one of {EFFECTS}')


def short_config() -> IdentificationConfig:
    return IdentificationConfig(MultisineConfig(n_realisations=3, n_periods=2),
                                ChirpConfig(duration=10.0, u_des=ChirpConfig().u_des[:1],
                                            r_initial=np.array([0.006]), max_iterations=4))


def run_case(hidden: dict[str, Any], seed: int = 3, noise: float = 2e-5) -> dict[str, Any]:
    """Identify a plant = nominal + ``hidden`` (+ velocity noise) and diagnose it."""
    rob = robot_from_dict(NOMINAL_1AXIS)
    ctrl = controller_from_dict(NOMINAL_1AXIS, rob)
    real = replace(rob, axes=[replace(rob.axes[0], velocity_noise=noise, **hidden)], seed=seed)
    rec = run_identification(FlexibleJointPlant(real), controller_from_dict(NOMINAL_1AXIS, rob),
                             short_config())
    return diagnose_experiments(rec, rob, ctrl)


def param_error(name: str, hidden: dict[str, Any], found: dict[str, Any]) -> float:
    """Relative error of the effect's characteristic parameter."""
    if name == 'parameter_mismatch':
        key = next(iter(hidden))
        return abs(found.get(key, math.nan) / hidden[key] - 1)
    key = CHECK_KEY[name]
    if key == 'amplitude':
        return abs(found['torque_ripple'][-1]['amplitude'] / hidden['torque_ripple'][0]['amplitude'] - 1)
    return abs(found[key] / hidden[key] - 1)


def hit_rate(n_seeds: int = 14) -> dict[str, Any]:
    runs = []
    for seed in range(n_seeds):
        rng = np.random.default_rng(1000 + seed)
        name = EFFECTS[seed % len(EFFECTS)]
        hidden = draw_effect(name, rng, robot_from_dict(NOMINAL_1AXIS).axes[0])
        res = run_case(hidden, seed=seed)
        eff = res['effects']
        hit = bool(eff) and eff[0].name == name
        perr = param_error(name, hidden, eff[0].parameters) if hit else math.nan
        m = res['metrics']
        runs.append({'seed': seed, 'effect': name, 'hidden': hidden, 'hit': hit,
                     'found': [e.name for e in eff], 'param_error': perr,
                     'gain': m['extended']['frf_error_db'] < m['baseline']['frf_error_db']
                     or m['extended']['time_nrmse'] < m['baseline']['time_nrmse']})
    per: dict[str, list[bool]] = {}
    for r in runs:
        per.setdefault(r['effect'], []).append(r['hit'])
    hits = sum(r['hit'] for r in runs)
    return {'n': len(runs), 'hits': hits, 'rate': hits / max(len(runs), 1),
            'param_ok': sum(r['hit'] and r['param_error'] < 0.2 for r in runs),
            'gain_ok': sum(r['gain'] for r in runs), 'per_effect': per, 'runs': runs}


if __name__ == '__main__':
    import json
    print(json.dumps(hit_rate(), indent=1, default=str))
