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
The Local Polynomial Method against analytic truth and Monte-Carlo.

The simulated 3-axis robot runs in closed loop with its velocity PI from rest (the start-up
transient is in the record) with a reference r that is not periodic: band-limited filtered
noise, or a PRBS (a maximum-length sequence much longer than the record, held 4 samples).
The output noise is 1 % of the velocity rms (40 dB SNR). The truth is the analytic sampled
FRF (:func:`robot_frf_sampled`), the spread of the estimate is measured over noise
realisations with the same r (Monte-Carlo), neither produced by the estimator.
"""
from frf_ident.core.estimation.lpm import default_half_width, lpm_lines
from frf_ident.core.estimation.lpm_frames import lpm_frf, LpmAccumulator
from frf_ident.core.model.schema import default_model_dict, robot_from_dict
from frf_ident.core.simulation.analytic import robot_frf_sampled
from frf_ident.core.simulation.controller import controller_from_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.errors import EstimationError
import numpy as np
import pytest
from scipy import signal

FS = 1000.0                 # [Hz], the model's dt = 1 ms
N = 20000                   # samples per record (20 s, 0.05 Hz lines)
RUNS = 10                   # Monte-Carlo noise realisations per excitation
BAND = (2.0, 70.0)          # [Hz] analysed band: r is excited 1-80 Hz
R_RMS = 0.01                # [rad/s] reference rms: torques stay well below their limits


def _reference(kind: str) -> np.ndarray:
    rng = np.random.default_rng(1)
    if kind == 'noise':
        b, a = signal.butter(4, [1.0, 80.0], 'bandpass', fs=FS)
        r = signal.lfilter(b, a, rng.standard_normal((N + 2000, 3)), axis=0)[2000:]
    else:
        bits = [signal.max_len_seq(17, state=rng.integers(0, 2, 17))[0][:N // 4]
                for _ in range(3)]
        r = np.repeat(2.0 * np.array(bits, dtype=float).T - 1.0, 4, axis=0)
    return r * R_RMS / np.std(r, axis=0)


@pytest.fixture(scope='module', params=['noise', 'prbs'])
def monte_carlo(request):
    """Return (robot, controller, per-run LPM results, last run) for one excitation."""
    d = default_model_dict()
    rob = robot_from_dict(d)
    ctrl = controller_from_dict(d, rob)
    r = _reference(request.param)

    def run(seed):
        plant = FlexibleJointPlant(rob)
        plant.reset(seed=seed)
        return plant.simulate(reference=r, controller=ctrl.copy())
    quiet = run(0)
    for axis, rms in zip(rob.axes, np.std(quiet.velocity, axis=0) / 100.0):
        axis.velocity_noise = float(rms)
    results, last = [], None
    for m in range(RUNS):
        last = run(100 + m)
        results.append(lpm_frf(last.velocity, last.effort, FS, r=last.reference,
                               frame_samples=N))
    return request.param, rob, ctrl, results, last


def _band(f):
    return (f > BAND[0]) & (f < BAND[1])


def test_reference_lpm_within_01db_and_1_percent_bias(monte_carlo):
    kind, rob, _, results, _ = monte_carlo
    f = results[0].frf.freq_hz
    truth = robot_frf_sampled(rob, f)
    P = np.array([res.frf.response for res in results])
    k = _band(f)
    diag = np.abs(20 * np.log10(np.abs(P[:, range(3), range(3)] / truth[range(3), range(3)])))
    fro = np.linalg.norm((P.mean(axis=0) - truth).reshape(9, -1), axis=0) \
        / np.linalg.norm(truth.reshape(9, -1), axis=0)
    print(f'{kind}: diagonal |error| median {np.median(diag[..., k]):.4f} dB per run; '
          f'|mean P - P| / |P| median {100 * np.median(fro[k]):.3f} %, 90th percentile '
          f'{100 * np.percentile(fro[k], 90):.3f} % ({k.sum()} lines {BAND} Hz)')
    assert np.median(diag[..., k]) < 0.1
    assert np.median(fro[k]) < 0.01
    assert results[0].method == 'indirect' and results[0].dof >= 1


def test_lpm_noise_variance_within_25_percent_of_monte_carlo(monte_carlo):
    kind, _, _, results, _ = monte_carlo
    f = results[0].frf.freq_hz
    k = _band(f)
    P = np.array([res.frf.response for res in results])[..., k]
    mc = np.var(P, axis=0, ddof=1)                             # E|P - E P|^2 over runs
    est = np.mean([res.frf.noise_variance[..., k] for res in results], axis=0)
    ratio = est.sum(axis=-1) / mc.sum(axis=-1)                 # per element, over the band
    print(f'{kind}: LPM variance / Monte-Carlo per element:\n{np.round(ratio, 3)}')
    assert np.all(np.abs(ratio - 1) < 0.25), ratio


def test_direct_h1_is_biased_towards_minus_one_over_c_where_noise_feeds_back(monte_carlo):
    """
    Above the 80 Hz band of r only the output noise drives the loop: y = -P C v.

    There u = -C y and the direct H1 (y on u) estimates -1/C, 30x off P, while inside the
    band at 40 dB SNR the direct H1 is within a few 0.01 dB like the LPM. The PRBS excites up
    to Nyquist; only the filtered noise leaves a band to the noise.
    """
    kind, rob, ctrl, results, _ = monte_carlo
    if kind != 'noise':
        pytest.skip('the PRBS excites every line')
    h1 = np.mean([res.h1.response for res in results], axis=0)
    fh = results[0].h1.freq_hz
    truth = robot_frf_sampled(rob, fh)
    z = np.exp(2j * np.pi * fh / FS)
    inv_c = 1.0 / (ctrl.kp[:, None] + ctrl.ki[:, None] / FS * z / (z - 1))
    out = (fh > 250) & (fh < 450)
    d = range(3), range(3)
    to_c = np.median(np.abs(h1[d][:, out] + inv_c[:, out]) / np.abs(inv_c[:, out]))
    to_p = np.median(np.abs(h1[d][:, out] - truth[d][:, out]) / np.abs(truth[d][:, out]))
    print(f'direct H1 250-450 Hz: |H1 + 1/C| / |1/C| median {to_c:.3f}, |H1 - P| / |P| '
          f'median {to_p:.1f}')
    assert to_c < 0.1 and to_p > 10


def test_streamed_frames_equal_one_call():
    """Frames added piece by piece (a streamed bag) give what one call on the record gives."""
    rng = np.random.default_rng(3)
    u = rng.standard_normal((6000, 2))
    y = signal.lfilter([0.2, 0.1], [1, -0.7], u, axis=0) + 0.01 * rng.standard_normal((6000, 2))
    whole = LpmAccumulator(FS, 2000)
    whole.add(y, u)
    parts = LpmAccumulator(FS, 2000)
    used = parts.add(y[:2500], u[:2500])
    parts.add(y[used:], u[used:])
    assert used == 2000 and parts.frames == whole.frames == 3
    a, b = whole.result(), parts.result()
    np.testing.assert_allclose(a.frf.response, b.frf.response)
    np.testing.assert_allclose(a.h1.response, b.h1.response)


def test_lpm_removes_the_transient_that_biases_the_etfe():
    """
    A first-order system from a non-zero initial state: the record's DFT holds a transient.

    The empirical transfer function Y/U (no transient term) is biased by it at every line; the
    LPM estimates and removes it (noise free: exact up to the polynomial approximation).
    """
    rng = np.random.default_rng(4)
    n = 4096
    u = rng.standard_normal(n)
    b, a = [0.0, 0.5], [1.0, -0.9]
    y = signal.lfilter(b, a, u, zi=[8.0])[0]
    Y, U = np.fft.rfft(y)[1:], np.fft.rfft(u)[1:]
    f = np.arange(1, n // 2 + 1) / n
    truth = signal.freqz(b, a, worN=2 * np.pi * f)[1]
    fit = lpm_lines(Y, U)
    etfe = np.median(np.abs(Y / U - truth) / np.abs(truth))
    lpm = np.median(np.abs(fit.G[0, 0] - truth) / np.abs(truth))
    print(f'median relative error: ETFE {etfe:.2e}, LPM {lpm:.2e}')
    assert lpm < 1e-3 < etfe


def test_window_too_wide_for_the_record_is_refused():
    with pytest.raises(EstimationError, match='fewer than one LPM window'):
        lpm_lines(np.ones((1, 10)), np.ones((1, 10)))
    assert default_half_width(3) == 10        # q = 21 - 12 = 9 >= 2 (n_in + 1)
