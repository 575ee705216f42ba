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
Scenes of the diagnosis sweep: hidden effects drawn at realistic sizes, with their truth.

A scene is a plug-in scene of the independent reference plant (test/plants/reference.py)
with 0-4 hidden effects, a second link-side mode or a realistic sensor, drawn by kind
(:data:`KINDS` cycled, :data:`EXTRA_KINDS` by name) from a seeded generator
(:func:`scene_of`), and the truth the diagnosis is scored against
(benchmarks/diagnosis_scene_run.py; the sweep: benchmarks/diagnosis.py).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / 'config' / 'model_3axis.yaml'
NOISE = 2e-5                      # velocity noise of the "real" robot [rad/s]
KINDS = ('random', 'random', 'random', 'two_on_one_axis', 'weak_axis_small', 'second_mode',
         'clean', 'gravity')
# the characteristic parameter of each effect, compared within 20 %
CHECK_KEY = {'coulomb_friction': 'coulomb_friction', 'viscous_friction': 'viscous_friction',
             'stiffness_nonlinearity': 'stiffness_k2', 'backlash': 'backlash',
             'torque_ripple': 'amplitude', 'time_delay': 'time_delay', 'gravity': 'amplitude',
             'parameter_mismatch': 'stiffness', 'second_mode': 'frequency_hz'}
# gravity, a parameter mismatch and a second mode: scene kinds of their own
DRAWN = tuple(k for k in CHECK_KEY if k not in ('gravity', 'parameter_mismatch', 'second_mode'))
# drawn only when asked for by name (not in the cycle, so the README sweeps keep their scenes):
# 'sensor' is the nominal plant read by a realistic sensor, 'sensor_two' the same with two
# small effects on two axes (issue 55); 'link_mode', 'link_mode_beside' a second mode (57)
EXTRA_KINDS = ('mismatch', 'sensor', 'sensor_two', 'link_mode', 'link_mode_beside')
#: [rad] the encoder steps of a realistic sensor are drawn log-uniformly between these
ENCODER_RANGE = (1e-6, 1e-5)
# issue 57: a second link-side mode, 10-25 % of the link's inertia, tuned to 15-45 Hz (with
# the link held), damping ratio 0.005-0.08 (log-uniform: as many light as heavy modes)
LINK_MODE_RATIO = (0.10, 0.25)
LINK_MODE_HZ = (15.0, 45.0)
LINK_MODE_DAMPING = (0.005, 0.08)


def _nominal() -> dict[str, Any]:
    from frf_ident.io.model_file import load_model
    return load_model(MODEL)[0]


def draw_effect(name: str, rng: np.random.Generator, axis: dict[str, Any],
                small: bool = False) -> dict[str, Any]:
    """
    Draw a random realistic change of one axis.

    Random realistic change of one axis for effect ``name`` (model-file keys); ``small``
    draws from the low end of the range (near the noise floor).
    """
    hi = 0.3 if small else 1.0

    def u(a, b):
        return float(a + (b - a) * rng.uniform(0.0, hi))
    if name == 'coulomb_friction':
        return {'coulomb_friction': u(4.0, 25.0)}
    if name == 'viscous_friction':
        return {'viscous_friction': axis['viscous_friction'] + u(20.0, 80.0)}
    if name == 'stiffness_nonlinearity':
        return {'stiffness_k2': axis['stiffness'] * u(1.3, 1.8),
                'stiffness_breakpoint': u(1.5e-4, 4e-4)}
    if name == 'backlash':
        return {'backlash': u(2e-5, 8e-5)}
    if name == 'torque_ripple':
        return {'torque_ripple': [{'amplitude': u(2.0, 8.0),
                                   'spatial_frequency': float(rng.uniform(60, 1500)),
                                   'phase': float(rng.uniform(-3, 3))}]}
    if name == 'time_delay':
        return {'time_delay': u(1e-3, 4e-3)}
    raise ValueError(f'{name=} is not one of {DRAWN}')


