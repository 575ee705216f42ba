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
Sweeps whose law is not the exponential chirp of eq. 16: refused, never a wrong FRF (issue 39).

The case of the issue: a linear 15 -> 2 Hz sine sweep (scipy.signal.chirp) over 260 s drives
a 6 Hz mode (scipy's lfilter: analytic FRF). Before, detection called it an exponential chirp
'16.6-4.27 Hz' and failed in the chirp design ('f_high=4.27 must be greater than
f_low=16.63'), and the given `--chirp 2 15 --chirp-time 0 260` wrote an FRF 13 dB off.
"""
from frf_ident.core.estimation.detected import estimate_in_blocks, RecordingBlocks
from frf_ident.core.estimation.excitation_options import ExcitationOptions
from frf_ident.core.excitation.chirp_detect import detect_chirp
from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError
import numpy as np
import pytest
from scipy import signal

FS = 100.0


def _mode(f_hz=6.0, zeta=0.05):
    w = 2 * np.pi * f_hz
    b, a, _ = signal.cont2discrete(([w * w], [1, 2 * zeta * w, w * w]), 1 / FS,
                                   method='bilinear')
    return b[0], a


def sweep_recording(f0, f1, method, t_end=260.0, tail=10.0):
    """Sweep f0 -> f1 Hz on [0, t_end] s, quiet tail; output of the 6 Hz mode + 0.1 % noise."""
    t = np.arange(0, t_end + tail, 1 / FS)
    u = np.where(t <= t_end, signal.chirp(t, f0, t_end, f1, method=method), 0.0)
    y = signal.lfilter(*_mode(), u)
    y = y + 1e-3 * np.std(y) * np.random.default_rng(0).standard_normal(t.size)
    return Recording(t, ['j'], np.zeros((t.size, 1)), y[:, None], u[:, None])


@pytest.fixture(scope='module')
def linear_down():
    return sweep_recording(15.0, 2.0, 'linear')


def test_linear_sweep_is_not_detected_as_exponential_chirp(linear_down):
    with pytest.raises(EstimationError) as err:
        detect_chirp(linear_down.effort, FS)
    text = str(err.value)
    print(text)
    assert 'linear sweep 15 -> 2' in text and 'exponential' in text


def test_given_chirp_that_the_data_do_not_follow_is_refused(linear_down):
    opts = ExcitationOptions(chirp=(2.0, 15.0), chirp_time=(0.0, 260.0))
    with pytest.raises(EstimationError) as err:
        estimate_in_blocks(RecordingBlocks(linear_down), opts)
    text = str(err.value)
    print(text)
    assert 'does not match the recorded excitation' in text and 'linear sweep 15 -> 2' in text


def test_given_down_sweep_is_refused_with_the_reason(linear_down):
    opts = ExcitationOptions(chirp=(15.0, 2.0), chirp_time=(0.0, 260.0))
    with pytest.raises(EstimationError, match='sweeps down'):
        estimate_in_blocks(RecordingBlocks(linear_down), opts)


@pytest.mark.parametrize('given', [False, True])
def test_exponential_chirp_detected_or_given_is_estimated(given):
    """The law of eq. 16 passes the check and gives the analytic FRF (no false refusal)."""
    rec = sweep_recording(1.0, 20.0, 'logarithmic', t_end=120.0)
    opts = ExcitationOptions(chirp=(1.0, 20.0), chirp_time=(0.0, 120.0)) if given else None
    frf = next(iter(estimate_in_blocks(RecordingBlocks(rec), opts).values()))
    z = np.exp(2j * np.pi * frf.freq_hz / FS)
    b, a = _mode()
    err_db = 20 * np.log10(np.abs(frf.response[0, 0] * np.polyval(a, z) / np.polyval(b, z)))
    band = (frf.freq_hz > 1.5) & (frf.freq_hz < 18)
    print(f'given={given}: median |error| {np.median(np.abs(err_db[band])):.3f} dB')
    assert np.median(np.abs(err_db[band])) < 0.2
