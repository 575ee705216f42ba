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
``frf-ident tune --modes rational`` on measured FRFs of ../shared/data.

The DaISy flexible arm (torque -> arm acceleration, H1 of 8 Hann segments with the coherence
variance, 0.005-0.2 cycles/sample, controller rate 1 cycle/sample) and the Silverbox BLA (10
realisations, its total variance; the rate of its record, 610.35 Hz), as
test/core/fit/test_fit_rational.py builds them. For every lightly damped mode the rational fit
finds, the notch placed there has its discrete minimum (scipy's sosfreqz on a 1e-5 grid:
Tustin prewarped at the centre) within 2 standard errors of the mode's frequency; printed
beside the FRF's largest line near the mode.
"""
import json
from pathlib import Path

from frf_ident.cli import main
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.spectra import best_linear_approximation, periodic_spectra
from frf_ident.core.loop.notch import design_notch, NOTCH_WIDTHS
from frf_ident.io.export import write_frf
import numpy as np
import pytest
from scipy import signal
from scipy.io import loadmat

SHARED_DATA = Path(__file__).resolve().parents[2].parent / 'shared' / 'data'
DAISY = SHARED_DATA / 'DaISy_robot_arm' / 'robot_arm.dat'
SILVERBOX = SHARED_DATA / 'Silverbox' / 'SNLS80mV.mat'
SILVERBOX_FS = 1e7 / 2 ** 14


def _daisy(path):
    d = np.loadtxt(DAISY)
    u, y = d[:, 0], d[:, 1]
    opts = {'fs': 1.0, 'nperseg': 128, 'noverlap': 0, 'window': 'hann'}
    f, puu = signal.welch(u, **opts)
    _, pyy = signal.welch(y, **opts)
    _, puy = signal.csd(u, y, **opts)
    h, coh = puy / puu, np.abs(puy) ** 2 / (puu * pyy)
    var = (1 - coh) / (coh * (len(u) // 128)) * np.abs(h) ** 2
    k = (f > 0.005) & (f < 0.2)
    write_frf(FrequencyResponse(f[k], h[k], inputs=['torque'], outputs=['acceleration'],
                                total_variance=var[k].reshape(1, 1, -1)), path)
    return f[k], h[k]


def _silverbox(path):
    n, lines = 8192, np.arange(1, 2684, 2)
    m = loadmat(SILVERBOX, squeeze_me=True)
    u, y = np.asarray(m['V1'], float), np.asarray(m['V2'], float)
    quiet = np.abs(u - np.median(u)) < 0.05 * np.std(u)
    run = np.convolve(quiet, np.ones(20), 'valid') == 20
    starts = [s for s in np.flatnonzero(run[:-1] & ~run[1:]) + 20 if 40000 < s < 120000]
    take = [slice(s + 492, s + 492 + n) for s in starts]

    def spec(x):
        return periodic_spectra(np.array([x[t] for t in take])[:, None, :, None, None], lines,
                                axis=2)
    bla = best_linear_approximation(spec(y), spec(u))
    f = lines * SILVERBOX_FS / n
    write_frf(FrequencyResponse(f, bla.response[0, 0], inputs=['u'], outputs=['y'],
                                total_variance=bla.total_variance[0, 0].reshape(1, 1, -1)), path)
    return f, bla.response[0, 0]


def _check(out, f, h, rate, name):
    doc = json.loads((out / 'tune.json').read_text())
    (axis,) = doc['axes']
    assert axis['bands'], 'no lightly damped mode found'
    for b, in zip(axis['bands']):
        (mode,) = [m for m in axis['modes'][0] if b['low_hz'] <= m['frequency_hz'] <= b['high_hz']]
        fm, se = mode['frequency_hz'], mode['frequency_std_hz']
        near = np.abs(f / fm - 1) < 0.15
        peak = f[near][np.argmax(np.abs(h[near]))]
        chosen = [x for x in axis['setting']['filters'] if x['kind'] == 'notch'
                  and b['low_hz'] <= x['frequency_hz'] <= b['high_hz']]
        candidates = [design_notch(b['low_hz'], b['high_hz'], b['damping'], z, rate).sos
                      for z in NOTCH_WIDTHS if z > 1.5 * max(b['damping'], 1e-9)]
        sos = [np.array(x['discrete']['sos']) for x in chosen] + candidates
        grid = np.linspace(fm - 10 * se, fm + 10 * se, 20001)
        resp = [np.abs(signal.sosfreqz(s.reshape(1, 6), worN=grid, fs=rate)[1]) for s in sos]
        minima = [grid[np.argmin(r)] for r in resp]
        print(f'{name}: mode {fm:.5g} +- {se:.2g} (damping {mode["damping"]:.4f}); notch '
              f'minima {", ".join(f"{x:.5g}" for x in minima[:len(chosen) or 1])}'
              f'{" (chosen by tune)" if chosen else " (candidate; tune chose other filters)"}; '
              f'FRF peak line {peak:.5g}')
        assert all(abs(x - fm) <= 2 * se for x in minima), (minima, fm, se)
    return doc


@pytest.mark.skipif(not DAISY.is_file(), reason='no DaISy arm data')
def test_daisy_arm_notches_at_its_two_modes(tmp_path):
    f, h = _daisy(tmp_path / 'daisy.json')
    assert main(['tune', str(tmp_path / 'daisy.json'), '--rate', '1', '--modes', 'rational',
                 '--out', str(tmp_path / 'out')]) == 0
    doc = _check(tmp_path / 'out', f, h, 1.0, 'DaISy arm [cycles/sample]')
    assert len(doc['axes'][0]['bands']) == 2


@pytest.mark.skipif(not SILVERBOX.is_file(), reason='no Silverbox data')
def test_silverbox_notch_at_its_resonance(tmp_path):
    f, h = _silverbox(tmp_path / 'silverbox.json')
    assert main(['tune', str(tmp_path / 'silverbox.json'), '--rate', str(SILVERBOX_FS),
                 '--modes', 'rational', '--order', '2', '--out', str(tmp_path / 'out')]) == 0
    _check(tmp_path / 'out', f, h, SILVERBOX_FS, 'Silverbox BLA [Hz]')
