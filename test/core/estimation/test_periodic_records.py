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
Periodic records not designed here: steady-state periods, period boundaries (issue 39).

A lightly damped mode driven by an odd multisine from rest (scipy's lfilter, known output
noise): the truth is analytic, the noise variance of the period mean sigma^2 / (N |U|^2 n).
"""
from frf_ident.core.estimation.detected import estimate_in_blocks, RecordingBlocks
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.core.excitation.multisine_detect import detect_multisine
from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError
import numpy as np
import pytest
from scipy import signal

FS = 1000.0


@pytest.fixture(scope='module')
def period():
    """Return a 3072-sample period of a 2-60 Hz odd multisine, unit amplitude."""
    des = design_odd_multisine(2.0, 60.0, bound=1.0, resolution_hz=0.5, fs=FS)
    real = multisine_realisation(des, 1, np.random.default_rng(0), fs=FS)
    return real.evaluate(np.arange(des.period_samples(FS)) / FS)[0][:, 0]


def _mode(f_hz, zeta):
    w = 2 * np.pi * f_hz
    b, a, _ = signal.cont2discrete(([w * w], [1, 2 * zeta * w, w * w]), 1 / FS,
                                   method='bilinear')
    return b[0], a


def _estimate(u, y):
    rec = Recording(np.arange(u.size) / FS, ['j'], np.zeros((u.size, 1)), y[:, None],
                    u[:, None])
    return next(iter(estimate_in_blocks(RecordingBlocks(rec)).values()))


@pytest.mark.parametrize('n_periods, shaker_zeta, zeta', [(3, 0.05, 0.02), (4, None, 0.01)])
def test_noise_variance_from_the_steady_periods(period, n_periods, shaker_zeta, zeta):
    """
    The estimate's noise variance is that of the steady periods, not of the transient.

    (3, 0.05, ...): a shaker whose force settles within the first period (the force, on
    which the excitation is detected, has the start-up transient). Before, the periodic
    block started inside the transient and dropped the last steady period; the transient's
    leakage made the period look 3072.67 samples long and the record was refused.
    (4, None, 0.01): the force is periodic from the start, the 20 Hz mode settles over two
    periods. Before, one period was skipped whatever the data: noise variance 170x the truth.
    """
    n = period.size
    u = np.tile(period, n_periods)
    if shaker_zeta is not None:
        u = signal.lfilter(*_mode(8.0, shaker_zeta), u)
    y0 = signal.lfilter(*_mode(20.0, zeta), u)
    sigma = 1e-3 * np.std(y0)
    y = y0 + sigma * np.random.default_rng(1).standard_normal(y0.size)
    frf = _estimate(u, y)
    used = frf.meta['periods']
    bins = np.round(frf.freq_hz * n / FS).astype(int)
    U = np.fft.rfft(u[-n:])[bins] / n
    truth = sigma ** 2 / n / np.abs(U) ** 2 / used
    ratio = frf.noise_variance[0, 0] / truth
    print(f'{n_periods} periods: {used} used; {frf.meta.get("transient")}; noise variance / '
          f'truth: mean {ratio.mean():.2f} over {ratio.size} lines')
    assert used == 2
    assert 1 / 1.5 < ratio.mean() < 1.5
    # the FRF itself: the analytic mode within the noise
    z = np.exp(2j * np.pi * frf.freq_hz / FS)
    g = np.polyval(_mode(20.0, zeta)[0], z) / np.polyval(_mode(20.0, zeta)[1], z)
    assert np.max(np.abs(frf.response[0, 0] / g - 1)) < 0.02


def test_steady_record_keeps_every_period(period):
    """No transient (noise only around a periodic signal): all periods stay."""
    from frf_ident.core.estimation.transient import steady_periods
    rng = np.random.default_rng(5)
    X = np.fft.rfft(period)[1:200]
    spectra = X[None, :, None] + 1e-3 * (rng.standard_normal((6, 199, 1))
                                         + 1j * rng.standard_normal((6, 199, 1)))
    st = steady_periods(spectra)
    assert st.first == 0 and st.tested and st.steady == 6


@pytest.mark.parametrize('extra', [0, 1])
def test_t_range_on_a_period_boundary_is_accepted(period, extra):
    """
    Exactly two periods (a --t-range from a period boundary, end inclusive: + 1 sample).

    Before: 'best autocorrelation 1.00 beyond the main lobe is below min_correlation=0.3'
    (the peak at half the record was the last lag searched, so not a peak).
    """
    x = np.concatenate([period, period, period[:extra]])
    det = detect_multisine(x, FS)
    assert det.period_samples == period.size and det.n_periods == 2 and det.start <= extra


def test_too_short_for_two_periods_says_so(period):
    """One sample short of two periods: the message names the real reason."""
    x = np.concatenate([period, period[:-1]])
    with pytest.raises(EstimationError) as err:
        detect_multisine(x, FS)
    text = str(err.value)
    assert 'below min_correlation' not in text
    assert 'longest lag searched' in text and 'min_periods=2' in text
