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
"""Excitation detection against analytic truth (designed multisines, chirps) and real data."""
from pathlib import Path

from frf_ident.core.excitation import chirp as ch
from frf_ident.core.excitation import multisine as ms
from frf_ident.core.excitation.chirp_detect import detect_chirp
from frf_ident.core.excitation.detect import detect_excitation
from frf_ident.core.excitation.detection_results import ChirpDetection, MultisineDetection
from frf_ident.core.excitation.multisine_detect import detect_multisine
from frf_ident.errors import EstimationError
from hypothesis import example, given, HealthCheck, settings
from hypothesis import strategies as st
import numpy as np
import pytest

FS = 1000.0


def _multisine(design, n_periods, *, lead=0, tail=0, noise=0.0, seed=0, n_u=1):
    real = ms.multisine_realisation(design, n_u, np.random.default_rng(seed), fs=FS)
    p = design.period_samples(FS)
    x = real.evaluate(np.arange(n_periods * p) / FS)[0]          # (N, n_u), experiment 1
    x = np.concatenate([np.zeros((lead, n_u)), x, np.zeros((tail, n_u))])
    rng = np.random.default_rng(seed + 100)
    x = x + noise * x.std() * rng.standard_normal(x.shape)
    return x[:, 0] if n_u == 1 else x


@pytest.fixture(scope='module')
def design():
    """1-60 Hz odd multisine at 1 kHz with 0.33 Hz resolution: 3072-sample period, 49 lines."""
    return ms.design_odd_multisine(1.0, 60.0, bound=1.0, resolution_hz=0.5, fs=FS)


@pytest.mark.parametrize('lead, n_periods, tail, noise', [
    (0, 5, 0, 0.0), (1234, 4, 300, 0.0), (500, 3, 0, 0.3), (777, 6, 2000, 0.3)])
def test_multisine_period_lines_start(design, lead, n_periods, tail, noise):
    x = _multisine(design, n_periods, lead=lead, tail=tail, noise=noise)
    det = detect_multisine(x, fs=FS)
    assert isinstance(det, MultisineDetection) and det.kind == 'multisine'
    assert det.period_samples == design.period_samples(FS) == 3072
    assert det.n_periods == n_periods
    assert det.f0 == pytest.approx(design.f0, rel=1e-12)
    np.testing.assert_array_equal(det.harmonics, design.harmonics)
    np.testing.assert_allclose(det.freq_hz, design.freq_hz, rtol=1e-12)
    assert det.odd
    tol = 0 if noise == 0 else 15              # exact without noise, a few samples with it
    assert abs(det.start - lead) <= tol
    text = det.describe()
    assert 'odd multisine' in text and '3072 samples' in text and f'{n_periods} whole' in text


# a start-up transient (a different signal) before six periods, then a gap of any length up
# to 1.6 periods anywhere; 1 % noise
GAP_P, GAP_PERIODS, GAP_LEAD = 3072, 6, 40


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(start=st.integers(0, GAP_PERIODS * GAP_P - 100), length=st.integers(4, 4900))
@example(start=9528, length=3072)   # the period came out tripled, and the record refused
@example(start=3000, length=500)    # the transient's comparison one period on lost: start 0
def test_multisine_with_a_gap(design, start, length):
    """
    A gap (NaN) neither changes the period nor lets the start-up transient into the block.

    The autocorrelation compares present samples only, and a sample whose partner one
    period on is missing is compared with a later period. Before, the two examples gave a
    tripled period (9216 samples: the record was refused) and a block from sample 0, the
    transient in it.
    """
    x = _multisine(design, GAP_PERIODS, lead=GAP_LEAD, noise=0.01)
    x[:GAP_LEAD] = np.random.default_rng(start).standard_normal(GAP_LEAD) * x.std()
    x[GAP_LEAD + start:GAP_LEAD + start + length] = np.nan
    det = detect_multisine(x, fs=FS)
    assert det.period_samples == GAP_P
    np.testing.assert_array_equal(det.harmonics, design.harmonics)
    # the block begins after the transient and holds every whole period after it (or
    # after a gap right after it, which ends the comparison), flush with the end
    assert det.start >= GAP_LEAD - 3
    assert det.n_periods == (x.size - det.start) // GAP_P
    assert det.n_periods >= (x.size - max(GAP_LEAD + 3, GAP_LEAD + start + length)) // GAP_P


