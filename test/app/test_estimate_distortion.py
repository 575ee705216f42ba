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
`frf-ident estimate` shows the nonlinear distortion of an odd multisine record (issue 39).

A 10 Hz mode followed by a static cubic (y = x + c x^3, Wiener system, scipy's lfilter), an
odd multisine on sparse odd lines, 4 periods, white output noise: the cubic puts power on the
non-excited odd lines and none on the even lines (truth from the structure, not our code).
Before, estimate printed no distortion level and wrote no plot.
"""
import json

from frf_ident.bag import write_recording
from frf_ident.cli import main
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.core.recording import Recording
import numpy as np
import pytest
from scipy import signal

FS = 1000.0


def _bag(tmp_path, cubic):
    des = design_odd_multisine(1.0, 40.0, bound=1.0, resolution_hz=0.5, fs=FS)
    real = multisine_realisation(des, 1, np.random.default_rng(0), fs=FS)
    n = des.period_samples(FS)
    u = np.tile(real.evaluate(np.arange(n) / FS)[0][:, 0], 5)
    w = 2 * np.pi * 10.0
    b, a, _ = signal.cont2discrete(([w * w], [1, 0.4 * w, w * w]), 1 / FS, method='bilinear')
    x = signal.lfilter(b[0], a, u)
    x = x / np.std(x)
    y = x + cubic * x ** 3 + 1e-3 * np.random.default_rng(1).standard_normal(x.size)
    rec = Recording(np.arange(u.size) / FS, ['j'], np.zeros((u.size, 1)), y[:, None],
                    u[:, None])
    return write_recording(rec, tmp_path / f'cubic{cubic}')


@pytest.mark.parametrize('cubic', [0.0, 0.05])
def test_estimate_prints_and_plots_odd_and_even_levels(tmp_path, capsys, cubic):
    out = tmp_path / 'est'
    assert main(['estimate', str(_bag(tmp_path, cubic)), '--out', str(out)]) == 0
    text = capsys.readouterr().out
    print(text)
    lines = text.splitlines()
    head = next(k for k, x in enumerate(lines) if x.startswith('distortion above the noise'))
    assert lines[head + 1].split() == ['estimate', 'output', 'odd', 'even', 'excited']
    _, _, odd, even, _ = lines[head + 2].split()
    odd, even = float(odd), float(even)
    assert abs(even) < 3                          # no even nonlinearity: noise only
    if cubic:
        assert odd > 8                            # the cubic, above the noise
    else:
        assert abs(odd) < 3
    assert (out / 'distortion.png').stat().st_size > 10_000
    doc = json.loads((out / 'estimates.json').read_text())
    d = next(iter(doc.values()))['meta']['distortion']
    assert set(d['kind']) == {'excited', 'odd', 'even'} and d['units'] == ['rad/s']
    assert len(d['power'][0]) == len(d['freq_hz']) == len(d['noise'][0])
