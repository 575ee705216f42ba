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
Map layouts: one shaker and many accelerometers, outputs kept as measured (issue 39).

A shaker force (odd multisine, 4 periods) drives three modes (5, 12, 30 Hz); each
accelerometer is the force through its own mode's discrete transfer function (scipy's
lfilter): the analytic accelerance is the truth. Before, the only way to map it was the force
as the effort of every sensor (refused: 'other inputs are excited at the same lines', printed
as '0 multisine periods ... remain of 0') or a 1e-9 scale trick.
"""
import json

from frf_ident.bag import write_recording
from frf_ident.cli import main
from frf_ident.core.estimation.detected import estimate_in_blocks, RecordingBlocks
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.errors import EstimationError, FrfIdentInputError
from frf_ident.io.importer import import_table
import numpy as np
import pytest
from scipy import signal

FS = 500.0
MODES = (5.0, 12.0, 30.0)


def _accel_tf(f_hz):
    """Accelerance of a unit-mass mode: s^2 / (s^2 + 2 zeta w s + w^2), bilinear."""
    w = 2 * np.pi * f_hz
    b, a, _ = signal.cont2discrete(([1, 0, 0], [1, 0.1 * w, w * w]), 1 / FS, method='bilinear')
    return b[0], a


@pytest.fixture(scope='module')
def shaker_csv(tmp_path_factory):
    des = design_odd_multisine(1.0, 60.0, bound=1.0, resolution_hz=0.5, fs=FS)
    real = multisine_realisation(des, 1, np.random.default_rng(0), fs=FS)
    n = des.period_samples(FS)
    force = np.tile(real.evaluate(np.arange(n) / FS)[0][:, 0], 4)
    acc = [signal.lfilter(*_accel_tf(f), force) for f in MODES]
    rng = np.random.default_rng(1)
    acc = [a + 1e-4 * np.std(a) * rng.standard_normal(a.size) for a in acc]
    path = tmp_path_factory.mktemp('shaker') / 'shaker.csv'
    rows = zip((np.arange(force.size) / FS).tolist(), force.tolist(),
               *[a.tolist() for a in acc])
    path.write_text('t,F,a1,a2,a3\n' + '\n'.join(','.join(repr(v) for v in r) for r in rows))
    return path


def _layout(**over):
    mp = {'frf_ident_map': 1, 'time': {'column': 't'},
          'inputs': [{'name': 'shaker', 'signal': 'F', 'unit': 'N'}],
          'outputs': [{'name': f'acc_{k + 1}', 'signal': f'a{k + 1}',
                       'quantity': 'acceleration', 'unit': 'm/s^2'} for k in range(3)]}
    mp.update(over)
    return mp


def test_one_shaker_many_accelerometers_gives_the_accelerance(shaker_csv, tmp_path, capsys):
    rec = import_table(shaker_csv, _layout())
    assert rec.meta['layout']['outputs'][0]['quantity'] == 'acceleration'
    bag = write_recording(rec, tmp_path / 'bag')
    assert main(['estimate', str(bag), '--out', str(tmp_path / 'est')]) == 0
    doc = json.loads((tmp_path / 'est' / 'frf.json').read_text())
    assert doc['inputs'] == ['tau_m/shaker']
    assert doc['outputs'] == ['dq_m/acc_1', 'dq_m/acc_2', 'dq_m/acc_3']   # outputs only
    f = np.asarray(doc['freq_hz'])
    z = np.exp(2j * np.pi * f / FS)
    P = np.asarray(doc['response_re']) + 1j * np.asarray(doc['response_im']) \
        if 'response_re' in doc else None
    est = json.loads((tmp_path / 'est' / 'estimates.json').read_text())
    d = next(iter(est.values()))['meta']['distortion']
    assert d['units'] == ['m/s^2'] * 3
    from frf_ident.app.estimate import frf_units
    from frf_ident.core.estimation.frd import FrequencyResponse as Frd
    assert frf_units(Frd.from_dict(next(iter(est.values())))) == '(m/s^2)/(N)'
    if P is None:      # the FRD layout of frf.json: compare through the Python API
        from frf_ident.core.estimation.frd import FrequencyResponse
        P = FrequencyResponse.from_dict(doc).response
    for o, fm in enumerate(MODES):
        b, a = _accel_tf(fm)
        err = np.abs(P[o, 0] / (np.polyval(b, z) / np.polyval(a, z)) - 1)
        # 1e-4 output noise: far below 1 % except where the accelerance is 50 dB down
        assert np.median(err) < 1e-3 and np.max(err) < 0.05, (fm, np.max(err))
    out = capsys.readouterr().out
    assert 'distortion above the noise' in out and ' dq_m/acc_1 ' in out


def test_derived_velocity_from_acceleration(shaker_csv):
    mp = _layout()
    mp['outputs'][0]['derive'] = 'velocity'
    rec = import_table(shaker_csv, mp)
    out = rec.meta['layout']['outputs'][0]
    assert out['quantity'] == 'velocity' and out['measured'] == 'acceleration'
    assert out['unit'] == 'm/s' and 'acc_1.output' in rec.meta['import']['derived']


@pytest.mark.parametrize('change, match', [
    ({'outputs': [{'name': 'a', 'signal': 'F', 'quantity': 'acceleration'}]},
     'a map refers to a signal once'),
    ({'outputs': [{'name': 'a', 'signal': 'a1', 'quantity': 'jerk'}]}, 'quantity='),
    ({'outputs': [{'name': 'a', 'signal': 'a1', 'quantity': 'position', 'derive': 'force'}]},
     'derive='),
    ({'joints': [{'name': 'j', 'position': 'a1', 'effort': 'F'}]}, 'both given'),
])
def test_layout_errors_are_one_line(shaker_csv, change, match):
    with pytest.raises(FrfIdentInputError, match=match) as err:
        import_table(shaker_csv, _layout(**change))
    assert '\n' not in str(err.value)


def test_force_repeated_per_joint_says_the_real_reason(shaker_csv):
    """The old way (the force as every joint's effort): the reason, not '0 periods of 0'."""
    mp = {'frf_ident_map': 1, 'time': {'column': 't'},
          'joints': [{'name': f'acc_{k}', 'velocity': f'a{k}', 'effort': 'F'}
                     for k in (1, 2, 3)]}
    rec = import_table(shaker_csv, mp)
    with pytest.raises(EstimationError) as err:
        estimate_in_blocks(RecordingBlocks(rec))
    text = str(err.value)
    assert 'other inputs are excited at the same lines' in text and 'remain' not in text


def test_two_shakers_one_accelerometer(tmp_path):
    """
    Many inputs to one output: two shakers on interleaved odd lines at once, one sensor.

    Shaker 1 excites lines 1, 5, 9, ..., shaker 2 lines 3, 7, 11, ... of a 1024-sample period;
    each input is detected on its own lines and estimated against the one output; the truths
    are the two analytic accelerances (5 Hz and 12 Hz paths).
    """
    n, rng = 1024, np.random.default_rng(2)
    k = np.arange(4 * n)

    def multisine(lines):
        ph = rng.uniform(0, 2 * np.pi, lines.size)
        return np.cos(2 * np.pi * np.outer(k, lines) / n + ph).sum(axis=1)
    f1, f2 = multisine(np.arange(1, 120, 4)), multisine(np.arange(3, 120, 4))
    acc = signal.lfilter(*_accel_tf(MODES[0]), f1) + signal.lfilter(*_accel_tf(MODES[1]), f2)
    acc = acc + 1e-4 * np.std(acc) * rng.standard_normal(acc.size)
    rows = zip((k / FS).tolist(), f1.tolist(), f2.tolist(), acc.tolist())
    path = tmp_path / 'two.csv'
    path.write_text('t,F1,F2,a\n' + '\n'.join(','.join(repr(v) for v in r) for r in rows))
    mp = {'frf_ident_map': 1, 'time': {'column': 't'},
          'inputs': [{'name': 'shaker_1', 'signal': 'F1', 'unit': 'N'},
                     {'name': 'shaker_2', 'signal': 'F2', 'unit': 'N'}],
          'outputs': [{'name': 'acc', 'signal': 'a', 'quantity': 'acceleration',
                       'unit': 'm/s^2'}]}
    est = estimate_in_blocks(RecordingBlocks(import_table(path, mp)))
    assert sorted(est) == ['detected/shaker_1', 'detected/shaker_2']
    for name, fm in (('shaker_1', MODES[0]), ('shaker_2', MODES[1])):
        frf = est[f'detected/{name}']
        assert frf.inputs == [f'tau_m/{name}'] and frf.outputs == ['dq_m/acc']
        z = np.exp(2j * np.pi * frf.freq_hz / FS)
        b, a = _accel_tf(fm)
        err = np.abs(frf.response[0, 0] / (np.polyval(b, z) / np.polyval(a, z)) - 1)
        assert np.median(err) < 1e-3 and np.max(err) < 0.05, (name, np.max(err))


def test_one_shaker_driven_by_noise_gives_the_accelerance_through_the_lpm(tmp_path):
    """
    A noise-driven shaker (no period: the LPM route) keeps the layout's outputs only.

    Before, the LPM took every channel as an output: the shaker's own channel (no motion)
    became a fourth output, and the units of the accelerometers were lost, so the Bode axis
    claimed (rad/s)/(N m). Truth: the analytic accelerance of each mode (lfilter).
    """
    rng = np.random.default_rng(3)
    b_lp, a_lp = signal.butter(4, 80.0, fs=FS)
    force = signal.lfilter(b_lp, a_lp, rng.standard_normal(int(60 * FS)))
    acc = [signal.lfilter(*_accel_tf(f), force) for f in MODES]
    acc = [a + 1e-3 * np.std(a) * rng.standard_normal(a.size) for a in acc]
    path = tmp_path / 'noise.csv'
    rows = zip((np.arange(force.size) / FS).tolist(), force.tolist(),
               *[a.tolist() for a in acc])
    path.write_text('t,F,a1,a2,a3\n' + '\n'.join(','.join(repr(v) for v in r) for r in rows))
    bag = write_recording(import_table(path, _layout()), tmp_path / 'bag')
    assert main(['-q', 'estimate', str(bag), '--out', str(tmp_path / 'est')]) == 0
    est = json.loads((tmp_path / 'est' / 'estimates.json').read_text())
    from frf_ident.app.estimate import frf_units
    from frf_ident.core.estimation.frd import FrequencyResponse
    lpm = FrequencyResponse.from_dict(est['lpm'])
    assert lpm.inputs == ['tau_m/shaker']
    assert lpm.outputs == ['dq_m/acc_1', 'dq_m/acc_2', 'dq_m/acc_3']
    assert frf_units(lpm) == '(m/s^2)/(N)'
    band = (lpm.freq_hz > 2.0) & (lpm.freq_hz < 70.0)
    z = np.exp(2j * np.pi * lpm.freq_hz[band] / FS)
    for o, fm in enumerate(MODES):
        b, a = _accel_tf(fm)
        err = np.abs(lpm.response[o, 0, band] / (np.polyval(b, z) / np.polyval(a, z)) - 1)
        assert np.median(err) < 0.01, (fm, np.median(err))
