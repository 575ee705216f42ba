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
Loop shaping of one axis (frf_ident/core/loop/shaping.py) on the analytic two-mass joint.

The search sees a noisy FRF; the chosen setting is judged on the noise-free analytic FRF by
python-control (truth the search did not compute), beside the simplest honest baseline: the
PI ``loop --propose`` reads off the same FRF for the same crossover (frf_ident/core/loop/
design.py), which knows nothing of the resonance.
"""
import warnings

import control
from frf_ident.core.fit.physical import two_mass_response
from frf_ident.core.loop.design import propose_pi
from frf_ident.core.loop.explain import explain_limit
from frf_ident.core.loop.modes import resonance_bands, two_mass_mode
from frf_ident.core.loop.shaping import AxisSetting, shape_axis
from frf_ident.core.loop.targets import TuneTargets
import numpy as np
import pytest

THETA = np.array([35.0, 150.0, 1.5e6, 130.0, 20.0])     # joint_1 of model_3axis_resonant.yaml
DELAY = 0.0035                                          # 3 ms drive + half a sample
DT = 1e-3
F = np.arange(2.0, 120.0, 0.5)


def _truth_margins(setting, f=F):
    lo = two_mass_response(THETA, f, DELAY) * setting.response(f, DT)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        gm, pm, sm, _, wgc, _ = control.stability_margins(control.frd(lo, 2 * np.pi * f),
                                                          method='frd')
    return 20 * np.log10(gm) if np.isfinite(gm) else np.inf, pm, sm, wgc / (2 * np.pi)


def _measured(seed=0, rel=0.01):
    rng = np.random.default_rng(seed)
    p = two_mass_response(THETA, F, DELAY)
    return p + rel * np.abs(p) * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size))


def test_a_notch_at_the_mode_and_the_targets_met_on_the_true_plant():
    p = _measured()
    mode = two_mass_mode(THETA, np.diag([0.1, 1.0, 1e3, 1.0, 0.1]) ** 2)
    bands = resonance_bands([[mode]], 0, (F[0], F[-1]))
    t = TuneTargets(crossover_hz=5.0)
    res = shape_axis('joint_1', F, p[None], 0, bands, DT, t)
    gm, pm, mm, wc = _truth_margins(res.setting)
    base = propose_pi(F, p, 5.0, t.phase_margin_deg)
    bgm, bpm, bmm, _ = _truth_margins(AxisSetting('joint_1', base.kp, base.ki))
    print(f'{res.setting.summary()}: true GM {gm:.2f} dB, PM {pm:.1f} deg, MM {mm:.3f}, '
          f'bandwidth {res.margins.bandwidth_hz[0]:.2f} Hz; loop --propose PI {base.kp:.0f}/'
          f'{base.ki:.0f}: GM {bgm:.2f} dB, PM {bpm:.1f} deg, MM {bmm:.3f}')
    assert res.feasible and res.limit is None
    assert res.setting.filters and res.setting.filters[0].kind == 'notch'
    assert abs(res.setting.filters[0].frequency_hz / mode.frequency_hz - 1) < 1e-3
    assert gm >= 0.97 * t.gain_margin_db and pm >= 0.97 * t.phase_margin_deg
    assert mm >= 0.97 * t.modulus_margin
    assert abs(res.margins.bandwidth_hz[0] / 5.0 - 1) < 0.05
    assert bmm < t.modulus_margin          # the resonance-blind PI misses what the notch gives


def test_targets_no_setting_meets_are_named_with_the_phase_budget():
    p = _measured()
    mode = two_mass_mode(THETA, np.zeros((5, 5)))
    bands = resonance_bands([[mode]], 0, (F[0], F[-1]))
    t = TuneTargets(gain_margin_db=25.0, modulus_margin=0.8)
    res = shape_axis('joint_1', F, p[None], 0, bands, DT, t)
    assert not res.feasible and res.limit is not None
    text = explain_limit(res.limit, F, p, res.setting, DT, delay_s=DELAY, bands=bands)
    print(text)
    assert res.limit.value < res.limit.wanted
    assert '3.5 ms delay' in text and 'deg' in text


@pytest.mark.parametrize('target', [3.0, 6.0])
def test_the_crossover_asked_is_the_worst_poses_bandwidth(target):
    p = _measured(1)
    bands = resonance_bands([[two_mass_mode(THETA, np.zeros((5, 5)))]], 0, (F[0], F[-1]))
    res = shape_axis('joint_1', F, p[None], 0, bands, DT, TuneTargets(crossover_hz=target))
    assert res.feasible
    assert abs(res.worst_bandwidth_hz / target - 1) < 0.05


def test_a_crossover_too_high_is_refused_with_what_binds_there():
    p = _measured()
    mode = two_mass_mode(THETA, np.zeros((5, 5)))
    bands = resonance_bands([[mode]], 0, (F[0], F[-1]))
    res = shape_axis('joint_1', F, p[None], 0, bands, DT, TuneTargets(crossover_hz=12.0))
    text = explain_limit(res.limit, F, p, res.setting, DT, delay_s=DELAY, bands=bands)
    print(text)
    assert res.feasible and res.limit.target == 'crossover_hz'
    assert res.limit.value < 0.95 * 12.0 and res.limit.because is not None
    assert 'crossover' in text and '12 Hz asked' in text
