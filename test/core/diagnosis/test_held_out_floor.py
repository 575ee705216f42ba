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
The held-out chirp's noise floor at its own level, against the misfit noise alone gives.

The diagnosis holds out the chirp iteration before the one it fits; with two iterations
that is the first, at ``r_initial`` (1/60 of the fitted torque on the UR5e scene of
test/app/test_diagnose_mjcf.py). Its floor is the fitted one's times
:func:`frf_ident.core.diagnosis.experiments.floors.held_out_chirp_scale`. Checked here on
the 3-axis model with velocity noise: the true model, simulated noise-free on the recorded
reference, misfits the held-out chirp by about that factor more than the fitted one (the
ratio of the two terms is noise alone: the same model, the same estimator), over a few
noise seeds.
"""
from frf_ident.core.diagnosis.experiments.evaluator import Evaluator
from frf_ident.core.estimation.chirp_estimate import chirp_input_power, effective_input_power
from frf_ident.core.excitation.chirp_iteration import ChirpConfig
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.model.schema import default_model_dict, robot_from_dict
from frf_ident.core.simulation.controller import controller_from_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.core.simulation.runner import IdentificationConfig, run_identification
import numpy as np
import pytest

#: noise seeds of the Monte-Carlo check
SEEDS = range(4)


def test_effective_power_of_a_diagonal_and_a_flipped_input_matrix():
    """1 / sum_m |U^-1[m, j]|^2: |U_jj|^2 for a diagonal U; the eq. 26 flips halve nothing."""
    U = np.diag([2.0, 3.0]).astype(complex)[None]
    np.testing.assert_allclose(effective_input_power(U)[0], [4.0, 9.0])
    # two inputs of amplitude a in both experiments, input 2 flipped in experiment 2: each
    # input's power is 2 a^2 (two experiments each carry it)
    a = 1.5
    F = np.array([[[a, a], [a, -a]]], complex)
    np.testing.assert_allclose(effective_input_power(F)[0], [2 * a * a, 2 * a * a])
    U[0, 0, 0] = np.nan
    assert np.all(np.isnan(effective_input_power(U)))


@pytest.fixture(scope='module')
def runs():
    """Per seed: (held-out chirp term / fitted chirp term of the true model, predicted)."""
    d = default_model_dict()
    rob = robot_from_dict(d)
    ctrl = controller_from_dict(d, rob)
    for a in rob.axes:
        a.velocity_noise = 2e-3
    out = []
    for seed in SEEDS:
        plant = FlexibleJointPlant(rob)
        plant.reset(seed=seed)
        rec = run_identification(plant, ctrl.copy(), IdentificationConfig(
            MultisineConfig(n_realisations=2, n_periods=2),
            ChirpConfig(duration=6.0, max_iterations=2)))
        ev = Evaluator(rec, ctrl, jobs=1)
        measured = ev.terms(rob, held_out=True)['chirp'] / ev.terms(rob)['chirp']
        # the uniform mean over the lines of power_fit / power_held, beside the weighted one
        r = chirp_input_power(ev.fit)[1] / chirp_input_power(ev.val)[1]
        out.append((measured, ev.floors_held['chirp'] / ev.floors['chirp'],
                    np.nanmean(r, axis=0)))
    return out


def test_held_out_chirp_floor_follows_the_noise_of_the_weaker_iteration(runs):
    measured = np.array([r[0] for r in runs])
    predicted = np.array([r[1] for r in runs])
    uniform = np.array([r[2] for r in runs])
    ratio = np.exp(np.mean(np.log(measured / predicted), axis=0))
    print(f'held-out / fitted chirp term of the true model over {len(runs)} noise seeds, per '
          f'axis (geometric mean): measured {np.exp(np.mean(np.log(measured), 0)).round(1)}, '
          f'predicted {np.exp(np.mean(np.log(predicted), 0)).round(1)}, uniform mean of the '
          f'power ratio {np.exp(np.mean(np.log(uniform), 0)).round(1)}; measured / predicted '
          f'{ratio.round(2)}')
    # the held-out iteration is far weaker: a floor borrowed from the fitted one is far off
    assert np.all(predicted > 20)
    # and the predicted factor is within 2x of what noise alone does, on every axis
    assert np.all(np.abs(np.log(ratio)) < np.log(2.0)), ratio
    # the line weights matter: the uniform mean is farther from what noise does on every axis
    off_uniform = np.abs(np.mean(np.log(measured / uniform), axis=0))
    assert np.all(off_uniform > np.abs(np.log(ratio))), (off_uniform, ratio)
