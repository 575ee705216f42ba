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
Filters at a resonance: the discrete notch where the continuous one is, and the modes' errors.

- Tustin with prewarping puts the discrete notch's minimum at its centre (scipy's sosfreqz on a
  fine grid), where plain Tustin misses it by the known frequency warping; the depth and the
  band coverage claimed in frf_ident/core/loop/notch.py hold.
- The two-mass resonance's first-order standard errors (frf_ident/core/loop/modes.py) match the
  spread over 100 Monte-Carlo fits of noisy FRFs of the model.
"""
from frf_ident.core.fit.physical import fit_two_mass, two_mass_response
from frf_ident.core.loop.modes import resonance_bands, two_mass_mode
from frf_ident.core.loop.notch import design_lowpass, design_notch, sections_response
from frf_ident.core.loop.shaping import AxisSetting
import numpy as np
import pytest
from scipy import signal


@pytest.mark.parametrize('f0, fs', [(36.6, 1000.0), (0.0625, 1.0), (200.0, 1000.0)])
def test_prewarped_notch_has_its_minimum_at_the_centre(f0, fs):
    n = design_notch(0.99 * f0, 1.01 * f0, 0.01, 0.35, fs)
    f = np.linspace(0.8 * f0, 1.2 * f0, 200001)
    mag = np.abs(signal.sosfreqz(n.sos.reshape(1, 6), worN=f, fs=fs)[1])
    at = f[np.argmin(mag)]
    plain_b, plain_a = signal.bilinear(n.num_s, n.den_s, fs=fs)
    plain = np.abs(signal.freqz(plain_b, plain_a, worN=f, fs=fs)[1])
    off = f[np.argmin(plain)] / f0 - 1
    print(f'notch {f0:g} Hz at {fs:g} Hz: prewarped minimum {at:.6g} Hz, plain Tustin '
          f'{f[np.argmin(plain)]:.6g} Hz ({100 * off:.2f} %)')
    assert abs(at / n.frequency_hz - 1) < 1e-5
    assert abs(mag.min() - n.zeta_zero / n.zeta_pole) < 1e-3 * mag.min()
    assert abs(off) > 10 * 1e-5                  # prewarping is what puts it there
    # the continuous filter at the centre and far away; DC gain 1
    depth = n.zeta_zero / n.zeta_pole
    assert abs(abs(n.continuous_response([n.frequency_hz])[0]) - depth) < 1e-9
    assert abs(sections_response([0.0], n.sos, fs)[0] - 1) < 1e-9


def test_notch_covers_its_band_and_costs_the_phase_it_should():
    """Across [low, high] |N| <= sqrt(2) x depth; the lag at w_c << w0 ~ 2 (zp - zz) w_c / w0."""
    lo, hi = 40.0, 56.0
    n = design_notch(lo, hi, 0.01, 0.7, 1000.0)
    f = np.linspace(lo, hi, 400)
    depth = n.zeta_zero / n.zeta_pole
    assert np.all(np.abs(n.continuous_response(f)) <= np.sqrt(2) * depth * 1.0001)
    wc = 3.0
    lag = -np.degrees(np.angle(n.response([wc])[0]))
    approx = np.degrees(2 * (n.zeta_pole - n.zeta_zero) * wc / n.frequency_hz)
    assert abs(lag / approx - 1) < 0.05, (lag, approx)


def test_lowpass_corner_and_dc():
    lp = design_lowpass(20.0, 1000.0)
    f = np.array([0.0, 20.0])
    r = lp.response(f)
    assert abs(r[0] - 1) < 1e-6
    assert abs(abs(r[1]) - 1 / (2 * lp.zeta_pole)) < 1e-6     # prewarped: exact at the corner
    s = AxisSetting('j', 1.0, 0.0, (lp,))
    assert np.allclose(s.filter_response(f), r) and s.sos().shape == (1, 6)


def test_two_mass_mode_standard_errors_match_monte_carlo():
    theta = np.array([35.0, 150.0, 1.5e5, 40.0, 20.0])
    f = np.arange(2.0, 60.0, 0.25)
    p = two_mass_response(theta, f, 0.0005)
    sd = 0.03 * np.abs(p)
    true = two_mass_mode(theta, np.zeros((5, 5)))
    rng = np.random.default_rng(0)
    est = []
    for _ in range(100):
        pn = p + sd * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2)
        fit = fit_two_mass(f, pn, sd ** 2, delay_s=None)
        m = two_mass_mode(fit.value, fit.covariance)
        est.append([m.frequency_hz, m.frequency_std_hz, m.damping, m.damping_std])
    e = np.array(est)
    print(f'resonance {true.frequency_hz:.4f} Hz, damping {true.damping:.5f}; Monte-Carlo sd '
          f'{e[:, 0].std():.2e} Hz / {e[:, 2].std():.2e}, mean SE {e[:, 1].mean():.2e} / '
          f'{e[:, 3].mean():.2e}')
    for k, (v, t) in enumerate([(0, true.frequency_hz), (2, true.damping)]):
        assert 0.75 < e[:, v + 1].mean() / e[:, v].std() < 1.33
        assert np.mean(np.abs(e[:, v] - t) <= 2 * e[:, v + 1]) >= 0.9


def test_resonance_bands_match_poses_and_skip_unstable_poles():
    from frf_ident.core.fit.rational import Mode
    poses = [[Mode(40.0, 0.1, 0.01, 0.001), Mode(90.0, 0.2, 0.02, 0.001)],
             [Mode(44.0, 0.1, 0.012, 0.001)],
             [Mode(36.0, 0.2, 0.011, 0.001), Mode(70.0, 0.5, -0.01, 0.001)]]
    bands = resonance_bands(poses, 0, (2.0, 120.0))
    assert len(bands) == 2
    b = bands[0]
    assert b.low_hz == pytest.approx(35.6) and b.high_hz == pytest.approx(44.2)
    assert b.damping == 0.01 and b.spread == pytest.approx(44 / 36 - 1)
    assert bands[1].modes[1] is None and bands[1].modes[2] is None   # 70 Hz pole: unstable
