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
The independent reference plant against FlexibleJointPlant.

The independent reference plant (test/plants/reference.py) against FlexibleJointPlant: two
implementations written apart (RK4 + Karnopp vs exponential integrator + set-valued friction)
must agree where the physics is the same; and the gravity keys of the model file.
"""
from dataclasses import replace
from pathlib import Path

from frf_ident.core.model.schema import robot_from_dict, robot_to_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.errors import ModelFileError
from frf_ident.io.model_file import load_model
import numpy as np
from plants import reference
import pytest

ROOT = Path(__file__).resolve().parents[3]

MODEL = ROOT / 'config' / 'model_3axis.yaml'


def _compare(changes: dict[int, dict], substeps: int = 4, extra_mode: dict | None = None
             ) -> tuple[np.ndarray, np.ndarray]:
    model, robot, _ = load_model(MODEL)
    reference.SCENE = {'axes': {str(k): v for k, v in changes.items()},
                       'extra_mode': extra_mode or {}}
    try:
        ref = reference.ReferencePlant(model)
    finally:
        reference.SCENE = {}
    axes = list(robot.axes)
    for k, v in changes.items():
        axes[k] = replace(axes[k], **v)
    ours = FlexibleJointPlant(replace(robot, axes=axes, substeps=substeps))
    rng = np.random.default_rng(4)
    n = 2500
    u = (ours.equilibrium_torque() + 60 * rng.standard_normal((n, 3))
         + 40 * np.sin(0.01 * np.arange(n))[:, None])
    v_ref = np.array([ref.step(x)[1] for x in u])
    v_ours = ours.simulate(torque=u).velocity
    # step() returns the measurement at the end of the sample, simulate() at its start
    return v_ref[:-1], v_ours[1:]


def test_linear_plants_agree_to_rounding():
    a, b = _compare({})
    assert np.max(np.abs(a - b)) < 1e-6 * np.max(np.abs(b))


@pytest.mark.parametrize('changes', [
    {1: {'gravity': [{'amplitude': 250.0, 'phase': 0.4}]},
     2: {'gravity': [{'amplitude': 60.0, 'phase': -0.3, 'joints': ['joint_2', 'joint_3']}]}},
    {0: {'time_delay': 0.0027, 'torque_ripple': [{'amplitude': 5.0, 'spatial_frequency': 300.0,
                                                  'phase': 1.0}]}},
    {1: {'stiffness_k2': 4.5e5, 'stiffness_breakpoint': 3e-4}, 2: {'backlash': 5e-5}},
])
def test_nonlinear_effects_agree(changes):
    a, b = _compare(changes)
    # the two integrators differ at second order in the nonlinear torques (Heun vs RK4)
    assert np.sqrt(np.mean((a - b) ** 2)) < 5e-3 * np.std(b), np.abs(a - b).max()


def test_a_second_mode_agrees_with_the_reference_plants_extra_mode():
    """
    The model file's ``second_mode`` is the reference plant's ``extra_mode``, written apart.

    The reference plant takes ``mass_ratio`` of the link inertia out of the rigid link onto a
    spring tuned to ``frequency_hz`` with the link held; the model file names that inertia and
    the same frequency and damping ratio (docs/model_file.md). With the link coupling of the
    3-axis model and a torque on every axis.
    """
    link = load_model(MODEL)[1].axes[2].link_inertia
    mode = {'frequency_hz': 24.0, 'damping_ratio': 0.01}
    a, b = _compare({2: {'second_mode': dict(mode, inertia=0.2 * link)}},
                    extra_mode={'2': dict(mode, mass_ratio=0.2)})
    assert np.max(np.abs(a - b)) < 1e-6 * np.max(np.abs(b))
    c, _ = _compare({})
    assert np.max(np.abs(a - c)) > 1e-2 * np.max(np.abs(b))       # the mode shows


def test_second_mode_keys_round_trip_and_refusals():
    model, _, _ = load_model(MODEL)
    model['axes'][2]['second_mode'] = {'frequency_hz': 30, 'damping_ratio': 0.05,
                                       'inertia': 12}
    rob = robot_from_dict(model)
    assert robot_from_dict(robot_to_dict(rob)).axes[2].second_mode == rob.axes[2].second_mode
    assert 'second_mode' not in robot_to_dict(rob)['axes'][0]      # absent where there is none
    for bad, match in [({'frequency_hz': 30, 'damping_ratio': 0.05}, 'exactly'),
                       ({'frequency_hz': 30, 'damping_ratio': 0.05, 'inertia': 60}, 'below'),
                       ({'frequency_hz': -1, 'damping_ratio': 0.05, 'inertia': 6}, 'positive'),
                       ({'frequency_hz': 30, 'damping_ratio': '0.05', 'inertia': 6}, 'number')]:
        model['axes'][2]['second_mode'] = bad
        with pytest.raises(ModelFileError, match=rf'axes\[2\].second_mode|{match}'):
            robot_from_dict(model)


def test_coulomb_friction_agrees_to_the_noise_level():
    """Karnopp stick band vs exact stick-slip: the same friction up to ~1e-4 rad/s."""
    a, b = _compare({0: {'coulomb_friction': 15.0}})
    assert np.sqrt(np.mean((a - b) ** 2)) < 1e-4


def test_gravity_keys_round_trip_and_refusals():
    model, robot, _ = load_model(MODEL)
    model['axes'][2]['gravity'] = [{'amplitude': 50.0, 'phase': 0.1,
                                    'joints': ['joint_2', 'joint_3']}]
    rob = robot_from_dict(model)
    assert robot_from_dict(robot_to_dict(rob)).axes[2].gravity == rob.axes[2].gravity
    load = rob.gravity_load(np.array([0.0, 0.2, 0.3]))
    assert load[2] == pytest.approx(40.0 + 50.0 * np.sin(0.5 + 0.1))
    model['axes'][2]['gravity'] = [{'amplitude': 50.0, 'joints': ['joint_9']}]
    with pytest.raises(ModelFileError, match='joint_9'):
        robot_from_dict(model)
    model['axes'][2]['gravity'] = [{'amplitude': 50.0, 'offset': 1.0}]
    with pytest.raises(ModelFileError, match=r'axes\[2\].gravity\[0\].*offset'):
        robot_from_dict(model)
