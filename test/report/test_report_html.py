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
"""The HTML report: one report.html referencing every PNG written next to it."""
import re

from frf_ident.bag import TimingReport, TopicTiming
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.excitation import chirp as ch
from frf_ident.core.recording import Recording
from frf_ident.errors import FrfIdentInputError
from frf_ident.report import write_report
import numpy as np
import pytest

PNG_MAGIC = b'\x89PNG\r\n\x1a\n'


def _two_mass(f):
    s = 2j * np.pi * f
    jm, jo, d, k = 35.0, 150.0, 400.0, 1.5e5
    return (jo * s ** 2 + d * s + k) / (s * (jm * jo * s ** 2 + (jm + jo) * (d * s + k)))


def _frfs(variances=True):
    f = np.geomspace(1, 60, 40)
    p = np.array([[_two_mass(f), 0.2 * _two_mass(f)], [0.2 * _two_mass(f), _two_mass(f)]])
    var = (0.05 * np.abs(p)) ** 2 if variances else None
    ms = FrequencyResponse(f, p * 1.02, ['tau_1', 'tau_2'], ['dq_1', 'dq_2'],
                           None if var is None else var / 4, var,
                           {'method': 'BLA'})
    chirp = FrequencyResponse(f, p * 0.98, ['tau_1', 'tau_2'], ['dq_1', 'dq_2'],
                              noise_variance=var)
    fr = np.geomspace(0.5, 80, 300)
    ref = FrequencyResponse(fr, np.array([[_two_mass(fr), 0.2 * _two_mass(fr)],
                                          [0.2 * _two_mass(fr), _two_mass(fr)]]),
                            ['tau_1', 'tau_2'], ['dq_1', 'dq_2'])
    return {'multisine': ms, 'chirp <fast>': chirp}, ref


def _recording(fs=250.0, duration=12.0):
    t = np.arange(int(fs * duration)) / fs
    a0, a1 = ch.exponential_chirp_coefficients(1.0, 60.0, 1.0, 11.0)
    u = np.column_stack([ch.exponential_chirp(t, a0, a1, 1.0, 11.0, 100.0),
                         ch.exponential_chirp(t, a0, a1, 1.0, 11.0, 150.0, np.pi)])
    return Recording(t, ['joint_1', 'joint_2'], np.zeros_like(u), 1e-3 * u, u, 1e-4 * u)


def _timing():
    topic = TopicTiming('/joint_states', 3000, dt_s=0.004, rate_hz=250.0, jitter=0.012,
                        gaps=1, missing_samples=2, longest_gap_samples=2,
                        longest_gap_at_s=3.5, header_log_offset_mean_s=2.5e-4)
    return TimingReport(0.004, 3000, 0.0, 11.996, True, 'resampled',
                        {'/joint_states': topic}, {'complete': True},
                        ['/frf/excitation at 125 Hz, half the joint-state rate'])


def _pngs_referenced(html_path):
    text = html_path.read_text()
    refs = set(re.findall(r'<img src="([^"]+)"', text))
    on_disk = {p.name for p in html_path.parent.glob('*.png')}
    assert refs == on_disk
    for name in on_disk:
        data = (html_path.parent / name).read_bytes()
        assert data.startswith(PNG_MAGIC) and len(data) > 5000
    return text, on_disk


def test_full_report(tmp_path):
    frfs, ref = _frfs()
    iterations = [{'iteration': i, 'error_db': [10.0 / i ** 2, 6.0 / i ** 2]}
                  for i in range(1, 7)]
    path = write_report(tmp_path / 'rep', frfs=frfs, reference=ref, recording=_recording(),
                        timing=_timing().to_dict(), iterations=iterations,
                        title='Axes 1-2 & <test>')
    assert path == tmp_path / 'rep' / 'report.html'
    text, pngs = _pngs_referenced(path)
    assert pngs == {'bode.png', 'snr.png', 'timeseries.png', 'spectrogram.png',
                    'iterations.png'}
    assert '<title>Axes 1-2 &amp; &lt;test&gt;</title>' in text
    assert 'chirp &lt;fast&gt;' in text                       # labels are escaped
    assert '/joint_states' in text and 'half the joint-state rate' in text   # timing
    assert 'tau_2 \u2192 dq_1' in text
    # the estimates table: median SNR 20 log10(1.02 / 0.05) = 26.19 dB (multisine, total
    # variance) and 20 log10(0.98 / 0.05) = 25.85 dB (chirp), RMS error to the reference
    # |20 log10(1.02)| = 0.172 dB and |20 log10(0.98)| = 0.175 dB
    assert 'median SNR [dB]' in text
    rows = {m.group(1): re.findall(r'<td[^>]*>([^<]*)</td>', m.group(0))
            for m in re.finditer(r'<tr><td>([^<]*)</td>.*?</tr>', text)}
    # (the reference is interpolated in log f onto the estimate's lines: +-0.01 dB)
    for label, snr, err in (('multisine', 26.19, 0.172), ('chirp &lt;fast&gt;', 25.85, 0.175)):
        assert float(rows[label][-2]) == pytest.approx(snr, abs=0.06)   # shown to 0.1
        assert float(rows[label][-1]) == pytest.approx(err, abs=0.01)
    assert '<script' not in text and 'http' not in text        # self-contained


def test_report_without_variances_recording_or_iterations(tmp_path):
    frfs, _ = _frfs(variances=False)
    timing = _timing()                                          # the object works too
    path = write_report(tmp_path, frfs=frfs, reference=None, recording=None, timing=timing,
                        iterations=None, title='minimal')
    text, pngs = _pngs_referenced(path)
    assert pngs == {'bode.png'}                                 # no SNR without variances
    assert 'Timing of the recording' in text


def test_iteration_key_of_the_runner_and_errors(tmp_path):
    its = [{'iteration': 1, 'error_db_per_channel': [3.0]}, {'iteration': 2,
                                                             'error_db_per_channel': [0.5]}]
    frfs, _ = _frfs()
    text, pngs = _pngs_referenced(write_report(tmp_path / 'a', frfs=frfs, iterations=its))
    assert 'iterations.png' in pngs
    with pytest.raises(FrfIdentInputError, match="iteration 1 has no 'error_db'"):
        write_report(tmp_path / 'b', frfs=frfs, iterations=[{'iteration': 1}])
    with pytest.raises(FrfIdentInputError, match='nothing to report'):
        write_report(tmp_path / 'c', frfs={})
