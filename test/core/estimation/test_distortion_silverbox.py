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
Distortion levels per line on real data: the Silverbox odd multisine (issue 39).

The Silverbox (../shared/data/Silverbox, SNLS80mV, read in place) is a lightly damped
resonance near 73 Hz with a cubic spring in feedback, driven by 10 realisations of an odd
multisine that excites EVERY odd line up to 200 Hz (one period each). So the odd
nonlinear distortion falls on the excited lines themselves: it is the residual of the
realisations around the best linear response there. The noise level is the data's own floor
above the band (220-305 Hz, where odd and even lines lie at the same level: nothing but
noise). Truth from physics, not from our code: a cubic spring distorts most where the
displacement is largest, at the resonance, and adds nothing at even lines.
"""
from pathlib import Path

from frf_ident.core.estimation.distortion import distortion_lines
from frf_ident.core.estimation.spectra import periodic_spectra
import numpy as np
import pytest
from scipy.io import loadmat

SILVERBOX = (Path(__file__).resolve().parents[3].parent / 'shared' / 'data' / 'Silverbox'
             / 'SNLS80mV.mat')
FS = 1e7 / 2 ** 14         # [Hz] (SOURCE.md)
N = 8192                   # samples per period
EXCITED = np.arange(1, 2684, 2)    # every odd line up to 200 Hz

pytestmark = pytest.mark.skipif(not SILVERBOX.is_file(), reason='shared Silverbox data absent')


@pytest.fixture(scope='module')
def levels():
    """Per-line levels of V2 over the 10 realisations, lines up to Nyquist."""
    m = loadmat(SILVERBOX, squeeze_me=True)
    u, y = np.asarray(m['V1'], float), np.asarray(m['V2'], float)
    quiet = np.abs(u - np.median(u)) < 0.05 * np.std(u)
    run = np.convolve(quiet, np.ones(20), 'valid') == 20
    starts = [s for s in np.flatnonzero(run[:-1] & ~run[1:]) + 20 if 40000 < s < 120000]
    assert len(starts) == 10
    take = [slice(s + 492, s + 492 + N) for s in starts]
    bins = np.arange(1, N // 2)

    def spec(x):
        return [periodic_spectra(x[t][None, :, None], bins, axis=1) for t in take]
    first = distortion_lines(spec(y), bins, EXCITED, FS / N, ['V2'], units=['V'])
    floor = (first.freq_hz > 220) & (first.kind != 'excited')
    noise = np.median(first.power[0, floor])
    return distortion_lines(spec(y), bins, EXCITED, FS / N, ['V2'], units=['V'],
                            noise=np.full(1, noise), U=spec(u))


def test_odd_distortion_above_noise_peaks_at_the_resonance(levels):
    f, res = levels.freq_hz, levels.residual[0]

    def db(lo, hi):
        sel = (f > lo) & (f < hi) & (levels.kind == 'excited')
        return 10 * np.log10(np.median(res[sel] / levels.noise[0, sel]))
    at_res, low, high = db(60, 80), db(1, 50), db(100, 200)
    print('\n'.join(levels.summary()))
    print(f'nonlinear residual at the odd lines over the noise: 60-80 Hz {at_res:.1f} dB, '
          f'1-50 Hz {low:.1f} dB, 100-200 Hz {high:.1f} dB')
    assert levels.above_noise_db('residual')[0] > 6           # odd distortion above noise
    assert at_res > 30 and at_res > low + 15 and at_res > high + 20


def test_no_distortion_above_the_band(levels):
    """Above 220 Hz odd and even lines agree: the cubic's products stay near the band."""
    f = levels.freq_hz
    oob = f > 220
    odd = np.median(levels.power[0, oob & (levels.kind == 'odd')])
    even = np.median(levels.power[0, oob & (levels.kind == 'even')])
    assert abs(10 * np.log10(odd / even)) < 1.0


def test_levels_round_trip_and_summary(levels):
    from frf_ident.core.estimation.distortion import DistortionLines
    back = DistortionLines.from_dict(levels.to_dict())
    np.testing.assert_array_equal(back.power, levels.power)
    np.testing.assert_array_equal(back.kind, levels.kind)
    line, = levels.summary()
    assert line.startswith('V2: odd lines') and 'nonlinear residual' in line
