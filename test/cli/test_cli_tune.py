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
``frf-ident tune`` on the command line: its files, the recipe's ``loop``, and its refusals.

One FRF of config/model_3axis_resonant.yaml (its exact sampled FRF plus 1 % noise,
test/plants/campaign.py at scale 1 with the model file's own drives). tuned_model.yaml is a
model file the other commands load; ``loop --model tuned_model.yaml`` on the same FRF (the
second command of the recipe in docs/tune.md) reports the margins tune.json predicts, filters
included. Bad input: one line on stderr, exit status 2, nothing written.
"""
import json

from frf_ident.cli import main
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.io.export import write_frf
from frf_ident.io.model_file import load_model
import numpy as np
from plants.campaign import FREQ_HZ, measured, MODEL
import pytest
import yaml


@pytest.fixture(scope='module')
def frf_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp('tune_cli')
    (root / 'est').mkdir()
    write_frf(measured(load_model(MODEL)[1], 0.01, np.random.default_rng(2)),
              root / 'est' / 'frf.json')
    return root / 'est'


def test_tune_writes_its_files_and_loop_reads_the_tuned_model(frf_dir, tmp_path, capsys):
    out = tmp_path / 'tune'
    assert main(['tune', str(frf_dir), '--model', str(MODEL), '--out', str(out),
                 '--targets', 'crossover_hz=5', 'modulus_margin=0.55']) == 0
    said = capsys.readouterr().out
    assert 'targets: crossover 5 Hz' in said and 'model file controller' in said
    names = {p.name for p in out.iterdir()}
    assert {'tune.json', 'tune.html', 'tune.png', 'pid_controller.yaml', 'filters.yaml',
            'control_objects.pkl', 'tuned_model.yaml', 'tune.log'} <= names
    doc = json.loads((out / 'tune.json').read_text())
    assert doc['targets']['crossover_hz'] == 5.0 and doc['files']
    _, robot, ctrl = load_model(out / 'tuned_model.yaml')
    assert ctrl.n_sections >= 1
    for j, a in enumerate(doc['axes']):
        assert ctrl.kp[j] == a['setting']['kp'] and ctrl.ki[j] == a['setting']['ki']
        assert a['before']['nominal']['kp'] == 3000.0 * [1, 4 / 3, 0.8 / 1.5][j]
    assert main(['-q', 'loop', str(frf_dir), '--model', str(out / 'tuned_model.yaml'),
                 '--out', str(tmp_path / 'loop'), '--draws', '0']) == 0
    loop = json.loads((tmp_path / 'loop' / 'loop.json').read_text())['check']['axes']
    for lo, a in zip(loop, doc['axes']):
        for k in ('phase_margin_deg', 'modulus_margin', 'crossover_hz'):
            assert lo[k]['value'] == pytest.approx(a['margins']['nominal'][k]['value'],
                                                   rel=1e-9)
    page = (out / 'tune.html').read_text()
    for heading in ('Targets per axis', 'Filters (on the measured velocity',
                    'Margins of the tuned controller', 'Margins of the model file',
                    'Uncertainty weights'):
        assert heading in page, heading
    pid = yaml.safe_load((out / 'pid_controller.yaml').read_text())
    gains = pid['velocity_pid_controller']['ros__parameters']['gains']
    assert gains['joint_1']['u_clamp_max'] == robot.axes[0].torque_limit
    # run again: refused without --overwrite, nothing touched; with it, replaced
    before = (out / 'tune.json').stat().st_mtime_ns
    assert main(['tune', str(frf_dir), '--rate', '1000', '--out', str(out)]) == 2
    assert (out / 'tune.json').stat().st_mtime_ns == before
    assert main(['-q', 'tune', str(frf_dir), '--rate', '1000', '--out', str(out),
                 '--overwrite']) == 0
    assert not (out / 'tuned_model.yaml').exists()          # no model file this time


def _other_lines(root):
    frf = measured(load_model(MODEL)[1], 0.01, np.random.default_rng(3), FREQ_HZ[::2])
    (root / 'b').mkdir(parents=True)
    write_frf(frf, root / 'b' / 'frf.json')
    return root


def _one_channel(root):
    root.mkdir(parents=True)
    write_frf(FrequencyResponse(FREQ_HZ, 1.0 / (2j * np.pi * FREQ_HZ)), root / 'f.json')
    return root / 'f.json'


@pytest.mark.parametrize('argv, needle', [
    (['tune', 'FRF', '--out', 'OUT'], 'give --model'),
    (['tune', 'FRF', '--out', 'OUT', '--rate', '1000', '--targets', 'pm=45'],
     '--targets pm=45: expected KEY=VALUE'),
    (['tune', 'FRF', '--out', 'OUT', '--rate', '1000', '--targets', 'phase_margin_deg=x'],
     "'x' is not a number"),
    (['tune', 'FRF', '--out', 'OUT', '--rate', '1000', '--targets', 'modulus_margin=1.2'],
     'modulus_margin=1.2'),
    (['tune', 'FRF', '--out', 'OUT', '--rate', '1000', '--verify'], '--verify: needs --model'),
    (['tune', 'FRF', '--out', 'OUT', '--rate', '-5'], '--rate -5'),
    (['tune', 'FRF', '--out', 'OUT', '--rate', '1000', '--nominal', 'nope'],
     '--nominal nope: no such input'),
    (['tune', 'FRF', 'OTHER', '--out', 'OUT', '--rate', '1000'], 'expected the lines of'),
    (['tune', 'SISO', '--out', 'OUT', '--model', 'MODEL'], 'no axes'),
])
def test_bad_input_is_one_line_and_exit_2(frf_dir, tmp_path, capsys, argv, needle):
    subs = {'FRF': str(frf_dir), 'OUT': str(tmp_path / 'o'), 'MODEL': str(MODEL)}
    if 'OTHER' in argv:
        subs['OTHER'] = str(_other_lines(tmp_path / 'other') / 'b')
    if 'SISO' in argv:
        subs['SISO'] = str(_one_channel(tmp_path / 'siso'))
    assert main([subs.get(a, a) for a in argv]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1, err
    assert not (tmp_path / 'o' / 'tune.json').exists()
