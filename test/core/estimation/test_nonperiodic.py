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
A recording without reference, without periodic excitation and with a gap: the direct LPM.

Two joints driven open loop by independent white-noise torques through known digital filters
(the truth: scipy's freqz of those filters), 1 % output noise; a stretch of missing samples
in the middle. Before issue 39 this recording was refused ("no multisine or chirp found").
"""
from frf_ident.core.estimation.described import estimate_recording
from frf_ident.core.estimation.lpm_frames import DIRECT_WARNING
from frf_ident.core.recording import Recording
import numpy as np
from scipy import signal

FS = 500.0
FILTERS = [[([0.3, 0.2], [1.0, -0.5]), ([0.1], [1.0, -0.8])],
           ([[0.05], [1.0, -0.9]], ([0.4, -0.1], [1.0, -0.3]))]


def _recording(n=3 * 4096 + 100):
    rng = np.random.default_rng(11)
    u = rng.standard_normal((n, 2))
    y = np.zeros((n, 2))
    for i in range(2):
        for j in range(2):
            y[:, i] += signal.lfilter(*FILTERS[i][j], u[:, j])
    y += 0.01 * np.std(y, axis=0) * rng.standard_normal(y.shape)
    y[5000:5010] = np.nan                     # a gap: its frame is dropped
    u[5000:5010] = np.nan
    t = np.arange(n) / FS
    return Recording(t, ['a', 'b'], np.cumsum(y, axis=0) / FS, y, u, None, None, [], {})


def test_direct_lpm_with_a_gap():
    est = estimate_recording(_recording(), window_s=4096 / FS)
    assert sorted(est) == ['lpm', 'lpm_h1']
    frf = est['lpm']
    assert frf.meta['method'] == 'lpm_direct' and frf.meta['dropped'] == {'frames': 1}
    assert frf.meta['frames'] == 2
    assert DIRECT_WARNING in frf.meta['detected']
    truth = np.array([[signal.freqz(*FILTERS[i][j], worN=frf.freq_hz, fs=FS)[1]
                       for j in range(2)] for i in range(2)])
    rel = np.abs(frf.response - truth) / np.abs(truth)
    z2 = np.abs(frf.response - truth) ** 2 / frf.noise_variance
    print(f'median relative error {100 * np.median(rel):.2f} %, mean |error|^2 / variance '
          f'{np.mean(z2):.2f}')
    assert np.median(rel) < 0.01
    assert 0.75 < np.mean(z2) < 1.25          # the variance is that of the error
    coh = np.asarray(est['lpm_h1'].meta['coherence'])
    assert coh.shape == (2, est['lpm_h1'].freq_hz.size) and np.median(coh) > 0.95


def test_a_reference_that_excites_no_line_is_refused_and_the_direct_estimate_offered():
    """
    A slow trajectory as the recorded reference: the indirect LPM has no line to estimate.

    KUKA KR300 trajectory A: 99 % of r's power lies in 0.1-0.4 Hz, every line there fails
    to excite all six inputs, and the estimate crashed with an IndexError (exit 1). Now the
    indirect route says why in one line, and ``method='lpm-direct'`` estimates y on u (here
    open loop, so the direct estimate is the truth's).
    """
    from frf_ident.core.estimation.excitation_options import ExcitationOptions
    from frf_ident.errors import EstimationError
    import pytest
    rec = _recording()
    t = rec.t
    ref = np.stack([np.sin(2 * np.pi * 0.2 * t), np.cos(2 * np.pi * 0.2 * t)], axis=1)
    rec = Recording(t, rec.joint_names, rec.position, rec.velocity, rec.effort, ref, None,
                    [], {})
    with pytest.raises(EstimationError, match='no line of the LPM is determined.*lpm-direct'):
        estimate_recording(rec, options=ExcitationOptions(method='lpm'), window_s=4096 / FS)
    est = estimate_recording(rec, options=ExcitationOptions(method='lpm-direct'),
                             window_s=4096 / FS)
    frf = est['lpm']
    assert frf.meta['method'] == 'lpm_direct'
    assert any("method='lpm-direct'" in line for line in frf.meta['detected'])
    truth = np.array([[signal.freqz(*FILTERS[i][j], worN=frf.freq_hz, fs=FS)[1]
                       for j in range(2)] for i in range(2)])
    assert np.median(np.abs(frf.response - truth) / np.abs(truth)) < 0.01
