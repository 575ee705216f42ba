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
The robust LPM's noise and nonlinear levels in a plot and in the HTML report (issue 39).

Truth by construction: P = 1 / (j 2 pi f) (rad/s per N m), noise variance 1e-4 |P|^2 (40 dB
below |P|), stochastic nonlinear variance 100 times the noise (20 dB above it).
"""
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.robust_levels import RobustLpmLevels
from frf_ident.report import write_report
from frf_ident.report.distortion import plt, robust_lpm_figure
import numpy as np
import pytest


@pytest.fixture
def estimate():
    f = np.arange(1.0, 61.0)
    p = 1 / (2j * np.pi * f)
    noise = 1e-4 * np.abs(p) ** 2
    levels = RobustLpmLevels(f, noise[None], 101 * noise[None], ['dq_m/j'],
                             ['(rad/s)^2/(N m)^2'], 6, 5, 'periods')
    return FrequencyResponse(f, p[None, None], ['tau_m/j'], ['dq_m/j'],
                             meta={'robust_lpm': levels.to_dict()})


def test_plot_has_frf_noise_and_nonlinear_level_in_db_with_units(estimate, monkeypatch,
                                                                 tmp_path):
    kept = []
    monkeypatch.setattr(plt, 'close', kept.append)
    levels = RobustLpmLevels.from_dict(estimate.meta['robust_lpm'])
    robust_lpm_figure(levels, estimate, tmp_path / 'r.png')
    (fig,) = kept
    (ax,) = fig.axes
    assert ax.get_xscale() == 'log' and ax.get_xlabel() == 'frequency [Hz]'
    assert ax.get_ylabel() == '[dB re 1 (rad/s)/(N m)]'
    lines = {ln.get_label().split(' ')[0]: ln for ln in ax.get_lines()}
    f = estimate.freq_hz
    mag = 20 * np.log10(np.abs(estimate.response[0, 0]))
    for key, want in (('|P|', mag), ('noise', mag - 40), ('stochastic', mag - 20)):
        x, y = lines[key].get_data()
        assert np.allclose(x, f) and np.allclose(y, want, atol=1e-6), key
    plt.close(fig)


def test_report_has_robust_lpm_panel_and_summary(estimate, tmp_path):
    text = write_report(tmp_path, frfs={'multisine': estimate}).read_text()
    assert 'robust_lpm.png' in text and (tmp_path / 'robust_lpm.png').stat().st_size > 10_000
    assert 'dq_m/j: nonlinear variance 20.0 dB above noise' in text
