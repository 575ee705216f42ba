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
"""The HTML report shows the distortion levels of a multisine estimate (issue 39)."""
import re

from frf_ident.core.estimation.distortion import distortion_lines
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.report import write_report
import numpy as np


def test_report_has_distortion_plot_and_summary(tmp_path):
    """
    Synthetic period spectra with a distortion at the odd lines 20 dB above the noise.

    Complex noise of variance 1 per line and period; at the odd lines a distortion 100 times
    the noise variance of the period mean, circular complex normal over the lines (as the
    stochastic distortion of a random-phase multisine).

    Truth by construction: odd lines 20 dB above the noise, even lines at it (0 dB); the
    summary in the page must say so within 1.5 dB.
    """
    rng = np.random.default_rng(0)
    n_q, bins = 8, np.arange(1, 601)
    excited = np.arange(1, 200, 4)
    noise = (rng.standard_normal((n_q, bins.size, 1))
             + 1j * rng.standard_normal((n_q, bins.size, 1))) / np.sqrt(2)
    scale = np.where(np.isin(bins, excited), 1e3, np.where(bins % 2 == 1, 1.0, 0.0))
    dist = (rng.standard_normal(bins.size) + 1j * rng.standard_normal(bins.size)) / np.sqrt(2)
    # odd lines: E|Y|^2 = 100 x the noise variance of the mean (1 / n_q)
    Y = noise + (scale * dist * np.sqrt(100.0 / n_q))[None, :, None]
    levels = distortion_lines(Y, bins, excited, 0.5, ['dq_m/j'], units=['rad/s'])
    frf = FrequencyResponse(excited * 0.5, np.ones((1, 1, excited.size), complex), ['tau_m/j'],
                            ['dq_m/j'], meta={'distortion': levels.to_dict()})
    path = write_report(tmp_path, frfs={'multisine': frf})
    text = path.read_text()
    assert 'distortion.png' in text and (tmp_path / 'distortion.png').stat().st_size > 10_000
    m = re.search(r'odd lines ([-+0-9.]+) dB, even lines ([-+0-9.]+) dB above the noise', text)
    assert m, text
    assert abs(float(m.group(1)) - 20) < 1.5 and abs(float(m.group(2))) < 1.5
