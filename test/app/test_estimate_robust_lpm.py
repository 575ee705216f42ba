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
`frf-ident estimate` splits noise and nonlinear variance of ONE multisine realisation (issue 39).

A mass on a spring with a cubic stiffening term, x'' + 2 zeta w x' + w^2 x + k3 x^3 = u
(10 Hz, zeta = 0.5; RK4 written here, not the package's code), driven by one realisation of
an odd multisine for 6 periods from rest, white noise on the measured velocity. Truth from the
structure: with k3 = 0 the system is linear, so the local-polynomial residual at the excited
lines is noise alone and its variance equals the period-spread noise variance; with k3 > 0 the
stochastic nonlinear distortion adds to it. Before, estimate printed and wrote no robust-LPM
variance at all (the BLA's spread over realisations needs several realisations).
"""
import json

from frf_ident.bag import write_recording
from frf_ident.cli import main
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.core.recording import Recording
import numpy as np
import pytest

FS = 250.0
W = 2 * np.pi * 10.0
ZETA = 0.5


def _velocity(u, k3, sub=4):
    """RK4 with the force held over each sample; the velocity at the samples."""
    h = 1 / (FS * sub)

    def f(x, v, uu):
        return v, uu - 2 * ZETA * W * v - W * W * x - k3 * x ** 3
    x = v = 0.0
    out = np.empty(u.size)
    for i, uu in enumerate(u):
        for _ in range(sub):
            ax, av = f(x, v, uu)
            bx, bv = f(x + h / 2 * ax, v + h / 2 * av, uu)
            cx, cv = f(x + h / 2 * bx, v + h / 2 * bv, uu)
            dx, dv = f(x + h * cx, v + h * cv, uu)
            x += h / 6 * (ax + 2 * bx + 2 * cx + dx)
            v += h / 6 * (av + 2 * bv + 2 * cv + dv)
        out[i] = v
    return out


def _bag(tmp_path, cubic):
    des = design_odd_multisine(1.0, 30.0, bound=1.0, resolution_hz=0.2, fs=FS)
    real = multisine_realisation(des, 1, np.random.default_rng(0), fs=FS)
    n = des.period_samples(FS)
    u = np.tile(real.evaluate(np.arange(n) / FS)[0][:, 0], 6)
    # cubic force = `cubic` x the linear spring force at one standard deviation of the
    # linear response's displacement (about std(v) / w)
    x_std = np.std(_velocity(u, 0.0)) / W
    v = _velocity(u, cubic * W * W / x_std ** 2)
    y = v / np.std(v) + 0.1 * np.random.default_rng(1).standard_normal(v.size)
    rec = Recording(np.arange(u.size) / FS, ['j'], np.zeros((u.size, 1)), y[:, None],
                    u[:, None])
    return write_recording(rec, tmp_path / f'duffing{cubic}')


@pytest.mark.parametrize('cubic', [0.0, 0.1])
def test_estimate_splits_noise_and_nonlinear_variance_of_one_realisation(tmp_path, capsys,
                                                                         cubic):
    out = tmp_path / 'est'
    assert main(['estimate', str(_bag(tmp_path, cubic)), '--out', str(out)]) == 0
    text = capsys.readouterr().out
    print(text)
    line, = [x for x in text.splitlines() if 'robust LPM: dq_m/j: nonlinear variance' in x]
    doc = json.loads((out / 'estimates.json').read_text())
    r = next(iter(doc.values()))['meta']['robust_lpm']
    noise, total = np.array(r['noise_variance'][0]), np.array(r['total_variance'][0])
    n_lines, dof, periods = noise.size, r['dof'], r['periods']
    assert r['outputs'] == ['dq_m/j'] and r['units'] == ['(rad/s)^2/(N m)^2']
    assert len(r['freq_hz']) == n_lines == len(r['nonlinear_variance'][0]) and periods >= 4
    assert (out / 'robust_lpm.png').stat().st_size > 10_000 and 'robust_lpm.png' in text
    assert np.allclose(r['nonlinear_variance'][0], np.maximum(total - noise, 0))
    # noise alone: sum(total) / sum(noise) is 1 within its spread. The total's windows
    # (2n+1 = dof + 3 lines) overlap, so it rests on at least n_lines dof / (dof + 3)
    # independent complex dof, the noise on n_lines (periods - 1): relative SD below
    # sqrt(1 / that + 1 / this); 3 SD allowed
    sd = np.sqrt((dof + 3) / (n_lines * dof) + 1 / (n_lines * (periods - 1)))
    ratio = total.sum() / noise.sum()
    print(f'sum total / sum noise {ratio:.2f} (3 SD of noise alone: {3 * sd:.2f}); {line}')
    if cubic:
        assert ratio > 1 + 10 * sd
        assert float(line.split('variance ')[1].split(' dB above')[0]) > 10
        assert r['nonlinear_above_noise_db'][0] > 10
    else:
        assert abs(ratio - 1) < 3 * sd
        # half the lines or more show total <= noise: the median nonlinear variance is below
        # the noise (or none)
        db = r['nonlinear_above_noise_db'][0]
        assert (db is None or db < 0) and ('below noise' in line or 'none above' in line)
