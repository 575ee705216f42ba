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
from frf_ident.core.excitation import chirp as ch
from frf_ident.errors import DesignError
import numpy as np
import pytest


def test_instantaneous_frequency_equals_eq16():
    fs, f_lo, f_hi, T = 2000.0, 1.0, 60.0, 20.0
    a0, a1 = ch.exponential_chirp_coefficients(f_lo, f_hi, 0.0, T)
    assert np.exp(a1) == pytest.approx(f_lo) and np.exp(a0 * T + a1) == pytest.approx(f_hi)
    t = np.arange(int(T * fs)) / fs
    x = ch.exponential_chirp(t, a0, a1, 0.0, T, 1.0)
    # measured: zero crossings of the sampled signal (linear interpolation); half a period apart
    i = np.flatnonzero(np.signbit(x[:-1]) != np.signbit(x[1:]))[1:]
    tz = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    f_meas = 0.5 / np.diff(tz)
    tm = 0.5 * (tz[1:] + tz[:-1])
    f_eq16 = ch.chirp_instantaneous_frequency(tm, a0, a1)
    assert np.max(np.abs(f_meas / f_eq16 - 1)) < 2e-3
    f_eq16 = ch.chirp_instantaneous_frequency(t, a0, a1)
    # the closed-form phase derivative is eq. 16 exactly
    dphi = np.gradient(ch.chirp_phase(t, a0, a1, 0.0), t) / (2 * np.pi)
    assert np.max(np.abs(dphi[1:-1] / f_eq16[1:-1] - 1)) < 1e-5
    assert ch.chirp_time_at_frequency(10.0, a0, a1) == pytest.approx(np.log(10) / a0)


def test_amplitude_schedule_table1_and_bound():
    d = ch.ChirpDesign(2.0, 60.0, 20.0, np.array([[100.0, 50.0], [150.0, 75.0]]), [40.0])
    t = np.arange(0, 20, 1e-3)
    x = d.evaluate(t, ch.chirp_phase_flips(2))
    f = ch.chirp_instantaneous_frequency(t, d.a0, d.a1)
    assert np.max(np.abs(x[:, :, 0])) <= 100 + 1e-9 and np.max(np.abs(x[:, :, 1])) <= 150 + 1e-9
    lo, hi = f < 30, f > 50
    assert np.max(np.abs(x[0, hi, 0])) == pytest.approx(50, rel=0.01)
    assert np.max(np.abs(x[0, lo, 0])) == pytest.approx(100, rel=0.01)


def test_eq26_phase_flips():
    phi = ch.chirp_phase_flips(3)
    assert np.allclose(phi, np.diag([0, np.pi, np.pi]))
    R = np.exp(1j * phi) * 1.0
    R[~np.eye(3, dtype=bool)] = 1.0
    assert np.linalg.matrix_rank(R) == 3


@pytest.mark.parametrize('args, needle', [
    ((60.0, 10.0, 20.0, [[1.0]]), 'f_high=10'),
    ((1.0, 60.0, 0.0, [[1.0]]), 'duration'),
    ((1.0, 60.0, 20.0, [[0.0]]), 'amplitude'),
    ((1.0, 60.0, 20.0, [[-5.0]]), 'amplitude'),
])
def test_bad_chirp_design(args, needle):
    with pytest.raises(DesignError, match=needle):
        ch.ChirpDesign(args[0], args[1], args[2], np.array(args[3]))


def test_chirp_above_nyquist_rejected():
    d = ch.ChirpDesign(1.0, 600.0, 10.0, np.array([[1.0]]))
    with pytest.raises(DesignError, match='Nyquist'):
        d.check_sample_rate(1000.0)
