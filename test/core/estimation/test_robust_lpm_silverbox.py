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
The robust LPM on the Silverbox: nonlinear variance from ONE realisation.

The Silverbox (Wigren & Schoukens 2013, ../shared/data/Silverbox, read in place) is an
electronic Duffing oscillator driven by 10 realisations of an odd random-phase multisine
(one period of 8192 samples each, every odd line up to 200 Hz). The 10-realisation BLA's
spread over realisations is the variance of a one-realisation BLA (noise plus stochastic
nonlinear distortion; noise is below 1 % of it at 80 mV). The robust LPM sees one
realisation at a time and must find the same from the line-to-line scatter around a smooth
G, and the noise from the non-excited (even) lines.
"""
from pathlib import Path

from frf_ident.core.estimation.lpm import robust_lpm
from frf_ident.core.estimation.spectra import best_linear_approximation, periodic_spectra
from frf_ident.errors import EstimationError
import numpy as np
import pytest
from scipy.io import loadmat

SILVERBOX = (Path(__file__).resolve().parents[3].parent / 'shared' / 'data' / 'Silverbox'
             / 'SNLS80mV.mat')
FS = 1e7 / 2 ** 14           # [Hz] (SOURCE.md)
N = 8192                     # samples per period
LINES = np.arange(1, 2684, 2)  # excited odd lines up to 200 Hz
#: the mean over realisations of the robust LPM's nonlinear variance (each from one
#: realisation) over the 10-realisation BLA's variance: median per band within this factor
FACTOR_POOLED = 1.15
#: one realisation's robust LPM total variance over that realisation's own squared
#: deviation from the 10-realisation BLA (x 10/9), summed over a band: within this factor
#: (the realisations of the data differ: their deviations from the mean range 0.3-2x the
#: pooled variance, 90-200 Hz most)
FACTOR_ONE = 1.5
BANDS = ((1, 40), (40, 60), (60, 80), (80, 120), (120, 200))   # [Hz]

pytestmark = pytest.mark.skipif(not SILVERBOX.is_file(), reason='shared Silverbox data absent')


@pytest.fixture(scope='module')
def realisations():
    """Return (u, y), shape (10, N): the steady-state period of each realisation."""
    m = loadmat(SILVERBOX, squeeze_me=True)
    u, y = np.asarray(m['V1'], float), np.asarray(m['V2'], float)
    # each realisation follows a quiet stretch (20+ samples at the generator's offset) and
    # starts with 500 samples of its own periodic tail; the period follows the tail
    quiet = np.convolve(np.abs(u - np.median(u)) < 0.05 * np.std(u), np.ones(20), 'valid') == 20
    starts = [s + 20 for s in np.flatnonzero(quiet[:-1] & ~quiet[1:]) if 40000 < s + 20 < 120000]
    assert len(starts) == 10
    return (np.array([u[s + 492:s + 492 + N] for s in starts]),
            np.array([y[s + 492:s + 492 + N] for s in starts]))


@pytest.fixture(scope='module')
def estimates(realisations):
    """Return the 10-realisation BLA and the robust LPM of each realisation alone."""
    u, y = realisations

    def spec(x):
        return periodic_spectra(x[:, None, :, None, None], LINES, axis=2)
    return (best_linear_approximation(spec(y), spec(u)),
            [robust_lpm(y[p], u[p], N, LINES, fs=FS) for p in range(10)])


def test_one_realisation_at_a_time_gives_the_nonlinear_variance_of_ten(estimates):
    bla, robust = estimates
    one = bla.total_variance[0, 0] * 10           # variance of a one-realisation BLA
    nl = np.mean([r.nonlinear_variance[0, 0] for r in robust], axis=0)
    f = LINES * FS / N
    ratio = [np.median((nl / one)[(f > lo) & (f < hi)]) for lo, hi in BANDS]
    share = np.median([r.frf.noise_variance[0, 0] / r.frf.total_variance[0, 0]
                       for r in robust])
    print('mean robust-LPM nonlinear variance / 10-realisation BLA variance per band: '
          + ', '.join(f'{lo}-{hi} Hz {x:.2f}' for (lo, hi), x in zip(BANDS, ratio))
          + f'; noise / total median {100 * share:.2f} %')
    assert all(1 / FACTOR_POOLED < x < FACTOR_POOLED for x in ratio), ratio
    assert share < 0.05
    for p, r in enumerate(robust):
        assert r.noise_from == 'non-excited lines'
        np.testing.assert_allclose(r.frf.response[0, 0], bla.per_realisation[p, 0, 0])


def test_each_realisation_variance_matches_its_own_deviation(estimates):
    bla, robust = estimates
    f = LINES * FS / N
    worst = []
    for p, r in enumerate(robust):
        dev = np.abs(bla.per_realisation[p, 0, 0] - bla.response[0, 0]) ** 2 * 10 / 9
        tot = r.frf.total_variance[0, 0]
        worst.append(max((np.sum(tot[k]) / np.sum(dev[k])
                          for k in ((f > lo) & (f < hi) for lo, hi in BANDS)),
                         key=lambda x: abs(np.log(x))))
    print('per realisation, the band furthest from 1 of robust total / own deviation: '
          + ', '.join(f'{x:.2f}' for x in worst))
    assert all(1 / FACTOR_ONE < x < FACTOR_ONE for x in worst), worst


def test_two_inputs_from_one_realisation_refused():
    with pytest.raises(EstimationError, match='expected one'):
        robust_lpm(np.zeros((64, 1)), np.zeros((64, 2)), 64, np.arange(1, 20, 2))
