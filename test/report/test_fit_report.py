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
The fit section of a report page and its figures: what a reader sees of a fit and a loop check.

Truth: the Section 6 joint (analytic FRF, 1.5 ms delay, 1 % noise with that variance); the
residual the figure draws is recomputed here from the measured FRF and the model, and the
margins are given numbers the table must show as they are.
"""
from __future__ import annotations

import re

from frf_ident.core.fit.physical import fit_two_mass
from frf_ident.core.loop.check import AxisMargins, LoopCheck, Margin
from frf_ident.core.simulation.analytic import two_mass_frf
from frf_ident.report import fit_figures
from frf_ident.report.html import fit_sections, write_fit_report
import matplotlib.pyplot as plt
import numpy as np
import pytest

FREQ = np.geomspace(0.5, 60.0, 60)
TAU = 1.5e-3


@pytest.fixture(scope='module')
def measured():
    p = two_mass_frf(FREQ, 35.0, 150.0, 1.5e5, 400.0, 20.0) * np.exp(-2j * np.pi * FREQ * TAU)
    var = (0.01 * np.abs(p)) ** 2
    rng = np.random.default_rng(2)
    return p + np.sqrt(var / 2) * (rng.standard_normal(p.size)
                                   + 1j * rng.standard_normal(p.size)), var


def test_residual_panel_is_the_error_over_sigma_on_a_labelled_frequency_axis(
        measured, monkeypatch, tmp_path):
    p, var = measured
    fit = fit_two_mass(FREQ, p, var, delay_s=None)
    kept = []
    monkeypatch.setattr(fit_figures.plt, 'close', kept.append)
    fit_figures.fit_figure(FREQ, p[None], fit.model[None], var[None], ['joint_1'],
                           tmp_path / 'fit.png', ['cost/dof 1.0: explained by the noise'])
    (fig,) = kept
    am, ap, ar = fig.axes[:3]
    (line, *_) = [ln for ln in ar.get_lines() if np.size(ln.get_xdata()) == FREQ.size]
    np.testing.assert_allclose(line.get_ydata(), np.abs(p - fit.model) / np.sqrt(var))
    # a right model: the squared residual averages about 1 (chi-square, 2 dof a line over 2)
    assert 0.7 < np.mean(line.get_ydata() ** 2) < 1.3
    assert ar.get_xlabel() == 'frequency [Hz]' and ar.get_xscale() == 'log'
    assert '\u03c3' in ar.get_ylabel() and am.get_ylabel() == '|P| [dB]'
    assert ar.get_title() == 'cost/dof 1.0: explained by the noise'
    plt.close(fig)


def test_loop_figure_has_frequency_axes_with_units(monkeypatch, tmp_path):
    kept = []
    monkeypatch.setattr(fit_figures.plt, 'close', kept.append)
    loop = (1e3 / (2j * np.pi * FREQ))[None]
    fit_figures.loop_figure(FREQ, loop, None, ['joint_1'], [0.8], tmp_path / 'loop.png')
    (fig,) = kept
    am, ap, an = fig.axes[:3]
    assert ap.get_xlabel() == 'frequency [Hz]' and am.get_xscale() == 'log'
    assert am.get_ylabel() == '|L| [dB]' and an.get_xlabel() == 'Re L [-]'
    plt.close(fig)


def test_sections_show_parameters_with_errors_and_units_the_verdict_and_the_margins(
        measured, tmp_path):
    p, var = measured
    fit = fit_two_mass(FREQ, p, var, delay_s=None)
    wrong = fit_two_mass(FREQ, p, var, delay_s=0.0)       # no delay: structure missing
    margins = AxisMargins('joint_1', 1500.0, 6000.0, Margin(12.5, 0.25), Margin(48.2, 1.3),
                          Margin(14.7, 0.013), Margin(0.61, 0.004))
    check = LoopCheck([margins], None, 50, 0.001)
    sections = fit_sections(physical=[fit], check=check, fit_png='fit.png',
                            loop_png='loop.png')
    assert [a for a, _, _ in sections] == ['fit', 'parameters', 'margins']
    page = write_fit_report(tmp_path / 'fit.html', title='Fit of <x>', sections=sections)
    text = page.read_text()
    assert '<title>Fit of &lt;x&gt;</title>' in text
    for k, unit in (('motor_inertia', 'kg m^2'), ('stiffness', 'N m/rad'),
                    ('damping', 'N m s/rad')):
        i = list(fit.names).index(k)
        cell = f'{fit.value[i]:.4g} \u00b1 {fit.std[i]:.2g}'
        assert re.search(rf'<td>{k}</td><td>{re.escape(cell)}</td><td>{re.escape(unit)}</td>',
                         text), (k, cell)
    delay = f'{1e3 * fit.delay_s:.4g} \u00b1 {1e3 * fit.delay_std_s:.2g}'
    assert f'<td>delay (fitted)</td><td>{delay}</td><td>ms</td>' in text
    assert 'class="ok"' in text and 'residual explained by the noise' in text
    for cell in ('12.5 \u00b1 0.25', '48.2 \u00b1 1.3', '0.61 \u00b1 0.004',
                 '14.7 \u00b1 0.013', 'crossover [Hz]', 'phase margin [deg]',
                 'discrete at dt = 0.001 s', '50 draws'):
        assert cell in text, cell
    bad = fit_sections(physical=[wrong])
    assert 'class="warn"' in bad[0][2] and 'structure missing' in bad[0][2]
    assert 'delay (given (--delay))' in bad[0][2]