def draw_scene(rng: np.random.Generator, kind: str) -> dict[str, Any]:
    """
    Draw a random scene.

    A scene: {'scene': plug-in scene, 'truth': [(effect, axis index, params)], 'mode':
    (axis, Hz) or None, 'kind'}.
    """
    model = _nominal()
    axes = model['axes']
    truth: list[tuple[str, int, dict[str, Any]]] = []
    mode = None

    def add_random(k: int) -> None:
        used = {(t[0], t[1]) for t in truth}
        while len(truth) < k:
            name, ax = str(rng.choice(DRAWN)), int(rng.integers(3))
            if (name, ax) in used or (name == 'backlash' and any(
                    t[0] == 'stiffness_nonlinearity' and t[1] == ax for t in truth)):
                continue
            used.add((name, ax))
            truth.append((name, ax, draw_effect(name, rng, axes[ax])))
    if kind == 'random':
        add_random(int(rng.integers(1, 5)))
    elif kind == 'two_on_one_axis':
        ax = int(rng.integers(3))
        a, b = rng.choice(['coulomb_friction', 'torque_ripple', 'time_delay',
                           'stiffness_nonlinearity'], 2, replace=False)
        truth = [(str(a), ax, draw_effect(str(a), rng, axes[ax])),
                 (str(b), ax, draw_effect(str(b), rng, axes[ax]))]
    elif kind == 'weak_axis_small':
        truth = [('coulomb_friction', 1, draw_effect('coulomb_friction', rng, axes[1])),
                 ('coulomb_friction', 2, draw_effect('coulomb_friction', rng, axes[2],
                                                     small=True))]
    elif kind == 'gravity':
        # an axis the nominal model loads with a constant (its value at the operating point)
        # carries a link's weight G sin(q + phi) instead: the constant within 10 %, the
        # configuration dependence hidden (G from 1.2 to 4 times the load, either slope)
        ax = int(rng.choice([i for i, a in enumerate(axes) if a.get('gravity_torque')]))
        load = float(axes[ax]['gravity_torque']) * float(rng.uniform(0.9, 1.1))
        amp = abs(load) * float(rng.uniform(1.2, 4.0))
        phase = math.asin(load / amp)
        if rng.uniform() < 0.5:
            phase = math.pi - phase
        truth = [('gravity', ax, {'gravity': [{'amplitude': amp, 'phase': phase}],
                                  'gravity_torque': 0.0})]
        add_random(1 + int(rng.integers(0, 3)))      # and 0-2 other effects anywhere
    elif kind == 'mismatch':
        # as on every real robot, the nominal model's linear parameters are off: one axis'
        # stiffness 5-20 % either way, next to 1-2 drawn effects anywhere
        ax = int(rng.integers(3))
        scale = float(rng.uniform(1.05, 1.2)) ** (1 if rng.uniform() < 0.5 else -1)
        truth = [('parameter_mismatch', ax, {'stiffness': float(axes[ax]['stiffness']) * scale})]
        add_random(2 + int(rng.integers(0, 2)))      # the mismatch and 1-2 others
    elif kind == 'sensor_two':
        # two small effects of different kinds on two different axes
        ax = [int(a) for a in rng.choice(3, 2, replace=False)]
        names = [str(n) for n in rng.choice(DRAWN, 2, replace=False)]
        truth = [(n, a, draw_effect(n, rng, axes[a], small=True)) for n, a in zip(names, ax)]
    elif kind == 'second_mode':
        ax = int(rng.integers(3))
        mode = (ax, float(rng.uniform(18.0, 30.0)))
    elif kind in ('link_mode', 'link_mode_beside'):
        return _link_mode_scene(rng, kind, axes)
    sc: dict[str, Any] = {'axes': {}, 'velocity_noise': NOISE, 'seed': int(rng.integers(1e6))}
    if kind in ('sensor', 'sensor_two'):
        # every axis read by an encoder, its velocity the difference of two readings
        lo, hi = np.log(ENCODER_RANGE)
        sc['encoder_resolution'] = [float(np.exp(rng.uniform(lo, hi))) for _ in axes]
        sc['velocity_from_encoder'] = True
    for name, ax, ch in truth:
        sc['axes'].setdefault(str(ax), {}).update(ch)
    if mode:
        em = {'frequency_hz': mode[1], 'mass_ratio': float(rng.uniform(0.3, 0.5)),
              'damping_ratio': float(rng.uniform(0.01, 0.03))}
        sc['extra_mode'] = {str(mode[0]): em}
        # the mode in the model file's terms (docs/model_file.md): the inertia on the spring
        truth.append(('second_mode', mode[0], {'second_mode': {
            'frequency_hz': em['frequency_hz'], 'damping_ratio': em['damping_ratio'],
            'inertia': em['mass_ratio'] * axes[mode[0]]['link_inertia']}}))
    return {'scene': sc, 'truth': truth, 'mode': mode, 'kind': kind}


