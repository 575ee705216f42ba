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
"""`frf-ident reproduce paper`: the paper's findings as numbers computed from results.json."""
import json

from frf_ident.app.reproduce import analytic_linear
from frf_ident.cli import main
import numpy as np
import pytest


@pytest.fixture(scope='module')
def results(tmp_path_factory):
    out = tmp_path_factory.mktemp('paper')
    assert main(['reproduce', 'paper', '--out', str(out)]) == 0
    assert (out / 'figure4_coulomb.png').stat().st_size > 10_000
    assert (out / 'figure5_stiffness.png').stat().st_size > 10_000
    return json.loads((out / 'results.json').read_text())


def _est(results, case, design):
    e = results['cases'][case][design]
    return np.asarray(e['freq_hz']), np.asarray(e['re']) + 1j * np.asarray(e['im'])


def _peak(f, p, band=(6.0, 40.0)):
    m = (f >= band[0]) & (f <= band[1])
    k = np.argmax(np.abs(p[m]))
    return f[m][k], 20 * np.log10(np.abs(p[m][k]))


def test_linear_case_both_designs_median_error(results):
    for design in ('multisine', 'chirp'):
        f, p = _est(results, 'linear', design)
        err = 20 * np.log10(np.abs(p / analytic_linear(f)))
        assert np.median(np.abs(err)) <= 0.05, design


def test_coulomb_friction_hides_multisine_resonance_not_chirp(results):
    _, lin = _peak(*_est(results, 'linear', 'multisine'))
    _, lin_c = _peak(*_est(results, 'linear', 'chirp'))
    _, ms = _peak(*_est(results, 'coulomb', 'multisine'))
    _, ch = _peak(*_est(results, 'coulomb', 'chirp'))
    assert lin - ms >= 10.0
    assert abs(lin_c - ch) <= 6.0


def test_nonlinear_stiffness_warps_chirp_not_multisine(results):
    f_dense = np.geomspace(6, 40, 20000)
    f_true = f_dense[np.argmax(np.abs(analytic_linear(f_dense)))]
    fr_ch = results['findings']['peaks']['stiffness/chirp']['resonance_hz']
    fr_ms = results['findings']['peaks']['stiffness/multisine']['resonance_hz']
    assert fr_ch / f_true - 1 >= 0.15
    assert abs(fr_ms / f_true - 1) <= 0.03
    # the same on the raw lines, without the parabolic refinement
    f_ch, _ = _peak(*_est(results, 'stiffness', 'chirp'))
    assert f_ch / f_true - 1 >= 0.15


def test_multisine_power_fraction_of_chirp(results):
    assert 0.11 <= results['power_ratio'] <= 0.20
