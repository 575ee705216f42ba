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
The LPM with missing output samples (issue 55, item 5) against truth it did not produce.

- the least-squares problem written out with explicit DFT matrices and each window's local
  regressors (the normal matrix of :mod:`frf_ident.core.estimation.missing_lpm` is formed
  from FFTs of its diagonals instead);
- a known filter (its exact FRF), coloured output noise and 200 noise seeds: the spread of
  the estimates of the missing samples and of the FRF against the reported standard
  deviations, beside the LPM of the complete record.
"""
from frf_ident.core.estimation.lpm import lpm_lines
from frf_ident.core.estimation.missing_lpm import lpm_missing
from frf_ident.errors import EstimationError
import numpy as np
import pytest
from scipy import signal

B, A = signal.cheby1(4, 1, 0.3)
NOISE = ([1.0], [1.0, -0.7])


def _frame(rng, n, level=0.05):
    x = rng.standard_normal(n + 500)
    y = signal.lfilter(B, A, x)[500:]
    v = level * signal.lfilter(*NOISE, rng.standard_normal(n + 500))[500:]
    return (y + v)[:, None], x[500:, None]


def _gaps(n, spans):
    gone = np.zeros(n, bool)
    for a, k in spans:
        gone[a:a + k] = True
    return gone


def test_normal_equations_equal_the_explicit_least_squares():
    """Minimise over x and every window's G, T: sum_w |Z0 + E x - K theta|^2, written out."""
    n = 512
    rng = np.random.default_rng(5)
    z, x = _frame(rng, n)
    z = np.concatenate([z, 0.3 * z + 0.01 * rng.standard_normal((n, 1))], axis=1)
    gone = _gaps(n, [(90, 12), (300, 20), (301 + 100, 7)])
    t = np.flatnonzero(gone)
    m = lpm_missing(np.where(gone[:, None], np.nan, z), x)
    X = np.fft.rfft(x, axis=0)[1:].T / np.sqrt(n)
    Z0 = np.fft.rfft(np.where(gone[:, None], 0.0, z), axis=0)[1:].T / np.sqrt(n)
    k = np.arange(1, n // 2 + 1)
    E = np.exp(-2j * np.pi * np.outer(k, t) / n) / np.sqrt(n)          # (L, M)
    # the estimator's windows: 2 n + 1 lines side by side (n from its dof: 2 n + 1 - 6), the
    # rest joined to the last; in each, G and T quadratic in the line offset
    w = m.lines.dof + 6
    edges = list(range(0, k.size - w + 1, w)) + [k.size]
    blocks = []
    for a, b in zip(edges[:-1], edges[1:]):
        pw = np.arange(a - b, 0)[:, None] ** np.arange(3) * 1.0
        blocks.append((a, b, np.concatenate([X[0, a:b, None] * pw, pw], axis=1)))
    n_par = sum(K.shape[1] for *_, K in blocks)
    # unknowns: Re theta, Im theta (all windows), x (real); equations: Re and Im of each line
    M = np.zeros((2 * k.size, 2 * n_par + t.size))
    col = 0
    for a, b, K in blocks:
        p = K.shape[1]
        M[a:b, col:col + p], M[a:b, col + p:col + 2 * p] = K.real, -K.imag
        M[k.size + a:k.size + b, col:col + p] = K.imag
        M[k.size + a:k.size + b, col + p:col + 2 * p] = K.real
        col += 2 * p
    M[:k.size, col:], M[k.size:, col:] = -E.real, -E.imag
    worst = 0.0
    for c in range(z.shape[1]):
        rhs = np.concatenate([Z0[c].real, Z0[c].imag])
        sol = np.linalg.lstsq(M, rhs, rcond=None)[0]
        np.testing.assert_allclose(m.values[:, c], sol[col:], rtol=1e-7, atol=1e-9)
        worst = max(worst, np.max(np.abs(m.values[:, c] - sol[col:])) / np.max(np.abs(sol[col:])))
    print(f'{t.size} estimates against the explicit least squares: largest difference '
          f'{worst:.1e} of the largest estimate')


@pytest.fixture(scope='module')
def monte_carlo():
    n = 4096
    gone = _gaps(n, [(700, 60), (1900, 60), (3000, 60)])
    G0 = signal.freqz(B, A, worN=np.arange(1, n // 2 + 1) * 2 * np.pi / n)[1]
    runs = []
    for seed in range(200):
        z, x = _frame(np.random.default_rng(seed), n)
        m = lpm_missing(np.where(gone[:, None], np.nan, z), x)
        full = lpm_lines(np.fft.rfft(z, axis=0)[1:].T / np.sqrt(n),
                         np.fft.rfft(x, axis=0)[1:].T / np.sqrt(n))
        runs.append((m.lines.G[0, 0], m.lines.variance()[0, 0], m.values[:, 0] - z[gone, 0],
                     m.sd[:, 0], full.G[0, 0], full.variance()[0, 0]))
    return gone, G0, [np.array(v) for v in zip(*runs)]


def test_sd_of_the_estimated_samples_matches_monte_carlo(monte_carlo):
    gone, _, (_, _, err, sd, _, _) = monte_carlo
    ratio = err.std(axis=0) / np.sqrt(np.mean(sd ** 2, axis=0))
    print(f'{gone.sum()} missing samples of {gone.size} (3 gaps), coloured noise, 200 seeds: '
          f'Monte-Carlo sd / reported sd median {np.median(ratio):.3f}, '
          f'5-95 % {np.percentile(ratio, 5):.3f}-{np.percentile(ratio, 95):.3f}')
    assert abs(np.median(ratio) - 1) < 0.1 and np.all(np.abs(ratio - 1) < 0.3)


def test_frf_variance_matches_monte_carlo_and_truth(monte_carlo):
    _, G0, (G, var, _, _, Gf, varf) = monte_carlo
    mc, mcf = np.var(G, axis=0), np.var(Gf, axis=0)
    r, rf = var.mean(axis=0) / mc, varf.mean(axis=0) / mcf
    bias = np.abs(G.mean(axis=0) - G0) / np.sqrt(mc)
    print(f'FRF variance / Monte-Carlo: missing-data LPM median {np.median(r):.3f} '
          f'(10-90 % {np.percentile(r, 10):.2f}-{np.percentile(r, 90):.2f}); complete record '
          f'{np.median(rf):.3f}; Monte-Carlo sd missing / complete '
          f'{np.median(np.sqrt(mc / mcf)):.3f}; |mean - exact FRF| / sd median '
          f'{np.median(bias):.3f}')
    assert abs(np.median(r) - 1) < 0.1 and 0.8 < np.percentile(r, 10)
    assert np.percentile(r, 90) < 1.3 and np.median(bias) < 0.2


def test_what_cannot_be_estimated_is_refused():
    n = 1024
    z, x = _frame(np.random.default_rng(1), n)
    gone = _gaps(n, [(0, 30)])
    with pytest.raises(EstimationError, match='not determined by the data'):
        lpm_missing(np.where(gone[:, None], np.nan, z), x)
    x[500] = np.nan
    with pytest.raises(EstimationError, match='regressor samples missing'):
        lpm_missing(z, x)


def test_without_missing_samples_it_is_the_lpm():
    z, x = _frame(np.random.default_rng(2), 1024)
    m = lpm_missing(z, x)
    full = lpm_lines(np.fft.rfft(z, axis=0)[1:].T / 32, np.fft.rfft(x, axis=0)[1:].T / 32)
    np.testing.assert_array_equal(m.lines.G, full.G)
    assert m.index.size == 0


@pytest.mark.slow
def test_closed_loop_indirect_estimate_over_noise_seeds():
    """
    3-axis closed loop, PRBS on r, 40 dB SNR, 5 % of y and u lost in 4 gaps, r complete.

    Over 20 noise seeds against the robot's exact FRF (2-70 Hz): the estimate's spread
    grows by a few per cent; its reported variance covers the mean-square error about the
    exact FRF. The residual of this record is mostly the local model's own error (the gaps'
    estimates inherit it, so their error repeats over seeds as a bias), and the estimates'
    errors do not cancel in y - P u the way the noise does: the variance is conservative.
    """
    from frf_ident.core.estimation.lpm_frames import LpmAccumulator
    from frf_ident.core.model.schema import default_model_dict, robot_from_dict
    from frf_ident.core.simulation.controller import controller_from_dict
    from frf_ident.core.simulation.analytic import robot_frf_sampled
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    n = 12000
    d = default_model_dict()
    rob = robot_from_dict(d)
    ctrl = controller_from_dict(d, rob)
    rng = np.random.default_rng(7)
    bits = [signal.max_len_seq(16, state=rng.integers(0, 2, 16))[0][:n // 4] for _ in range(3)]
    r = np.repeat(2.0 * np.array(bits, dtype=float).T - 1.0, 4, axis=0) * 0.01
    quiet = FlexibleJointPlant(rob).simulate(reference=r, controller=ctrl.copy())
    for axis, rms in zip(rob.axes, np.std(quiet.velocity, axis=0) / 100.0):
        axis.velocity_noise = float(rms)
    gone = _gaps(n, [(a, 150) for a in (2100, 4700, 7300, 9600)])
    est = {False: [], True: []}
    for seed in range(20):
        plant = FlexibleJointPlant(rob)
        plant.reset(seed=seed)
        s = plant.simulate(reference=r, controller=ctrl.copy())
        for miss in est:
            y, u = s.velocity.copy(), s.effort.copy()
            y[gone & miss], u[gone & miss] = np.nan, np.nan
            acc = LpmAccumulator(1000.0, n)
            acc.add(y, u, r)
            res = acc.result().frf
            est[miss].append((res.response, res.noise_variance))
    band = (res.freq_hz > 2) & (res.freq_hz < 70)
    truth = robot_frf_sampled(rob, res.freq_hz[band])
    out = {}
    for miss, runs in est.items():
        P = np.array([p for p, _ in runs])[..., band]
        var = np.mean([v for _, v in runs], axis=0)[..., band]
        out[miss] = (P.var(axis=0), var / np.mean(np.abs(P - truth) ** 2, axis=0))
    dd = (range(3), range(3))
    grow = np.median(np.sqrt(out[True][0] / out[False][0])[dd])
    print(f'closed loop, {gone.sum()} of {n} samples of y and u missing: Monte-Carlo sd '
          f'missing / complete (driven) median {grow:.3f}; reported variance / mean-square '
          f'error about the exact FRF median {np.median(out[True][1]):.2f} '
          f'(complete record {np.median(out[False][1]):.2f}), 10-90 % '
          f'{np.percentile(out[True][1], 10):.2f}-{np.percentile(out[True][1], 90):.2f}')
    assert grow < 1.15 and 0.8 < np.median(out[False][1]) < 1.25
    assert 0.8 < np.median(out[True][1]) < 1.6
