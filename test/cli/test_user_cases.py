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
The five user cases of issue 54: each gives a working result or a refusal naming the fix.

1. `fit` of the Silverbox BLA on 1-150 Hz: a stable model, every mode inside the band, the
   orders tried with their costs and the runner-up printed (it chose order 12 with unstable
   pole pairs, and said nothing).
2. `fit --physical` of the demo robot's FRF with a vanishing variance (the cost test fails by
   orders of magnitude): errors that cover the true parameters, the coupled lines labelled
   with units, the delay printed as model.yaml's time_delay, the base model named.
3. `loop --propose` on the demo robot's FRF: the missed phase margin said with by how much,
   no "inf" gain margin where |L| stays above 1 to the band edge, and an out-of-band
   bandwidth refused naming an option that exists.
4. `estimate` of the DaISy arm (1024 samples at 1 s): estimated without options (the block
   window scales with the record), with `--method lpm` too, and a too short `--window`
   refused naming the one that works.
5. Docs and labels: `import --help` names a file that exists, `--version`, and the DaISy
   record (torque -> acceleration, no robot) described by the map's names.

Truth: the Silverbox measurement and the DaISy record (../shared/data, read in place), the
exact sampled FRF of the demo robot (config/robot_3axis_demo.yaml's linear part).
"""
from __future__ import annotations

import json
from pathlib import Path
import re

from core.fit.test_fit_rational import DAISY, SILVERBOX, silverbox_bla
from frf_ident.cli.main import build_parser, main
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.excitation.multisine import design_odd_multisine
from frf_ident.core.fit.physical import PARAMETERS
from frf_ident.core.simulation.analytic import robot_frf_sampled
from frf_ident.io.export import write_frf
from frf_ident.io.model_file import load_model
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def demo_frf(folder: Path, relative_sd: float, seed: int = 1) -> Path:
    """Write the demo robot's exact sampled FRF with noise of that relative SD; return it."""
    _, robot, _ = load_model(ROOT / 'config' / 'robot_3axis_demo.yaml')
    f = design_odd_multisine(2.0, 60.0, bound=0.01, resolution_hz=0.5, fs=1000.0).freq_hz
    p = robot_frf_sampled(robot, f)
    var = (relative_sd * np.abs(p)) ** 2
    rng = np.random.default_rng(seed)
    pn = p + np.sqrt(var / 2) * (rng.standard_normal(p.shape) + 1j * rng.standard_normal(p.shape))
    names = robot.joint_names
    folder.mkdir(parents=True, exist_ok=True)
    write_frf(FrequencyResponse(f, pn, [f'tau_m/{n}' for n in names],
                                [f'dq_m/{n}' for n in names], total_variance=var),
              folder / 'frf.json')
    return folder


@pytest.mark.skipif(not (SILVERBOX / 'SNLS80mV.mat').is_file(), reason='no Silverbox data')
def test_case1_silverbox_fit_is_stable_with_its_modes_in_the_band(tmp_path, capsys):
    f, g, var = silverbox_bla()
    est = tmp_path / 'silverbox'
    est.mkdir()
    write_frf(FrequencyResponse(f, g.reshape(1, 1, -1), ['V1'], ['V2'],
                                total_variance=var.reshape(1, 1, -1)), est / 'frf.json')
    out = tmp_path / 'fit'
    assert main(['fit', str(est), '--band', '1', '150', '--out', str(out)]) == 0
    said = capsys.readouterr().out
    rat = json.loads((out / 'fit.json').read_text())['rational']
    with capsys.disabled():
        print('\n'.join(line for line in said.splitlines() if line.strip().startswith(
            ('mode', 'order', 'tried', 'runner-up', 'not admissible'))))
    assert np.all(np.roots(rat['den']).real < 0)
    modes = [m for m in rat['modes'] if m['damping'] < 1]
    assert modes and all(1.0 <= m['frequency_hz'] <= 150.0 and m['in_band']
                         and not m['at_limit'] for m in modes)
    assert 'chosen by the' in said and 'tried (order: cost, cost/dof)' in said
    assert 'runner-up: order' in said and rat['runner_up'] is not None
    assert len(rat['tried']) == 12 and 'OUTSIDE' not in said


def test_case2_physical_fit_errors_cover_the_truth_and_say_their_units(tmp_path, capsys):
    _, robot, _ = load_model(ROOT / 'config' / 'robot_3axis_demo.yaml')
    est = demo_frf(tmp_path / 'est', 1e-6)
    out = tmp_path / 'fit'
    assert main(['fit', str(est), '--physical', '--out', str(out), '--no-figure']) == 0
    said = capsys.readouterr().out
    doc = json.loads((out / 'fit.json').read_text())
    c = doc['coupled']
    assert c['cost']['structure_missing'] and c['cost']['ratio'] > 1e4
    for i, axis in enumerate(robot.axes):
        got, sd = c['axes'][i]['parameters'], c['axes'][i]['std_reported']
        for k in PARAMETERS:
            assert abs(got[k] - getattr(axis, k)) <= 2 * sd[k], (axis.name, k, got[k], sd[k])
    coupling = np.array(c['link_coupling'])
    assert np.all(np.abs(coupling - robot.link_coupling)
                  <= 2 * np.array(c['link_coupling_std_reported']) + 1e-12)
    # every coupled line is labelled, parameters with units; a verdict per fit
    coupled = [line.strip() for line in said.splitlines() if 'coupled:' in line]
    assert any('link_inertia' in line and 'kg m^2' in line for line in coupled)
    assert any(line.startswith('coupled: link coupling [kg m^2]') for line in coupled)
    assert 'coupled: structure missing: treat errors as lower bounds' in said
    # the delay on the console is model.yaml's time_delay, in the same convention
    ms = float(re.search(r'coupled: time_delay ([-0-9.e+]+) \+-', said).group(1))
    _, fitted, _ = load_model(out / 'model.yaml')
    assert abs(fitted.axes[0].time_delay * 1e3 - ms) <= 1e-3 * max(abs(ms), 1e-3)
    assert abs(c['time_delay_s'] - fitted.axes[0].time_delay) < 1e-12
    # the keys the fit does not give: from which model
    assert 'from the default model' in said and 'give --model M.yaml' in said
    assert 'from the default model' in (out / 'model.yaml').read_text()


def test_case3_loop_propose_says_what_is_missed(tmp_path, capsys):
    est = demo_frf(tmp_path / 'est', 0.005)
    model = str(ROOT / 'config' / 'model_3axis.yaml')
    assert main(['loop', str(est), '--model', model, '--propose', '20', '60', '--draws', '10',
                 '--out', str(tmp_path / 'l20')]) == 0
    said = capsys.readouterr().out
    assert re.search(r'joint_2: target missed: phase margin [0-9.]+ deg, [0-9.]+ deg below the '
                     r'60 deg target', said), said
    gains = json.loads((tmp_path / 'l20' / 'loop.json').read_text())['proposal']['gains']
    assert not gains[1]['targets_met'] and gains[1]['missed']
    assert 'target missed' in (tmp_path / 'l20' / 'loop.html').read_text()
    assert main(['loop', str(est), '--model', model, '--propose', '5', '60', '--draws', '10',
                 '--out', str(tmp_path / 'l5')]) == 0
    said = capsys.readouterr().out
    assert ' inf dB' not in said and 'no gain margin within the measured band' in said
    assert re.search(r'joint_1: target missed: .*\|L\| is \+[0-9.]+ dB at the band edge', said)
    page = (tmp_path / 'l5' / 'loop.html').read_text()
    assert 'at the band edge' in page and 'inf' not in re.sub(r'<[^>]+>', ' ', page).split()
    # a bandwidth below the band: refused, naming an option that exists
    assert main(['loop', str(est), '--propose', '2', '60', '--out', str(tmp_path / 'l2')]) == 2
    err = capsys.readouterr().err
    assert '--propose 2 60' in err and 'outside the measured band' in err, err
    loop = next(a for a in build_parser()._actions if a.dest == 'command').choices['loop']
    options = {o for a in loop._actions for o in a.option_strings}
    assert set(re.findall(r'--[a-z][a-z-]*', err)) <= options, err


@pytest.fixture(scope='module')
def daisy_bag(tmp_path_factory):
    if not (DAISY / 'robot_arm.dat').is_file():
        pytest.skip('no DaISy arm data')
    bag = tmp_path_factory.mktemp('daisy') / 'bag'
    assert main(['import', str(DAISY / 'robot_arm.dat'), '--map',
                 str(ROOT / 'config' / 'map_daisy_arm.yaml'), '--out', str(bag)]) == 0
    return bag


def test_case4_daisy_arm_estimates_or_names_the_window(daisy_bag, tmp_path, capsys):
    assert main(['estimate', str(daisy_bag), '--out', str(tmp_path / 'e')]) == 0
    assert main(['estimate', str(daisy_bag), '--method', 'lpm',
                 '--out', str(tmp_path / 'lpm')]) == 0
    frf = json.loads((tmp_path / 'e' / 'frf.json').read_text())
    assert len(frf['freq_hz']) > 100 and max(frf['freq_hz']) < 0.5
    capsys.readouterr()
    assert main(['estimate', str(daisy_bag), '--window', '300',
                 '--out', str(tmp_path / 'w300')]) == 2
    err = capsys.readouterr().err
    assert '--window 1024' in err, err
    # and a fit of the estimate keeps its modes inside the band
    assert main(['fit', str(tmp_path / 'e'), '--out', str(tmp_path / 'fit')]) == 0
    rat = json.loads((tmp_path / 'fit' / 'fit.json').read_text())['rational']
    lo, hi = min(frf['freq_hz']), max(frf['freq_hz'])
    assert all(lo <= m['frequency_hz'] <= hi for m in rat['modes'] if m['damping'] < 1)


def test_case5_help_points_to_files_and_labels_follow_the_map(daisy_bag, tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(['import', '--help'])
    text = capsys.readouterr().out
    named = re.findall(r'docs/[\w.]+\.md', text)
    assert named and all((ROOT / n).is_file() for n in named), named
    assert 'README' not in text
    with pytest.raises(SystemExit):
        main(['--version'])
    assert capsys.readouterr().out.startswith('frf-ident ')
    # a record that is no robot's: no derived position of the sensor, the input by its name
    assert main(['import', str(DAISY / 'robot_arm.dat'), '--map',
                 str(ROOT / 'config' / 'map_daisy_arm.yaml'), '--out', str(tmp_path / 'b')]) == 0
    said = capsys.readouterr().out
    assert 'trapezoidal integral' not in said and 'arm.position' not in said, said
    assert main(['estimate', str(daisy_bag), '--out', str(tmp_path / 'e')]) == 0
    said = capsys.readouterr().out
    assert 'direct, input torque' in said and 'torque of torque' not in said, said
