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
"""Estimators against analytic truth and Monte-Carlo truth."""
from frf_ident.core.estimation.spectra import frf_from_reference, frf_from_spectra
from frf_ident.core.excitation.chirp import chirp_phase_flips, ChirpDesign
from frf_ident.core.excitation.chirp_dft import chirp_excerpt_dft, chirp_spectra, decimation_filter
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.core.model.params import AxisParams, RobotParams
from frf_ident.core.model.schema import default_robot
from frf_ident.core.simulation.analytic import robot_frf
from frf_ident.core.simulation.open_loop import run_open_loop_chirp, run_open_loop_multisine
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.errors import EstimationError
import numpy as np
import pytest
from scipy import signal

FS = 1000.0


def test_eq7_exact_for_known_spectra_and_rank_check():
    rng = np.random.default_rng(0)
    P = rng.normal(size=(2, 3, 5)) + 1j * rng.normal(size=(2, 3, 5))
    U = rng.normal(size=(5, 3, 4)) + 1j * rng.normal(size=(5, 3, 4))
    Y = np.einsum('oif,fie->foe', P, U)
    Ph, cond = frf_from_spectra(Y, U)
    assert np.allclose(Ph, P) and np.all(cond >= 1)
    with pytest.raises(EstimationError, match='n_ex=2'):
        frf_from_spectra(Y[:, :, :2], U[:, :, :2])
    Pr, _ = frf_from_reference(Y, U, U.conj() + 0.3 * U)
    assert np.allclose(Pr, P)


def test_multisine_bla_exact_on_linear_mimo_plant():
    """3x3 with link coupling, eq. 9 excitation: the closed-form continuous MIMO FRF."""
    # open loop without viscous friction and gravity, so one transient period suffices
    rob = default_robot().with_axes(viscous_friction=0.0, gravity_torque=0.0)
    plant = FlexibleJointPlant(rob)
    d = design_odd_multisine(2.0, 60.0, bound=50.0, resolution_hz=0.5, fs=FS)
    run = run_open_loop_multisine(plant, d, n_realisations=2, n_periods=2,
                                  rng=np.random.default_rng(1))
    truth = robot_frf(rob, d.freq_hz)
    err = np.abs(run.frf.response / truth - 1)
    assert np.max(err) < 1e-4          # quadratic input interpolation at 1 kHz; < 0.001 dB
    assert run.frf.meta['cond_max'] < 1.5


def test_chirp_estimate_on_linear_mimo_plant():
    rob = default_robot().with_axes(viscous_friction=0.0, gravity_torque=0.0)
    rob.substeps = 2
    plant = FlexibleJointPlant(rob)
    d = ChirpDesign(2.0, 60.0, 20.0, np.array([[100.0], [150.0], [120.0]]))
    run = run_open_loop_chirp(plant, d, chirp_phase_flips(3))
    truth = robot_frf(rob, run.frf.freq_hz)
    err_db = 20 * np.log10(np.abs(run.frf.response / truth))
    diag = err_db[[0, 1, 2], [0, 1, 2]]
    assert np.median(np.abs(diag)) < 0.1
    # eq. 26 excitation is well conditioned for eq. 7
    assert run.frf.meta['cond_max'] < 5


def _nonlinear_plant(seed):
    ax = AxisParams(stiffness_k2=4.5e5, stiffness_breakpoint=1.5e-4, velocity_noise=4e-5,
                    torque_limit=1e4)
    return FlexibleJointPlant(RobotParams([ax], sample_rate=FS, substeps=1, seed=seed))


