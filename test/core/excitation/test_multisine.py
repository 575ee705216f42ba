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
import re

from frf_ident.core.excitation import multisine as ms
from frf_ident.errors import DesignError
import numpy as np
import pytest


def test_paper_design_values():
    """Sec. 6: 1-60 Hz at 1 kHz gives Ts = 3 ms, nf = 4096, 12.3 s per period."""
    d = ms.design_odd_multisine(1.0, 60.0, bound=150.0, resolution_hz=0.1, fs=1000.0)
    assert d.ts == pytest.approx(0.003)
    assert d.nf == 4096
    assert d.period == pytest.approx(12.288)
    assert d.f0 == pytest.approx(1 / 12.288)
    assert np.all(d.harmonics % 2 == 1)
    assert d.freq_hz[0] == pytest.approx(1.0, rel=0.1)
    assert d.freq_hz[-1] == pytest.approx(60, rel=0.01)
    # nearest odd multiple of f0 to each reference frequency
    ref = ms.reference_frequency_set(1, 60, 80)
    for f in ref:
        h = d.harmonics[np.argmin(np.abs(d.harmonics * d.f0 - f))]
        assert abs(h * d.f0 - f) <= d.f0 * (1 + 1e-9)


def test_dft_length_power_of_two():
    assert ms.dft_length(0.1, 0.003) == 4096   # ceil(3333.3) -> 4096
    assert ms.dft_length(1 / (0.003 * 2048), 0.003) == 2048


def test_realisation_periodic_odd_lines_and_bound():
    fs = 1000.0
    d = ms.design_odd_multisine(2.0, 60.0, bound=0.02, resolution_hz=0.5, fs=fs)
    r = ms.multisine_realisation(d, 3, np.random.default_rng(1), fs=fs)
    n = d.period_samples(fs)
    t = np.arange(2 * n) / fs
    x = r.evaluate(t)                                   # (n_ex, 2n, n_u)
    assert np.allclose(x[:, :n], x[:, n:], atol=1e-12)  # periodic
    assert np.max(np.abs(x)) <= d.bound * (1 + 1e-12)   # bound respected
    fine = r.evaluate(np.arange(16 * n) / (16 * fs))    # ... also between samples
    assert np.max(np.abs(fine)) <= d.bound * (1 + 1e-3)
    spec = np.abs(np.fft.rfft(x[:, :n], axis=1))
    excited = np.zeros(spec.shape[1], bool)
    excited[d.harmonics] = True
    assert np.all(spec[:, ~excited] < 1e-9 * spec.max())   # only the odd design lines
    assert np.all(d.harmonics % 2 == 1)
    assert 1.2 < ms.crest_factor(x[0, :n, 0]) < 6


def test_eq9_phase_shifts_condition_number_one():
    for n_u in (1, 2, 3, 6):
        phi = ms.mimo_phase_shifts(n_u)
        R = np.exp(1j * phi)
        assert np.linalg.cond(R) == pytest.approx(1.0, abs=1e-9)
    # and on the real signals' spectra
    fs = 1000.0
    d = ms.design_odd_multisine(2.0, 60.0, bound=1.0, resolution_hz=1.0, fs=fs)
    r = ms.multisine_realisation(d, 3, np.random.default_rng(0), fs=fs)
    x = r.evaluate(np.arange(d.period_samples(fs)) / fs)
    X = np.fft.rfft(x, axis=1)[:, d.harmonics, :]       # (n_ex, lines, n_u)
    conds = [np.linalg.cond(X[:, k, :].T) for k in range(X.shape[1])]
    assert max(conds) == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize('kwargs, needle', [
    ({'f_low': 1, 'f_high': 600, 'bound': 1, 'fs': 1000, 'resolution_hz': 0.1}, 'f_high=600'),
    ({'f_low': 60, 'f_high': 10, 'bound': 1, 'fs': 1000, 'resolution_hz': 0.1}, 'f_high=10'),
    ({'f_low': 1, 'f_high': 60, 'bound': 0, 'fs': 1000, 'resolution_hz': 0.1}, 'bound=0'),
    ({'f_low': 1, 'f_high': 60, 'bound': -3, 'fs': 1000, 'resolution_hz': 0.1}, 'bound=-3'),
    ({'f_low': -1, 'f_high': 60, 'bound': 1, 'fs': 1000, 'resolution_hz': 0.1}, 'f_low=-1'),
    ({'f_low': 1, 'f_high': 60, 'bound': 1, 'fs': 1000, 'resolution_hz': 0}, 'resolution_hz=0'),
])
def test_bad_design_names_value(kwargs, needle):
    with pytest.raises(DesignError, match=needle.replace('(', r'\(')):
        ms.design_odd_multisine(**kwargs)


@pytest.mark.parametrize('kw, match', [
    ({'resolution_hz': float('nan')}, 'resolution_hz=nan must be a finite number, positive'),
    ({'f_low': 70.0}, 'f_low=70.0, f_high=60.0: expected 0 < f_low < f_high'),
    ({'settle_s': -1.0}, 'settle_s=-1.0 must be a finite number, at least 0'),
    ({'transient_periods': -1}, 'transient_periods=-1 must be at least 0'),
    ({'seed': -1}, 'seed=-1 must be at least 0'),
])
def test_multisine_config_refuses_non_finite_and_empty_settings(kw, match):
    """A node took resolution_hz NaN at start-up and refused it only at the service call."""
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    from frf_ident.errors import DesignError
    with pytest.raises(DesignError, match=re.escape(match)):
        MultisineConfig(**kw)


@pytest.mark.parametrize('kw, match', [
    ({'duration': float('nan')}, 'duration=nan must be a finite number, positive'),
    ({'f_high': float('inf')}, 'f_low=2.0, f_high=inf'),
    ({'torque_margin': 1.5}, 'torque_margin=1.5 must be at most 1'),
    ({'position_margin': 1.5}, 'position_margin=1.5 must be at most 1'),
    ({'position_margin': 0.0}, 'position_margin=0.0 must be a finite number, positive'),
    ({'r_initial': [0.006, float('nan'), 0.012]}, 'must be finite'),
])
def test_chirp_config_refuses_non_finite_and_empty_settings(kw, match):
    from frf_ident.core.excitation.chirp_iteration import ChirpConfig
    from frf_ident.errors import DesignError
    with pytest.raises(DesignError, match=re.escape(match)):
        ChirpConfig(**kw)
