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
"""Round trips of the FRF exports (JSON, MAT for idfrd, CSV, python-control)."""
import json
import warnings

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.export import from_control, read_frf, to_control, write_frf
import numpy as np
import pytest
from scipy.io import loadmat


def _frf(n_out=2, n_in=3, n_freq=40, variances=True, seed=0):
    rng = np.random.default_rng(seed)
    shape = (n_out, n_in, n_freq)
    resp = rng.standard_normal(shape) * 10.0 ** rng.uniform(-6, 3, shape) \
        + 1j * rng.standard_normal(shape) * 1e-2
    var = (lambda: rng.uniform(1e-9, 1.0, shape)) if variances else (lambda: None)
    return FrequencyResponse(np.geomspace(1.0 / 3.0, 60.0, n_freq), resp,
                             [f'tau_m,{k + 1}' for k in range(n_in)],
                             [f'dq_m "{k + 1}"' for k in range(n_out)], var(), var(),
                             {'method': 'BLA', 'n_p': 10})


def _assert_same(a, b, rtol=1e-12):
    assert a.inputs == b.inputs and a.outputs == b.outputs
    np.testing.assert_allclose(b.freq_hz, a.freq_hz, rtol=rtol, atol=0)
    np.testing.assert_allclose(b.response, a.response, rtol=rtol, atol=0)
    for name in ('noise_variance', 'total_variance'):
        va, vb = getattr(a, name), getattr(b, name)
        assert (va is None) == (vb is None)
        if va is not None:
            np.testing.assert_allclose(vb, va, rtol=rtol, atol=0)


@pytest.mark.parametrize('suffix', ['.json', '.mat', '.csv'])
@pytest.mark.parametrize('variances', [True, False])
@pytest.mark.parametrize('shape', [(2, 3), (1, 1)])
def test_file_round_trip_exact(tmp_path, suffix, variances, shape):
    frf = _frf(*shape, variances=variances)
    path = write_frf(frf, tmp_path / f'frf{suffix}')
    back = read_frf(path)
    _assert_same(frf, back)
    assert np.array_equal(back.response, frf.response)      # in fact bit-exact
    if suffix != '.csv':
        assert back.meta == frf.meta


def test_mat_has_idfrd_layout(tmp_path):
    frf = _frf(2, 3, 40)
    d = loadmat(write_frf(frf, tmp_path / 'g.mat'))
    assert d['ResponseData'].shape == (2, 3, 40) and np.iscomplexobj(d['ResponseData'])
    assert d['Frequency'].shape == (40, 1)
    assert str(d['FrequencyUnit'][0]) == 'Hz'
    assert d['InputName'].shape == (3, 1) and d['InputName'].dtype == object
    assert [str(c[0]) for c in d['InputName'][:, 0]] == frf.inputs
    assert d['CovarianceData'].shape == (2, 3, 40, 2, 2)
    np.testing.assert_allclose(d['CovarianceData'][..., 0, 0] * 2, frf.total_variance)
    assert json.loads(str(d['Meta'][0])) == frf.meta


def test_csv_long_format(tmp_path):
    frf = _frf(2, 3, 5)
    lines = write_frf(frf, tmp_path / 'g.csv').read_text().splitlines()
    assert lines[0] == 'output,input,freq_hz,re,im,noise_variance,total_variance'
    assert len(lines) == 1 + 2 * 3 * 5
    assert lines[1].startswith('"dq_m ""1""","tau_m,1",0.333333')


def test_python_control_round_trip():
    frf = _frf(2, 3, 40, variances=False)
    sys = to_control(frf)
    np.testing.assert_allclose(sys.omega, 2 * np.pi * frf.freq_hz, rtol=1e-12)
    fresp = sys.frdata if hasattr(sys, 'frdata') else sys.fresp   # fresp is deprecated in 0.10.1
    np.testing.assert_allclose(fresp, frf.response, rtol=1e-12, atol=0)
    assert list(sys.input_labels) == frf.inputs and list(sys.output_labels) == frf.outputs
    # evaluating the FRD at its own frequencies gives the data back
    np.testing.assert_allclose(sys(1j * sys.omega[7]), frf.response[..., 7], rtol=1e-12)
    with warnings.catch_warnings():   # FrequencyResponse.from_control reads .fresp
        warnings.simplefilter('ignore', FutureWarning)
        _assert_same(frf, from_control(sys))


@pytest.mark.parametrize('name, text, needle', [
    ('a.json', '{"freq_hz": [1], "re": [[[1]]]}', "lacks the field 'im'"),
    ('a.json', '[1, 2]', 'expected a JSON object'),
    ('a.json', '{"freq_hz": [1, 2], "re": [[[1]]], "im": [[[1]]]}', 'response must be shaped'),
    ('a.csv', 'output,input,freq_hz,re\n', "header lacks ['im']"),
    ('a.csv', 'output,input,freq_hz,re,im\ny,u,1,x,0\n', 'line 2'),
    ('a.csv', 'output,input,freq_hz,re,im\ny,u,1,0,0\ny,v,2,0,0\n', 'other frequencies'),
    ('a.mat', 'not a mat file', 'cannot read MAT file'),
    ('a.txt', '', "unknown format '.txt'"),
])
def test_bad_files_one_line(tmp_path, name, text, needle):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(FrfIdentInputError) as err:
        read_frf(path)
    assert needle in str(err.value) and '\n' not in str(err.value)


def test_refuses_overwrite(tmp_path):
    path = write_frf(_frf(), tmp_path / 'g.json')
    with pytest.raises(FrfIdentInputError, match='refusing to overwrite'):
        write_frf(_frf(), path)
    write_frf(_frf(seed=1), path, overwrite=True)
    assert read_frf(path).response[0, 0, 0] == _frf(seed=1).response[0, 0, 0]
