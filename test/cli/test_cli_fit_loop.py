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
`frf-ident fit` and `frf-ident loop` end to end on an FRF file.

The FRF is the exact sampled FRF (zero-order hold, 1 kHz) of the Section 6 joint with viscous
friction, plus 1 % noise and that variance: the half-sample delay given with --delay makes
the continuous two-mass model right, so the fitted model.yaml must hold the true parameters
within 3 standard errors, and be a model file the other commands load.
"""
from __future__ import annotations

import json

from frf_ident.cli.main import main
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.model.params import AxisParams, RobotParams
from frf_ident.core.simulation.analytic import robot_frf_sampled
from frf_ident.io.export import write_frf
from frf_ident.io.model_file import load_model
import numpy as np
import pytest

TRUE = {'motor_inertia': 35.0, 'link_inertia': 150.0, 'stiffness': 1.5e5, 'damping': 400.0,
        'viscous_friction': 20.0}


@pytest.fixture(scope='module')
def frf_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp('est')
    robot = RobotParams([AxisParams(**TRUE)])
    f = np.arange(0.5, 40.01, 0.5)
    p = robot_frf_sampled(robot, f)
    var = (0.01 * np.abs(p)) ** 2
    rng = np.random.default_rng(5)
    pn = p + np.sqrt(var / 2) * (rng.standard_normal(p.shape) + 1j * rng.standard_normal(p.shape))
    write_frf(FrequencyResponse(f, pn, ['joint_1'], ['joint_1'], total_variance=var),
              d / 'frf.json')
    return d


def test_fit_physical_writes_a_model_file_with_the_true_parameters(frf_dir, tmp_path, capsys):
    out = tmp_path / 'fit'
    assert main(['fit', str(frf_dir), '--out', str(out), '--physical', '--delay', '0.0005']) == 0
    doc = json.loads((out / 'fit.json').read_text())
    (axis,) = doc['physical']
    for k, v in TRUE.items():
        assert abs(axis['parameters'][k] - v) <= 3 * axis['std'][k], (k, axis)
    assert not axis['cost']['structure_missing']
    _, robot, ctrl = load_model(out / 'model.yaml')
    assert robot.joint_names == ['joint_1'] and ctrl.kp.size == 1
    assert abs(robot.axes[0].stiffness / 1.5e5 - 1) < 0.01
    assert (out / 'fit.png').stat().st_size > 0
    text = capsys.readouterr().out
    assert 'stiffness' in text and 'residual explained by the noise' in text

    # the loop check takes the fitted model file's controller
    lo = tmp_path / 'loop'
    assert main(['loop', str(frf_dir), '--out', str(lo), '--model', str(out / 'model.yaml'),
                 '--draws', '20']) == 0
    check = json.loads((lo / 'loop.json').read_text())['check']
    assert check['discrete_dt'] == 0.001 and check['axes'][0]['phase_margin_deg']['std'] > 0


def test_fit_rational_writes_mat_and_the_chosen_order(frf_dir, tmp_path):
    out = tmp_path / 'fit'
    assert main(['fit', str(frf_dir), '--out', str(out), '--order', '3']) == 0
    doc = json.loads((out / 'fit.json').read_text())
    assert doc['rational']['order'] == 3 and (out / 'model.mat').is_file()
    assert doc['physical'] is None


@pytest.mark.parametrize('argv, needle', [
    (['fit', 'missing_dir/', '--out', 'OUT'], 'missing_dir'),
    (['fit', 'FRF', '--out', 'OUT', '--order', '0'], '--order 0'),
    (['loop', 'FRF', '--out', 'OUT', '--kp', '1'], '--kp and --ki'),
    (['loop', 'FRF', '--out', 'OUT', '--kp', '1', '2', '--ki', '1', '2'], 'expected 1 kp'),
])
def test_bad_input_is_one_line_and_exit_2(frf_dir, tmp_path, capsys, argv, needle):
    argv = [str(frf_dir) if a == 'FRF' else str(tmp_path / 'o') if a == 'OUT' else a
            for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1, err


def test_fit_physical_on_the_coupled_robot_writes_the_link_coupling(tmp_path):
    """The default robot's sampled 3x3 FRF (1 % noise): model.yaml gets the coupling."""
    from frf_ident.core.model.schema import default_robot
    robot = default_robot()
    f = np.arange(0.5, 40.01, 0.5)
    p = robot_frf_sampled(robot, f)
    var = (0.01 * np.abs(p)) ** 2
    rng = np.random.default_rng(6)
    pn = p + np.sqrt(var / 2) * (rng.standard_normal(p.shape) + 1j * rng.standard_normal(p.shape))
    write_frf(FrequencyResponse(f, pn, robot.joint_names, robot.joint_names, total_variance=var),
              tmp_path / 'frf.json')
    out = tmp_path / 'fit'
    assert main(['fit', str(tmp_path / 'frf.json'), '--out', str(out), '--physical',
                 '--delay', '0.0005']) == 0
    doc = json.loads((out / 'fit.json').read_text())
    assert not doc['coupled']['cost']['structure_missing']
    c = np.array(doc['coupled']['link_coupling'])
    sd = np.array(doc['coupled']['link_coupling_std'])
    assert np.all(np.abs(c - robot.link_coupling) <= 4 * sd + 1e-12)
    _, fitted, _ = load_model(out / 'model.yaml')
    assert np.allclose(fitted.link_coupling, c)