def test_paper_design_mimo_channel(design):
    """The paper's 12.288 s design on 3 inputs (eq. 9 shifts): strongest channel analysed."""
    paper = ms.design_odd_multisine(1.0, 60.0, bound=150.0, resolution_hz=0.1, fs=FS)
    x = _multisine(paper, 3, n_u=3, lead=100, noise=0.05)
    x[:, 1] *= 3.0
    det = detect_excitation(x, FS)
    assert det.kind == 'multisine' and det.channel == 1
    assert det.period_samples == 12288 and det.n_periods == 3
    np.testing.assert_array_equal(det.harmonics, paper.harmonics)


def test_multisine_with_even_lines_is_not_odd():
    p = 2000
    t = np.arange(4 * p) / FS
    h = np.arange(2, 40)
    x = ms.multisine(t, h * FS / p, 1.0, np.random.default_rng(3).uniform(0, 2 * np.pi, h.size))
    det = detect_multisine(x + 2.0, fs=FS)                # constant offset is ignored
    assert det.period_samples == p and det.n_periods == 4
    np.testing.assert_array_equal(det.harmonics, h)
    assert not det.odd and 'not all odd' in det.describe()


def test_common_factor_shortens_period():
    """Lines 2, 4, 6 of a 1000-sample window are lines 1, 2, 3 of a 500-sample period."""
    t = np.arange(6000) / FS
    x = sum(np.sin(2 * np.pi * k * t + k) for k in (2, 4, 6))
    det = detect_multisine(x, fs=FS)
    assert det.period_samples == 500 and det.n_periods == 12
    np.testing.assert_array_equal(det.harmonics, [1, 2, 3])


@pytest.mark.parametrize('f_low, f_high, duration, lead, phi, noise', [
    (1.0, 60.0, 20.0, 2.0, 0.0, 0.0),
    (1.0, 60.0, 20.0, 2.0, 1.3, 0.1),
    (2.0, 60.0, 20.0, 0.0, 0.0, 0.1),
    (0.5, 100.0, 30.0, 1.3, 2.5, 0.1),
])
def test_chirp_band_within_2_percent(f_low, f_high, duration, lead, phi, noise):
    a0, a1 = ch.exponential_chirp_coefficients(f_low, f_high, lead, lead + duration)
    t = np.arange(int((lead + duration + 1.5) * FS)) / FS
    x = ch.exponential_chirp(t, a0, a1, lead, lead + duration, 1.0, phi)
    x = x + noise * np.random.default_rng(4).standard_normal(x.size)
    det = detect_chirp(x, fs=FS)
    assert isinstance(det, ChirpDetection) and det.kind == 'chirp'
    assert det.f_low == pytest.approx(f_low, rel=0.02)
    assert det.f_high == pytest.approx(f_high, rel=0.02)
    assert det.a0 == pytest.approx(a0, rel=0.01)
    assert det.t0 == pytest.approx(lead, abs=0.05)
    assert det.t1 == pytest.approx(lead + duration, abs=0.05)
    assert 'exponential chirp' in det.describe()
    with pytest.raises(EstimationError, match='no periodicity'):
        detect_multisine(x, fs=FS)


