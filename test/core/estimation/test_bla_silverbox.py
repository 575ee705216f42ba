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
The multisine BLA (eq. 14) and its variance on real measured data: the Silverbox.

The Silverbox (Wigren & Schoukens 2013, ../shared/data/Silverbox, read in place) is an
electronic Duffing oscillator: a lightly damped resonance with a cubic spring in feedback.
SNLS80mV holds 10 realisations of an odd random-phase multisine (every odd line of 8192,
0.07-200 Hz), each preceded by 500 samples of its own periodic tail and separated by short
quiet gaps. One period per realisation, so the total variance (noise plus the stochastic
nonlinear distortions) is all the BLA can report; the truth it is checked against was not
produced by our code: the data's other realisations, scipy's Welch estimate, the physics.
"""
from pathlib import Path

from frf_ident.core.estimation.spectra import best_linear_approximation, periodic_spectra
import numpy as np
import pytest
from scipy import signal, stats
from scipy.io import loadmat

SILVERBOX = (Path(__file__).resolve().parents[3].parent / 'shared' / 'data' / 'Silverbox'
             / 'SNLS80mV.mat')
FS = 1e7 / 2 ** 14         # [Hz] (SOURCE.md)
N = 8192                   # samples per period
LINES = np.arange(1, 2684, 2)    # the excited odd lines, up to 200 Hz
#: z^2 of two 5-realisation BLAs with their estimated variances, when these are right
NULL = stats.f(2, 16)

pytestmark = pytest.mark.skipif(not SILVERBOX.is_file(), reason='shared Silverbox data absent')


@pytest.fixture(scope='module')
def periods():
    """Return (u, y), shape (10, N): one steady-state period of each realisation."""
    m = loadmat(SILVERBOX, squeeze_me=True)
    u, y = np.asarray(m['V1'], float), np.asarray(m['V2'], float)
    # a realisation starts where a quiet run (the generator's offset, 20+ samples) ends
    quiet = np.abs(u - np.median(u)) < 0.05 * np.std(u)
    run = np.convolve(quiet, np.ones(20), 'valid') == 20
    starts = [s for s in np.flatnonzero(run[:-1] & ~run[1:]) + 20 if 40000 < s < 120000]
    assert len(starts) == 10 and np.all(np.abs(np.diff(starts) - 8692) <= 3)
    # skip the 500-sample tail (the resonance has settled), less a margin for the start
    take = [slice(s + 492, s + 492 + N) for s in starts]
    return np.array([u[t] for t in take]), np.array([y[t] for t in take])


def _bla(u, y):
    """Return the BLA result of periods u, y (n_p, N), one period per realisation."""
    def spec(x):
        return periodic_spectra(x[:, None, :, None, None], LINES, axis=2)
    return best_linear_approximation(spec(y), spec(u))


def test_input_is_an_odd_multisine(periods):
    u, _ = periods
    power = np.mean(np.abs(np.fft.rfft(u, axis=1)) ** 2, axis=0)
    level = np.median(power[LINES])
    # every odd line up to 200 Hz carries the excitation; above 200 Hz the input is 20 dB
    # down. The even lines carry what the measured input picks up besides (-29 dB on
    # average, single lines up to -10 dB: 150 Hz mains), not part of the design
    assert power[LINES].min() > 0.1 * level
    assert power[np.arange(2, 2684, 2)].mean() < 0.01 * level
    assert power[2700:N // 2].max() < 0.01 * level


def test_variance_predicts_the_difference_of_disjoint_realisations(periods):
    u, y = periods
    for a, b in ((slice(0, 5), slice(5, 10)), (slice(0, 10, 2), slice(1, 10, 2))):
        ra, rb = _bla(u[a], y[a]), _bla(u[b], y[b])
        z2 = (np.abs(ra.response - rb.response) ** 2
              / (ra.total_variance + rb.total_variance))[0, 0]
        # with the variances right z2 is F(2, 16)-distributed (each variance from 5
        # realisations): median 0.72, 96 % below 4. A variance off by 2x either way moves
        # the median to about 0.36 or 1.4
        print(f'disjoint realisations {a} vs {b}: median z^2 {np.median(z2):.2f}, '
              f'{100 * np.mean(z2 < 4):.0f} % of {z2.size} lines within 2 SD '
              f'(F(2, 16): {NULL.median():.2f}, {100 * NULL.cdf(4):.0f} %)')
        assert 0.5 < np.median(z2) < 1.2, np.median(z2)
        assert np.mean(z2 < 4) > 0.9, np.mean(z2 < 4)


def test_bla_agrees_with_welch(periods):
    u, y = periods
    bla = _bla(u, y).response[0, 0]
    f = LINES * FS / N
    # scipy's Welch H1 (Hann, 1024 samples: 0.6 Hz resolution) of the same periods
    fw, puu = signal.welch(u, fs=FS, nperseg=1024)
    _, puy = signal.csd(u, y, fs=FS, nperseg=1024)
    h1 = puy.mean(axis=0) / puu.mean(axis=0)
    keep = (fw > 2) & (fw < 195)
    smooth = np.array([bla[np.abs(f - x) < 0.3].mean() for x in fw[keep]])
    ratio = h1[keep] / smooth
    print(f'Welch H1 / BLA: {np.max(np.abs(20 * np.log10(np.abs(ratio)))):.2f} dB, '
          f'{np.max(np.abs(np.degrees(np.angle(ratio)))):.1f} deg at most (2-195 Hz)')
    assert np.max(np.abs(20 * np.log10(np.abs(ratio)))) < 0.5
    assert np.max(np.abs(np.degrees(np.angle(ratio)))) < 3.0


def test_uncertainty_peaks_at_the_resonance_where_the_cubic_spring_acts(periods):
    u, y = periods
    res = _bla(u, y)
    f = LINES * FS / N
    mag = np.abs(res.response[0, 0])
    rel = np.sqrt(res.total_variance[0, 0]) / mag
    f_peak = f[np.argmax(mag)]
    print(f'resonance {f_peak:.1f} Hz; relative SD {100 * rel.max():.1f} % at '
          f'{f[np.argmax(rel)]:.1f} Hz, median {100 * np.median(rel):.1f} %')
    # output noise alone would give the smallest relative spread where |BLA| is largest; the
    # distortion of the cubic spring grows with the displacement, largest at the resonance
    assert 60 < f_peak < 80, f_peak
    assert abs(f[np.argmax(rel)] - f_peak) < 10
    assert rel.max() > 2 * np.median(rel)