def test_bla_variances_agree_with_monte_carlo():
    """
    Check the BLA variances against Monte-Carlo.

    Noise variance (from periods) and total variance (from realisations) of the BLA agree
    with the Monte-Carlo spread of the BLA over repeated experiments within 25 %.
    """
    d = design_odd_multisine(2.0, 40.0, bound=60.0, resolution_hz=0.5, fs=FS)
    n_p, n_q, runs = 6, 4, 40
    fixed = [multisine_realisation(d, 1, np.random.default_rng(100 + p), fs=FS)
             for p in range(n_p)]
    noise_only, full = [], []
    for r in range(runs):
        # noise-only repetitions: same phases, new noise
        a = run_open_loop_multisine(_nonlinear_plant(r), d, n_realisations=n_p, n_periods=n_q,
                                    rng=np.random.default_rng(0), realisations=fixed)
        noise_only.append(a)
        # full repetitions: new phases and new noise
        b = run_open_loop_multisine(_nonlinear_plant(1000 + r), d, n_realisations=n_p,
                                    n_periods=n_q, rng=np.random.default_rng(5000 + r))
        full.append(b)
    P_noise = np.stack([a.frf.response[0, 0] for a in noise_only])
    mc_noise = np.var(P_noise, axis=0, ddof=1)
    pred_noise = np.mean([a.bla.noise_variance[0, 0] for a in noise_only], axis=0)
    P_full = np.stack([b.frf.response[0, 0] for b in full])
    mc_total = np.var(P_full, axis=0, ddof=1)
    pred_total = np.mean([b.bla.total_variance[0, 0] for b in full], axis=0)
    ratio_noise = np.mean(pred_noise) / np.mean(mc_noise)
    ratio_total = np.mean(pred_total) / np.mean(mc_total)
    assert 0.75 < ratio_noise < 1.25, ratio_noise
    assert 0.75 < ratio_total < 1.25, ratio_total
    # the nonlinearity is active: nonlinear variance well above noise variance
    nl = np.mean([b.bla.nonlinear_variance[0, 0] for b in full], axis=0)
    assert np.mean(nl) > 3 * np.mean(pred_noise)


def test_decimation_filter_is_the_one_resample_poly_designs():
    """The cached FIR gives bit-identical decimation to scipy's own default design."""
    x = np.random.default_rng(3).normal(size=(997, 2))
    for q in (2, 3, 7, 25):
        np.testing.assert_array_equal(
            signal.resample_poly(x, 1, q, axis=0),
            signal.resample_poly(x, 1, q, axis=0, window=decimation_filter(q)))


def _excerpt_dft_by_scipy(x, fs, f_x, t_center, t_first):
    """Sec. 5.1 for one frequency with scipy's own polyphase decimation (the oracle)."""
    half = 2.0 / f_x
    i0 = int(round((t_center - half - t_first) * fs))
    i1 = int(round((t_center + half - t_first) * fs))
    seg = x[i0:i1] - x[i0:i1].mean(axis=0)
    q = max(1, int(np.floor(fs / (10.0 * f_x))))
    if q > 1:
        seg = signal.resample_poly(seg, 1, q, axis=0)
    t = t_first + i0 / fs + np.arange(seg.shape[0]) * (q / fs)
    w = signal.windows.hann(seg.shape[0], sym=False)
    kernel = w * np.exp(-2j * np.pi * f_x * (t - t_center))
    return np.tensordot(kernel, seg, axes=(0, 0)) / np.sum(w)


def test_chirp_spectra_equal_scipy_decimation_and_lose_only_the_gapped_channel():
    """
    The compiled Sec. 5.1 processing equals resample_poly + Hann + DFT per frequency.

    At 1e-12 relative over decimation factors 1-83 (fs 250 Hz, 0.3-30 Hz), a record that
    does not start at 0; a missing sample removes the frequencies whose excerpt holds it, on
    its channel only.
    """
    rng = np.random.default_rng(11)
    fs, t_first = 250.0, 0.5
    x = rng.standard_normal((5000, 2, 2))
    gap = 2500
    x[gap, 0, 1] = np.nan
    f = np.geomspace(0.3, 30.0, 120)
    tc = 8.0 + (f - 0.3) / 30.0 * 4.0
    got = chirp_spectra(x, fs, f, tc, t_first=t_first)
    assert got.shape == (120, 2, 2)
    clean = x.copy()
    clean[gap, 0, 1] = 0.0
    for k in range(f.size):
        ref = _excerpt_dft_by_scipy(clean, fs, f[k], tc[k], t_first)
        half = 2.0 / f[k]
        hit = (round((tc[k] - half - t_first) * fs) <= gap
               < round((tc[k] + half - t_first) * fs))
        assert np.isnan(got[k, 0, 1]) == hit, f[k]
        ok = np.isfinite(got[k])
        assert ok.sum() == (3 if hit else 4)
        np.testing.assert_allclose(got[k][ok], ref[ok], rtol=1e-12, atol=1e-15)
    assert np.isnan(got[:, 0, 1]).sum() >= 10
    np.testing.assert_allclose(chirp_excerpt_dft(x[:, 1], fs, f[7], tc[7], t_first=t_first),
                               got[7, 1], rtol=1e-14)
    with pytest.raises(EstimationError, match='outside the record'):
        chirp_spectra(x, fs, f, tc - 7.5, t_first=t_first)
