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
Missing samples of periodic records estimated from the other periods (issue 55, item 5).

Truth the estimator did not produce: the least-squares solution of the missing-data model
written out with explicit DFT matrices, Monte-Carlo runs over noise seeds of a periodic
signal with coloured noise whose missing samples are known, and a known drift.
"""
from frf_ident.core.estimation.missing_periodic import (fill_periods, fill_steady_periods,
                                                        FilledPeriods)
from frf_ident.core.estimation.spectra import best_linear_approximation, periodic_spectra
import numpy as np
import pytest
from scipy import signal

N_PER = 256
P = 6
#: (period, first sample, length): every period touched, two gaps overlapping in phase
GAPS = [(0, 20, 30), (1, 100, 25), (2, 110, 30), (3, 200, 20), (4, 40, 35), (5, 150, 30)]


def _mask(n_q=P, n_per=N_PER, gaps=GAPS):
    m = np.zeros((n_q, n_per), bool)
    for q, a, n in gaps:
        m[q, a:a + n] = True
    return m


def _record(rng, n_q=P, n_ch=2, level=0.1):
    """Periodic signal (random-phase multisine) plus AR(1) noise, (n_q, N_PER, n_ch)."""
    t = np.arange(N_PER)
    k = np.arange(1, 40, 2)
    s = np.sum(np.cos(2 * np.pi * np.outer(t, k) / N_PER + rng.uniform(0, 2 * np.pi, k.size)),
               axis=1)
    noise = signal.lfilter([1.0], [1.0, -0.7], rng.standard_normal((n_q * N_PER + 200, n_ch)),
                           axis=0)[200:] * level
    return s[None, :, None] + noise.reshape(n_q, N_PER, n_ch), s


def test_the_fill_is_the_least_squares_solution_of_the_missing_data_model():
    """
    The per-phase mean equals min_x ||P_nh (Z0 + E x)||^2 solved with explicit matrices.

    P_nh keeps the DFT lines of the whole record that are not multiples of P (the periodic
    response is free at those); the standard deviation sigma sqrt(1 + 1/n_phi) is the
    diagonal of sigma^2 (E^H P_nh E)^-1 (unitary DFT, all lines).
    """
    rng = np.random.default_rng(1)
    n_q, n_per = 4, 16
    miss = _mask(n_q, n_per, [(0, 2, 3), (1, 3, 2), (2, 9, 4), (3, 3, 1)])
    x = rng.standard_normal((n_q, n_per, 2))
    n = n_q * n_per
    t = np.flatnonzero(miss.ravel())
    F = np.fft.fft(np.eye(n)) / np.sqrt(n)                       # unitary DFT
    keep = np.arange(n) % n_q != 0                                # non-harmonic lines
    E = F[keep][:, t]
    z0 = np.where(miss[:, :, None], 0.0, x).reshape(n, 2)
    Z0 = F[keep] @ z0
    # real unknowns: stack real and imaginary parts
    A = np.concatenate([E.real, E.imag])
    b = -np.concatenate([Z0.real, Z0.imag])
    ls = np.linalg.lstsq(A, b, rcond=None)[0]
    fill = fill_periods(x, miss, trend=False)
    np.testing.assert_allclose(fill.values.reshape(n, 2)[t], ls, atol=1e-12)
    print(f'period mean against the explicit least squares: largest difference '
          f'{np.max(np.abs(fill.values.reshape(n, 2)[t] - ls)):.1e}')
    cov = np.linalg.inv(np.real(np.conj(E).T @ E))
    k = fill.sd() / fill.noise_sd[None, :]
    np.testing.assert_allclose(k[:, 0] ** 2, np.diag(cov), rtol=1e-12)


def test_standard_deviation_of_the_estimates_matches_monte_carlo():
    """
    Estimate minus true sample over 400 noise seeds against the reported sd (coloured noise).

    Bound: within 10 % per sample in the median, 30 % at every sample (the Monte-Carlo sd of
    400 runs is itself 3.5 % uncertain).
    """
    miss = _mask()
    err, sd = [], []
    for seed in range(400):
        x, _ = _record(np.random.default_rng(seed))
        fill = fill_periods(np.where(miss[:, :, None], np.nan, x), miss)
        err.append(fill.values[miss] - x[miss])
        sd.append(fill.sd())
    ratio = np.std(err, axis=0) / np.sqrt(np.mean(np.square(sd), axis=0))
    print(f'Monte-Carlo sd / reported sd of {miss.sum()} estimated samples x 2 channels: '
          f'median {np.median(ratio):.3f}, range {ratio.min():.3f}-{ratio.max():.3f}')
    assert abs(np.median(ratio) - 1) < 0.1 and np.all(np.abs(ratio - 1) < 0.3)


def test_bla_noise_variance_with_estimated_samples_matches_monte_carlo():
    """
    The BLA of filled periods: its noise variance against the spread over 400 seeds.

    y = G u (a periodic multisine through a 4th-order filter, steady state) plus coloured
    output noise; every period misses 8 to 14 % of its samples. The spread over periods with
    the estimates in place underestimates the variance of their mean (they carry no noise of
    their own): :class:`FilledPeriods` corrects the dof and the variance of the mean.
    """
    b, a = signal.cheby1(4, 1, 0.3)
    miss = _mask()
    bins = np.arange(1, 40, 2)
    P_est, var, var_raw = [], [], []
    for seed in range(400):
        rng = np.random.default_rng(seed)
        t = np.arange(N_PER * (P + 2))
        k = bins
        u = np.sum(np.cos(2 * np.pi * np.outer(t, k) / N_PER + np.random.default_rng(7)
                          .uniform(0, 2 * np.pi, k.size)), axis=1)
        y = signal.lfilter(b, a, u)[2 * N_PER:] + 0.05 * signal.lfilter(
            [1.0], [1.0, -0.7], rng.standard_normal(P * N_PER))
        u = u[2 * N_PER:]
        x = np.stack([u, y], axis=1).reshape(P, N_PER, 2)
        fill = fill_periods(np.where(miss[:, :, None], np.nan, x), miss)
        X = periodic_spectra(fill.values, bins, axis=1)            # (P, F, 2)
        Y, U = X[:, :, 1, None, None], X[:, :, 0, None, None]
        bla = best_linear_approximation([Y], [U], filled=[fill.periods()])
        raw = best_linear_approximation([Y], [U])
        P_est.append(bla.response[0, 0])
        var.append(bla.noise_variance[0, 0])
        var_raw.append(raw.noise_variance[0, 0])
    mc = np.var(P_est, axis=0, ddof=1)
    r, r_raw = np.mean(var, axis=0) / mc, np.mean(var_raw, axis=0) / mc
    print(f'BLA noise variance / Monte-Carlo over {len(bins)} lines: median {np.median(r):.3f} '
          f'({r.min():.2f}-{r.max():.2f}); without the correction {np.median(r_raw):.3f}; '
          f'scale {fill.periods().spread_scale():.3f}')
    assert abs(np.median(r) - 1) < 0.1 and abs(np.median(r_raw) - 1) > abs(np.median(r) - 1)


def test_spread_scale_is_one_without_estimated_samples():
    assert FilledPeriods(np.zeros(5), np.ones(5)).spread_scale() == 1.0
    fill = fill_periods(np.ones((3, 4, 1)), np.zeros((3, 4), bool))
    assert fill.complete and fill.factor == 1.0 and fill.periods().spread_scale() == 1.0


def test_a_sample_missing_in_every_period_is_not_estimated():
    miss = np.zeros((3, 8), bool)
    miss[:, 5] = True
    miss[1, 2] = True
    fill = fill_periods(np.ones((3, 8, 1)), miss)
    assert not fill.complete and np.isnan(fill.values[:, 5]).all()
    assert fill.values[1, 2, 0] == 1.0


def test_a_start_up_transient_is_left_out_of_the_estimates():
    """
    A transient in the first period would bias every estimate averaged over it by 1/n_phi.

    With the first period decaying from 5x the signal, the estimates from all periods are off
    by the transient's share; from the steady ones they are within the noise.
    """
    rng = np.random.default_rng(3)
    x, s = _record(rng, n_ch=1, level=0.01)
    x[0, :, 0] += 5 * np.exp(-np.arange(N_PER) / 40.0)
    miss = _mask()
    bad = fill_periods(np.where(miss[:, :, None], np.nan, x), miss)
    good = fill_steady_periods(np.where(miss[:, :, None], np.nan, x), miss,
                               lambda v: 1)
    m = miss.copy()
    m[0] = False                                   # the transient period's own gap
    e_bad = np.abs(bad.values[m] - x[m]).max()
    e_good = np.abs(good.values[m] - x[m]).max()
    print(f'largest error of the estimates: {e_bad:.3f} from all periods, {e_good:.3f} from '
          f'the steady ones (noise sd {good.noise_sd[0]:.3f})')
    assert e_good < 5 * good.noise_sd[0] < e_bad
    assert good.average.tolist() == [False] + [True] * (P - 1)


def test_a_drift_is_followed_across_the_gap():
    """
    A non-periodic drift (a ramp of 3x the noise per period, and a step) misleads the mean.

    The period mean alone puts the other periods' drift into the gap; the straight line
    through the residual on both sides of it follows the drift.
    """
    rng = np.random.default_rng(4)
    x, _ = _record(rng, n_ch=1, level=0.01)
    t = np.arange(P * N_PER).reshape(P, N_PER)
    x[:, :, 0] += 0.03 * t / N_PER + 0.2 * (t > 2.5 * N_PER)
    miss = _mask()
    miss[2] = False                                # the step's period has no gap
    gaps = np.where(miss[:, :, None], np.nan, x)
    plain = fill_periods(gaps, miss, trend=False)
    line = fill_periods(gaps, miss)
    e_plain = np.sqrt(np.mean((plain.values[miss] - x[miss]) ** 2))
    e_line = np.sqrt(np.mean((line.values[miss] - x[miss]) ** 2))
    print(f'rms error of the estimates under a drift: {e_plain:.4f} (period mean), {e_line:.4f} '
          f'(with the line across the gap); noise sd 0.014')
    assert e_line < 0.3 * e_plain and e_line < 0.03


@pytest.mark.slow
def test_closed_loop_robot_over_noise_seeds():
    """
    The simulated 3-axis robot in closed loop (test/bag/replay_synth.py), 20 noise seeds.

    6 periods of a multisine on joint_2, white measurement noise (the velocity's fed back),
    a 0.45 s gap in every period (5.5 %). The estimates of the missing torque and velocity
    samples from the steady periods against the simulated truth, and the detected estimate's
    FRF variance against its spread over the seeds, with and without the gaps.
    """
    import copy
    from pathlib import Path
    import sys
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / 'bag'))
    from replay_synth import multisine_run
    from frf_ident.core.estimation.described import estimate_recording
    n_per, n_q = 8192, 6
    miss = np.zeros((n_q, n_per), bool)
    for q, a in enumerate([1300, 5100, 2700, 6900, 600, 4000]):
        miss[q, a:a + 450] = True
    err, sd, est = [], [], {False: [], True: []}
    for seed in range(20):
        rec = multisine_run(n_q, velocity_noise=2e-5, torque_noise=0.05, noise_seed=seed)
        x = np.concatenate([rec.effort, rec.velocity], axis=1).reshape(n_q, n_per, -1)
        fill = fill_periods(np.where(miss[:, :, None], np.nan, x), miss,
                            average=np.arange(n_q) >= 1)          # period 0: the transient
        err.append(fill.values[miss] - x[miss])
        sd.append(fill.sd())
        gap = copy.deepcopy(rec)
        for s in (gap.velocity, gap.effort, gap.position, gap.reference):
            s[miss.ravel()] = np.nan
        for k, r in ((False, rec), (True, gap)):
            e = estimate_recording(r)['detected/joint_2']
            est[k].append((e.response, e.noise_variance))
    ratio = np.std(err, axis=0) / np.sqrt(np.mean(np.square(sd), axis=0))
    ch = [1, 3, 4, 5]                                       # torque of joint_2, velocities
    q = {k: np.mean([v for _, v in runs], axis=0) / np.var([p for p, _ in runs], axis=0)
         for k, runs in est.items()}
    grow = np.median(np.sqrt(np.var([p for p, _ in est[True]], axis=0)
                             / np.var([p for p, _ in est[False]], axis=0)))
    print(f'robot, 20 seeds: sd of the estimated samples (Monte-Carlo / reported) median per '
          f'channel {", ".join(f"{np.median(ratio[:, c]):.3f}" for c in ch)}; FRF variance / '
          f'Monte-Carlo median {np.median(q[True]):.3f} (without gaps {np.median(q[False]):.3f})'
          f'; spread with gaps / without {grow:.3f}')
    assert np.all(np.abs(np.median(ratio[:, ch], axis=0) - 1) < 0.3)
    assert abs(np.median(q[True]) - 1) < 0.3 and grow < 1.2
