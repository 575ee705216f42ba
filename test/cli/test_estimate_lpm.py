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
`frf-ident estimate` on records whose excitation is neither a multisine nor a chirp.

Issue 39: a closed-loop record driven by a PRBS on the velocity reference was refused with
"no multisine or chirp found ... pass the experiment descriptors or the excitation as
options", and no option could describe it. Now the Local Polynomial Method estimates it, on a
bag (in memory and streamed alike) and on a CSV imported through a map; the truth is the
analytic FRF of the simulated 3-axis robot.
"""
import json

from frf_ident.bag import write_recording
from frf_ident.cli import main
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.model.schema import default_model_dict, robot_from_dict
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.analytic import robot_frf_sampled
from frf_ident.core.simulation.controller import controller_from_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
import numpy as np
import pytest
from scipy import signal

N = 12000                    # 12 s at 1 kHz


@pytest.fixture(scope='module')
def prbs(tmp_path_factory):
    """Return (robot, recording, bag): PRBS on r of all three axes, 40 dB SNR, from rest."""
    d = default_model_dict()
    rob = robot_from_dict(d)
    ctrl = controller_from_dict(d, rob)
    rng = np.random.default_rng(7)
    bits = [signal.max_len_seq(16, state=rng.integers(0, 2, 16))[0][:N // 4] for _ in range(3)]
    r = np.repeat(2.0 * np.array(bits, dtype=float).T - 1.0, 4, axis=0) * 0.01
    plant = FlexibleJointPlant(rob)
    quiet = plant.simulate(reference=r, controller=ctrl.copy())
    for axis, rms in zip(rob.axes, np.std(quiet.velocity, axis=0) / 100.0):
        axis.velocity_noise = float(rms)
    plant = FlexibleJointPlant(rob)
    res = plant.simulate(reference=r, controller=ctrl.copy())
    rec = Recording(res.t, rob.joint_names, res.position, res.velocity, res.effort,
                    res.reference, None, [], {})
    bag = write_recording(rec, tmp_path_factory.mktemp('lpm') / 'prbs_bag')
    return rob, rec, bag


def _in_band_error(rob, frf):
    band = (frf.freq_hz > 2) & (frf.freq_hz < 70)
    truth = robot_frf_sampled(rob, frf.freq_hz[band])
    d = range(3), range(3)
    return np.median(np.abs(frf.response[..., band][d] / truth[d] - 1))


def test_prbs_bag_is_estimated_by_the_lpm_not_refused(prbs, tmp_path, capsys):
    rob, _, bag = prbs
    out = tmp_path / 'o'
    assert main(['estimate', str(bag), '--out', str(out)]) == 0
    text = capsys.readouterr().out
    line = [s for s in text.splitlines() if 'Local Polynomial Method' in s]
    print('\n'.join(s for s in text.splitlines() if s.startswith('detected:')))
    assert len(line) == 1
    assert 'indirect through the velocity reference r of joint_1, joint_2, joint_3' in line[0]
    # every DFT line is estimated but those the PRBS leaves without excitation (its spectral
    # nulls), which are dropped and counted
    import re
    kept = int(re.search(r'(\d+) lines', line[0]).group(1))
    gone = re.search(r'(\d+) line\(s\) with less than', line[0])
    assert kept + (int(gone.group(1)) if gone else 0) == N // 2 and kept > 0.8 * (N // 2)
    doc = json.loads((out / 'frf.json').read_text())
    assert doc['estimate'] == 'lpm'
    frf = FrequencyResponse.from_dict(doc)
    assert frf.noise_variance is not None
    est = json.loads((out / 'estimates.json').read_text())
    assert sorted(est) == ['lpm', 'lpm_h1']
    coherence = np.asarray(est['lpm_h1']['meta']['coherence'])
    assert coherence.shape == (3, len(est['lpm_h1']['freq_hz']))
    err = _in_band_error(rob, frf)
    print(f'LPM diagonal median relative error 2-70 Hz: {100 * err:.3f} %')
    assert err < 0.01


def test_streamed_equals_in_memory(prbs, tmp_path):
    _, _, bag = prbs
    frfs = []
    for mode in ([], ['--stream']):
        out = tmp_path / f'o{len(mode)}'
        assert main(['estimate', str(bag), '--out', str(out), '--window', '5', *mode]) == 0
        frfs.append(FrequencyResponse.from_dict(json.loads((out / 'frf.json').read_text())))
    a, b = frfs
    assert a.meta['frames'] == b.meta['frames'] == 2       # 5 s blocks: frames of 5 s
    np.testing.assert_allclose(a.response, b.response, rtol=1e-9, atol=0)


def test_csv_through_a_map_is_estimated_by_the_lpm(prbs, tmp_path, capsys):
    rob, rec, _ = prbs
    table = np.column_stack([rec.t, rec.position, rec.velocity, rec.effort, rec.reference])
    names = (['t'] + [f'q{j}' for j in range(3)] + [f'v{j}' for j in range(3)]
             + [f'u{j}' for j in range(3)] + [f'r{j}' for j in range(3)])
    csv = tmp_path / 'prbs.csv'
    np.savetxt(csv, table, delimiter=',', header=','.join(names), comments='')
    joints = '\n'.join(f'  - name: {n}\n    position: {{column: q{j}}}\n'
                       f'    velocity: {{column: v{j}}}\n    effort: {{column: u{j}}}\n'
                       f'    reference: {{column: r{j}}}' for j, n in enumerate(rec.joint_names))
    (tmp_path / 'map.yaml').write_text(
        f'frf_ident_map: 1\ntime:\n  column: t\njoints:\n{joints}\n')
    bag = tmp_path / 'bag'
    assert main(['import', str(csv), '--map', str(tmp_path / 'map.yaml'), '--out', str(bag)]) == 0
    assert main(['estimate', str(bag), '--out', str(tmp_path / 'o')]) == 0
    assert 'Local Polynomial Method' in capsys.readouterr().out
    frf = FrequencyResponse.from_dict(json.loads((tmp_path / 'o' / 'frf.json').read_text()))
    assert _in_band_error(rob, frf) < 0.01


def test_method_lpm_with_a_chirp_is_refused(prbs, capsys):
    _, _, bag = prbs
    assert main(['estimate', str(bag), '--out', str(bag.parent / 'x'), '--method', 'lpm',
                 '--chirp', '1', '10', '--chirp-time', '0', '5']) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and "method='lpm'" in err and str(bag) in err
