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
The pose model's least squares on a case solved by hand: a planar two-link arm.

M(q) of a planar arm with two revolute joints is [[a + 2 b cos q2, c + b cos q2], [c + b cos
q2, c]] in three parameters (a, b, c); a fourth parameter that M never depends on stands for
the combinations a campaign of poses does not see. With the entries observed at a few q2 with
noise of known standard deviation, the fit must find a, b, c within their standard errors (the
errors checked by Monte-Carlo), leave the fourth at its prior and report rank 3; the pooled
mean of pose-independent values must be the inverse-variance weighted mean.
"""
from frf_ident.core.fit.pose_model import (fit_inertial_parameters, median_db_error,
                                           pool_drive)
import numpy as np

TRUE = np.array([12.0, 2.5, 3.0, 7.0])
PRIOR = np.array([10.0, 2.0, 3.5, 5.0])
Q2 = np.linspace(-1.2, 1.5, 6)
STD = np.array([0.05, 0.02, 0.01])              # a, off-diagonal, c entries [kg m^2]


def regressor(q2):
    c = np.cos(q2)
    return np.array([[1, 2 * c, 0, 0], [0, c, 1, 0], [0, 0, 1, 0]], dtype=float)


def test_planar_arm_parameters_and_their_errors():
    y = np.stack([regressor(q) for q in Q2])
    rng = np.random.default_rng(11)
    std = np.broadcast_to(STD, (Q2.size, 3))
    fits = []
    for _ in range(300):
        obs = y @ TRUE + std * rng.standard_normal(std.shape)
        fits.append(fit_inertial_parameters(y, obs, std, PRIOR, per_link=4))
    first = fits[0]
    assert first.rank == 3 and first.n_obs == 18
    values = np.array([f.value for f in fits])
    assert np.all(values[:, 3] == PRIOR[3])           # unseen: the prior is kept
    assert first.std[3] == 0.0
    np.testing.assert_allclose(values[:, :3].mean(axis=0), TRUE[:3],
                               atol=4 * first.std[:3].max() / np.sqrt(len(fits)))
    np.testing.assert_allclose(values[:, :3].std(axis=0), first.std[:3], rtol=0.2)
    assert first.rms_before > 10 and 0.5 < first.rms_after < 1.5


def test_entries_not_fitted_are_left_out():
    y = np.stack([regressor(q) for q in Q2])
    obs = y @ TRUE
    obs[:, 1] = np.nan                                 # no coupling fitted (per-axis fits)
    fit = fit_inertial_parameters(y, obs, np.full(obs.shape, 0.01), PRIOR, per_link=4)
    assert fit.n_obs == 12
    np.testing.assert_allclose(fit.value[:3], TRUE[:3], rtol=1e-9)


def test_pooling_weights_and_scatter():
    v = np.array([[1.0, 10.0], [2.0, 10.0], [8.0, 10.0]])
    s = np.array([[1.0, 1.0], [1.0, 2.0], [2.0, 1.0]])
    mean, sd = pool_drive(v, s)
    np.testing.assert_allclose(mean, [np.average(v[:, 0], weights=1 / s[:, 0] ** 2), 10.0])
    assert sd[1] == 1 / np.sqrt(2.25)                  # no scatter: the errors alone
    assert sd[0] > 1 / np.sqrt(2.25)                   # scatter beyond the errors: inflated


def test_median_db_error():
    m = np.ones(4, complex)
    p = m * 10 ** (np.array([0.0, -1, 1, 2]) / 20)
    assert abs(median_db_error(p, m) - 1.0) < 1e-12
    assert abs(median_db_error(p, m, 1.0) - 2.0) < 1e-12
    assert np.isnan(median_db_error(np.zeros(3), np.ones(3)))
