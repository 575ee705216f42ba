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
Figures that read at a glance: log frequency axes, units, legends, measured data on top.

The frequency axes are checked where matplotlib's default log formatter failed: on a short band
(2-8 Hz) it labelled every minor tick as 2x10^0, 3x10^0, ... and the labels overlapped.
"""
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.report import figures
import matplotlib.pyplot as plt
import numpy as np
import pytest


def _labels(fig, ax):
    """Return the visible x tick labels of ``ax`` as (text, window extent), left to right."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    ticks = ax.xaxis.get_major_ticks() + ax.xaxis.get_minor_ticks()
    lo, hi = sorted(ax.get_xlim())
    shown = [(t.label1.get_text(), t.label1.get_window_extent(r)) for t in ticks
             if t.label1.get_visible() and t.label1.get_text() and lo <= t.get_loc() <= hi]
    return sorted(shown, key=lambda s: s[1].x0)


@pytest.mark.parametrize('band, expected', [
    ((2.0, 8.0), {'2', '5'}),                        # a short band: 2x and 5x labelled
    ((1.0, 60.0), {'1', '2', '5', '10', '20', '50'}),
    ((0.1, 1000.0), {'0.1', '1', '10', '100', '1000'}),   # four decades: decades only
])
def test_frequency_axis_labels_are_plain_numbers_that_do_not_overlap(band, expected):
    fig, ax = plt.subplots(figsize=(4.6, 2.3))        # one Bode panel of bode_figure
    f = np.geomspace(*band, 50)
    ax.plot(f, np.log(f))
    figures.frequency_axis(ax)
    ax.set_xlim(*band)
    shown = _labels(fig, ax)
    plt.close(fig)
    assert {text for text, _ in shown} == expected
    for (_, a), (_, b) in zip(shown, shown[1:]):
        assert a.x1 < b.x0, [t for t, _ in shown]       # a gap between neighbours
    assert ax.get_xlabel() == 'frequency [Hz]'


def test_bode_draws_estimates_over_the_reference_with_units_and_the_legend_outside(
        monkeypatch, tmp_path):
    kept = {}
    monkeypatch.setattr(figures, '_save', lambda fig, path: kept.setdefault('fig', fig))
    f = np.geomspace(1, 60, 40)
    p = (1 / (2j * np.pi * f))[None, None, :]
    est = FrequencyResponse(f, p * 1.1, ['tau_1'], ['dq_1'], noise_variance=np.abs(p) ** 2 / 1e4)
    figures.bode_figure({'multisine': est}, tmp_path / 'b.png',
                        reference=FrequencyResponse(f, p, ['tau_1'], ['dq_1']))
    fig = kept['fig']
    ax_m, ax_p = fig.axes[:2]
    for ax in (ax_m, ax_p):
        ref = [ln for ln in ax.get_lines() if ln.get_color() == 'k']
        est_lines = [ln for ln in ax.get_lines() if ln.get_color() != 'k']
        assert ref and est_lines
        assert min(ln.get_zorder() for ln in est_lines) > max(ln.get_zorder() for ln in ref)
        assert ax.get_legend() is None                  # no legend over the data
    assert ax_m.get_ylabel() == '|P| [dB re 1 (rad/s)/(N m)]'
    assert ax_p.get_ylabel() == 'phase [deg]' and ax_p.get_xlabel() == 'frequency [Hz]'
    (legend,) = fig.legends
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    box = legend.get_window_extent(r)
    for ax in (ax_m, ax_p):                              # the legend overlaps no panel
        assert not box.overlaps(ax.get_window_extent(r))
    plt.close(fig)


def test_phases_of_curves_that_agree_are_drawn_on_one_branch(monkeypatch, tmp_path):
    """
    Two estimates of one FRF near +-180 deg are drawn on top of each other, not 360 deg apart.

    The DaISy arm's LPM started just below -180 deg and its Welch H1 just above +180 deg:
    np.unwrap put the two curves a whole turn apart. Truth: an FRF whose phase is -180 deg
    +- 2 deg, sampled on two grids that start on either side of the cut.
    """
    kept = {}
    monkeypatch.setattr(figures, '_save', lambda fig, path: kept.setdefault('fig', fig))
    fa, fb = np.geomspace(0.001, 0.2, 60), np.geomspace(0.0045, 0.5, 80)

    def truth(f, offset_deg):
        return 0.1 * np.exp(1j * np.radians(-180.0 + offset_deg + 2.0 * np.sin(40 * f)))

    a = FrequencyResponse(fa, truth(fa, -0.5)[None, None, :], ['u'], ['y'])
    b = FrequencyResponse(fb, truth(fb, +0.5)[None, None, :], ['u'], ['y'])
    assert np.degrees(np.angle(a.response[0, 0, 0])) > 170        # either side of the cut
    assert np.degrees(np.angle(b.response[0, 0, 0])) < -170
    figures.bode_figure({'lpm': a, 'lpm_h1': b}, tmp_path / 'b.png', units=None)
    ax_m, ax_p = kept['fig'].axes[:2]
    (la, lb) = ax_p.get_lines()
    common = np.interp(lb.get_xdata(), la.get_xdata(), la.get_ydata())
    ok = (lb.get_xdata() >= fa[0]) & (lb.get_xdata() <= fa[-1])
    assert np.max(np.abs(lb.get_ydata()[ok] - common[ok])) < 5.0
    assert ax_m.get_ylabel() == '|P| [dB]'                          # no unit: plain dB
    plt.close(kept['fig'])


def test_a_coherence_panel_is_drawn_where_an_estimate_carries_one(monkeypatch, tmp_path):
    kept = {}
    monkeypatch.setattr(figures, '_save', lambda fig, path: kept.setdefault('fig', fig))
    f = np.geomspace(1, 60, 40)
    p = (1 / (2j * np.pi * f))[None, None, :]
    coh = np.linspace(0.2, 0.99, f.size)[None, :]
    h1 = FrequencyResponse(f, p, ['tau_1'], ['dq_1'], meta={'coherence': coh})
    figures.bode_figure({'lpm': FrequencyResponse(f, p, ['tau_1'], ['dq_1']), 'lpm_h1': h1},
                        tmp_path / 'b.png')
    fig = kept['fig']
    ax_c = fig.axes[2]
    (line,) = ax_c.get_lines()
    assert np.allclose(line.get_ydata(), coh[0])
    assert ax_c.get_ylabel() == 'coherence [-]' and ax_c.get_xlabel() == 'frequency [Hz]'
    assert fig.axes[1].get_xlabel() == ''                           # only the bottom panel
    plt.close(fig)