def _link_mode_scene(rng: np.random.Generator, kind: str, axes: list[dict[str, Any]]
                     ) -> dict[str, Any]:
    """
    Draw a scene with a second link-side mode (issue 57) on a random axis.

    ``link_mode_beside`` adds one drawn effect on another axis. The truth lists the mode as
    the effect ``second_mode`` with the model-file keys (docs/model_file.md): the reference
    plant takes ``mass_ratio`` of the link inertia onto the spring, the model file names that
    inertia.
    """
    ax = int(rng.integers(3))
    ratio = float(rng.uniform(*LINK_MODE_RATIO))
    hz = float(rng.uniform(*LINK_MODE_HZ))
    zeta = float(math.exp(rng.uniform(*np.log(LINK_MODE_DAMPING))))
    truth: list[tuple[str, int, dict[str, Any]]] = [
        ('second_mode', ax, {'second_mode': {'frequency_hz': hz, 'damping_ratio': zeta,
                                             'inertia': ratio * axes[ax]['link_inertia']}})]
    if kind == 'link_mode_beside':
        other = int(rng.choice([i for i in range(3) if i != ax]))
        name = str(rng.choice(DRAWN))
        truth.append((name, other, draw_effect(name, rng, axes[other])))
    sc: dict[str, Any] = {'axes': {}, 'velocity_noise': NOISE, 'seed': int(rng.integers(1e6))}
    for name, i, ch in truth[1:]:
        sc['axes'].setdefault(str(i), {}).update(ch)
    sc['extra_mode'] = {str(ax): {'frequency_hz': hz, 'mass_ratio': ratio,
                                  'damping_ratio': zeta}}
    return {'scene': sc, 'truth': truth, 'mode': (ax, hz), 'kind': kind}


def second_mode_hz(scene: dict[str, Any], ax: int) -> float:
    """
    Return the frequency of the resonance that the extra link-side mode adds.

    Frequency [Hz] of the resonance the extra link-side mode adds to axis ``ax`` (motor,
    rigid link part and the mode's mass as a free 3-mass chain, the highest of its two
    modes): what the measured FRF shows, not the spring's link-held tuning.
    """
    a = _nominal()['axes'][ax]
    em = scene['scene']['extra_mode'][str(ax)]
    me = em['mass_ratio'] * a['link_inertia']
    ke = me * (2 * math.pi * em['frequency_hz']) ** 2
    m = np.diag([a['motor_inertia'], a['link_inertia'] - me, me])
    k1 = a['stiffness']
    k = np.array([[k1, -k1, 0.0], [-k1, k1 + ke, -ke], [0.0, -ke, ke]])
    w2 = np.sort(np.real(np.linalg.eigvals(np.linalg.solve(m, k))))
    return float(math.sqrt(max(w2[-1], 0.0)) / (2 * math.pi))


def nominal_names() -> list[str]:
    return [a['name'] for a in _nominal()['axes']]


def scene_of(seed: int, k: int, kind: str | None = None) -> dict[str, Any]:
    """
    Return scene number ``k`` of the sweep that starts at ``seed``.

    Drawn as ``kind``, or as the cycle's kind when None.
    """
    return draw_scene(np.random.default_rng(seed + k), kind or KINDS[k % len(KINDS)])
