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
`frf-ident estimate --method lpm` on a linear down-sweep: what the chirp refusal points to.

Issue 39: a linear 15 -> 2 Hz sine sweep is not the exponential chirp of eq. 16; given as
`--chirp 2 15 --chirp-time ...` it is refused (before: an FRF 10-14 dB off). The refusal now
says what works, `--method lpm`; this test checks that it does: the LPM of the bag against the
analytic FRF of the simulated 6 Hz mode (scipy.signal.lfilter of a bilinear-discretised
second-order system, so the truth is exact at every line).
"""
import json

from frf_ident.bag import write_recording
from frf_ident.cli import main
from frf_ident.core.recording import Recording
import numpy as np
import pytest
from scipy import signal

FS = 100.0
T_END = 60.0                 # s of sweep, then 10 s quiet: 7000 samples


def _mode(f_hz=6.0, zeta=0.05):
    w = 2 * np.pi * f_hz
    b, a, _ = signal.cont2discrete(([w * w], [1, 2 * zeta * w, w * w]), 1 / FS,
                                   method='bilinear')
    return b[0], a


@pytest.fixture(scope='module')
def sweep_bag(tmp_path_factory):
    """Bag of a linear 15 -> 2 Hz sweep on the torque of one joint, 0.1 % output noise."""
    t = np.arange(0, T_END + 10.0, 1 / FS)
    u = np.where(t <= T_END, signal.chirp(t, 15.0, T_END, 2.0, method='linear'), 0.0)
    y = signal.lfilter(*_mode(), u)
    y = y + 1e-3 * np.std(y) * np.random.default_rng(0).standard_normal(t.size)
    rec = Recording(t, ['j'], np.zeros((t.size, 1)), y[:, None], u[:, None])
    return write_recording(rec, tmp_path_factory.mktemp('sweep') / 'bag')


def test_given_linear_sweep_refusal_names_what_works(sweep_bag, capsys):
    out = sweep_bag.parent / 'given'
    assert main(['estimate', str(sweep_bag), '--out', str(out), '--chirp', '2', '15',
                 '--chirp-time', '0', str(T_END)]) == 2
    err = capsys.readouterr().err
    print(err)
    assert err.count('\n') == 1 and str(sweep_bag) in err
    assert 'linear sweep 15 -> 2' in err and '--method lpm' in err
    assert not out.exists()


def test_method_lpm_gives_the_analytic_frf_of_a_linear_down_sweep(sweep_bag):
    out = sweep_bag.parent / 'lpm'
    assert main(['estimate', str(sweep_bag), '--out', str(out), '--method', 'lpm']) == 0
    d = json.loads((out / 'frf.json').read_text())
    f = np.array(d['freq_hz'])
    P = (np.array(d['re']) + 1j * np.array(d['im']))[0, 0]
    z = np.exp(2j * np.pi * f / FS)
    b, a = _mode()
    err_db = np.abs(20 * np.log10(np.abs(P * np.polyval(a, z) / np.polyval(b, z))))
    band = (f > 3) & (f < 14)                   # inside the sweep, away from its ends
    q = np.percentile(err_db[band], [50, 90])
    print(f'LPM of the linear 15 -> 2 Hz sweep, 3-14 Hz: {band.sum()} lines, median '
          f'{q[0]:.4f} dB, 90 % {q[1]:.3f} dB from the analytic FRF')
    assert d['meta']['method'] == 'lpm_direct'
    assert q[0] < 0.02 and q[1] < 0.2
