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
`frf-ident estimate A B --compare-levels`: a hardening spring at two levels (issue 39).

A Duffing oscillator x'' + 2 zeta w x' + w^2 x + k3 x^3 = F (8 Hz, hardening), driven by the
same odd multisine at a low and a 6x higher level, integrated with a fine fixed step
(semi-implicit Euler at 16 kHz, decimated to 1 kHz). Truth from the physics, not our code:
at the low level the spring is linear; at the high level the resonance moves up, and odd
(not even) distortion rises far above the noise.
"""
import json

from frf_ident.bag import write_recording
from frf_ident.cli import main
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.core.recording import Recording
import numpy as np
import pytest

FS, SUB = 1000.0, 16


def _duffing(force, f_hz=8.0, zeta=0.03, k3=4e5):
    w, h = 2 * np.pi * f_hz, 1 / (FS * SUB)
    x = v = 0.0
    out = np.empty(force.size)
    for i, fi in enumerate(force):           # force held over the sample
        for _ in range(SUB):
            v += h * (fi - 2 * zeta * w * v - w * w * x - k3 * x ** 3)
            x += h * v
        out[i] = v
    return out


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    des = design_odd_multisine(2.0, 30.0, bound=1.0, resolution_hz=0.5, fs=FS)
    real = multisine_realisation(des, 1, np.random.default_rng(0), fs=FS)
    n = des.period_samples(FS)
    unit = np.tile(real.evaluate(np.arange(n) / FS)[0][:, 0], 4)
    rng = np.random.default_rng(1)
    paths = []
    for level in (1.0, 6.0):
        u = 50.0 * level * unit
        y = _duffing(u)
        y = y + 1e-5 * np.std(y) * rng.standard_normal(y.size)
        rec = Recording(np.arange(u.size) / FS, ['j'], np.zeros((u.size, 1)), y[:, None],
                        u[:, None])
        paths.append(write_recording(rec, tmp_path_factory.mktemp('lv') / f'level{level:g}'))
    return paths


def test_compare_levels_shows_mode_shift_and_odd_distortion_growth(bags, tmp_path, capsys):
    out = tmp_path / 'cmp'
    assert main(['estimate', *map(str, bags), '--compare-levels', '--out', str(out)]) == 0
    text = capsys.readouterr().out
    print(text)
    doc = json.loads((out / 'compare.json').read_text())
    (f_low, f_high), = doc['mode_shifts'][1][0]
    assert 7.5 < f_low < 8.5 and f_high > 1.02 * f_low        # hardening: the mode moves up
    odd = [d['odd'][0] for d in doc['distortion']]
    even = [d['even'][0] for d in doc['distortion']]
    assert odd[1] > odd[0] + 5 and odd[1] > 10           # grows with the level
    assert all(abs(e) < 3 for e in even)
    assert (out / 'compare.png').stat().st_size > 10_000
    assert (out / '1_level1' / 'frf.json').is_file() and (out / '2_level6' / 'frf.json').is_file()
    assert sum('level6 dq_m/j: |P| change' in line for line in text.splitlines()) == 1


def test_several_bags_without_compare_levels_are_a_campaign(bags, tmp_path):
    """Several bags without --compare-levels are estimated one by one (issue 42), not compared."""
    out = tmp_path / 'x'
    assert main(['estimate', *map(str, bags), '--out', str(out), '--jobs', '1']) == 0
    assert (out / 'summary.csv').is_file() and not (out / 'compare.json').exists()