@settings(max_examples=40, deadline=None)
@given(start=st.floats(0.0, 19.9), length=st.floats(0.05, 3.0))
@example(start=0.2, length=2.0)     # the onset was found after the gap: t0 4.09 s
@example(start=0.1, length=0.3)
def test_chirp_with_a_gap(start, length):
    """
    A gap (NaN) in a 2-60 Hz chirp leaves its band and interval where they are.

    The on- and offset search counts two cycles of present samples, reaching across a gap;
    before, a gap within the first cycles put the onset after it (4.09 s for the first
    example: the band from 2.85 Hz).
    """
    lead, duration = 2.0, 20.0
    a0, a1 = ch.exponential_chirp_coefficients(2.0, 60.0, lead, lead + duration)
    t = np.arange(int((lead + duration + 1.5) * FS)) / FS
    x = ch.exponential_chirp(t, a0, a1, lead, lead + duration, 1.0, 0.0)
    x = x + 0.1 * np.random.default_rng(4).standard_normal(x.size)
    g0, g1 = lead + start, min(lead + start + length, lead + duration - 0.5)
    x[(t >= g0) & (t < g1)] = np.nan
    det = detect_chirp(x, fs=FS)
    assert det.a0 == pytest.approx(a0, rel=0.01)
    # an edge inside the gap cannot be seen: then anywhere in it will do
    assert lead - 0.05 <= det.t0 <= max(lead + 0.05, g1 + 0.05 if g0 <= lead + 0.05 else 0)
    assert det.t1 == pytest.approx(lead + duration, abs=0.05)
    assert det.f_high == pytest.approx(60.0, rel=0.02)
    if det.t0 <= lead + 0.05:
        assert det.f_low == pytest.approx(2.0, rel=0.02)


def test_chirp_design_table1_amplitudes_mimo():
    """Return a ChirpDesign with Table 1 amplitude steps (100 / 50 below / above 40 Hz)."""
    d = ch.ChirpDesign(2.0, 60.0, 20.0, np.array([[100.0, 50.0], [150.0, 75.0]]), [40.0], t0=1.0)
    t = np.arange(int(22.0 * FS)) / FS
    x = d.evaluate(t, ch.chirp_phase_flips(2))[1]          # experiment 2, (N, 2)
    det = detect_excitation(x, FS)
    assert det.kind == 'chirp' and det.channel == 1
    assert det.f_low == pytest.approx(2.0, rel=0.02) and det.f_high == pytest.approx(60, rel=0.02)
    assert det.duration == pytest.approx(20.0, rel=0.01)


def test_neither_raises_one_line():
    x = np.random.default_rng(5).standard_normal(20000)
    with pytest.raises(EstimationError) as err:
        detect_excitation(x, FS)
    msg = str(err.value)
    assert '\n' not in msg and 'no multisine or exponential chirp' in msg and 'fs=1000' in msg


@pytest.mark.parametrize('x, fs, needle', [
    (np.zeros(5), FS, 'samples'),
    (np.ones(100), -1.0, 'fs=-1.0'),
    (np.full(100, np.nan), FS, 'non-finite'),
    (np.zeros((10, 10, 10)), FS, 'x.shape'),
])
def test_bad_input(x, fs, needle):
    with pytest.raises(EstimationError, match=needle):
        detect_excitation(x, fs)


DAISY = Path(__file__).resolve().parents[3].parent / 'shared' / 'data' / 'DaISy_robot_arm' \
    / 'robot_arm.dat'


@pytest.mark.skipif(not DAISY.is_file(), reason='shared DaISy data absent')
def test_a_real_sweep_recorded_over_one_period_is_refused_not_guessed():
    """
    The DaISy flexible robot arm (real data, read in place): a sine sweep of one period.

    Its 1024 samples hold less than two periods of anything, and its sweep is not
    exponential: detection must refuse with both reasons in one line rather than invent a
    period or a band (its sample time is unknown: fs = 1).
    """
    u = np.loadtxt(DAISY)[:, 0]
    with pytest.raises(EstimationError) as err:
        detect_excitation(u, 1.0)
    msg = str(err.value)
    assert '\n' not in msg
    assert 'only 1 whole periods repeat' in msg and 'no exponential chirp' in msg, msg


def test_documented_import_path_still_resolves():
    """docs/import_maps.md imports the detectors from ``detect``: the objects of their homes."""
    from frf_ident.core.excitation import detect
    assert detect.detect_multisine is detect_multisine
    assert detect.detect_chirp is detect_chirp
    assert detect.MultisineDetection is MultisineDetection
    assert detect.ChirpDetection is ChirpDetection
