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
"""Refusal checks against analytic cases: clipping, Nyquist band, periods, coverage."""
from frf_ident.core.estimation.checks import (check_band, check_covers, check_not_clipped,
                                              check_periods, clipping, MIN_RUN)
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.errors import EstimationError
import numpy as np
import pytest

FS = 1000.0
T = np.arange(int(2 * FS)) / FS


def _refused(fn, *args, **kw) -> str:
    with pytest.raises(EstimationError) as exc:
        fn(*args, **kw)
    msg = str(exc.value)
    assert '\n' not in msg
    return msg


def test_clipped_sine_fraction_and_run_length_match_the_analytic_values():
    """
    Clip a 1.3 x 150 N m sine at 3 Hz at +-150 N m.

    (2/pi) arccos(1/1.3) of the time is at a limit, each plateau 2 arccos(1/1.3) / (2 pi 3 Hz)
    long.
    """
    u = np.clip(195.0 * np.sin(2 * np.pi * 3.0 * T), -150.0, 150.0)
    s = clipping(u[:, None])[0]
    theta = np.arccos(1 / 1.3)
    assert s.clipped_low and s.clipped_high
    assert s.fraction == pytest.approx(2 * theta / np.pi, abs=0.005)
    assert abs(s.longest_run - 2 * theta / (2 * np.pi * 3.0) * FS) <= 2
    msg = _refused(check_not_clipped, np.column_stack([np.sin(T), u]),
                   joint_names=['joint_1', 'joint_2'], where='bag: /joint_states',
                   span='the multisine segments')
    assert msg.startswith('bag: /joint_states effort[joint_2] is clipped at +-150 N m in 44 % '
                          'of the samples of the multisine segments (runs up to ')
    assert 'expected an unsaturated plant input' in msg


def test_one_sided_clipping_names_the_side():
    u = np.minimum(100.0 * np.sin(2 * np.pi * 2.0 * T) + 20.0, 90.0)
    msg = _refused(check_not_clipped, u[:, None], joint_names=['a'], where='x')
    assert 'effort[a] is clipped at +90 N m' in msg


def test_noisy_multisine_torque_and_its_extremes_are_not_clipping():
    des = design_odd_multisine(1.0, 60.0, bound=150.0, resolution_hz=0.5, fs=FS)
    real = multisine_realisation(des, 1, np.random.default_rng(1), fs=FS)
    u = np.tile(real.evaluate(np.arange(des.period_samples(FS)) / FS)[0][:, 0], 4)
    u = u + 0.5 * np.random.default_rng(2).standard_normal(u.size)
    assert not clipping(u[:, None])[0].clipped
    check_not_clipped(u[:, None], joint_names=['a'], where='x')


@pytest.mark.parametrize('quantum', [0.01, 0.1, 1.0])
def test_quantised_slow_sine_is_not_clipping(quantum):
    """
    Keep a quantised sine apart from a clipped plateau.

    A quantised 2 Hz, 150 N m sine repeats its top value over many samples at each peak
    (with 1 N m steps: ~18 samples, 2 % of the time) but is approached gradually: the
    pile-up test keeps it apart from a plateau.
    """
    u = np.round(150.0 * np.sin(2 * np.pi * 2.0 * T) / quantum) * quantum
    lax = clipping(u[:, None], min_run=2, min_fraction=0.0)[0]
    assert not lax.clipped, lax
    if quantum == 1.0:      # run length and fraction alone would have refused this signal
        at_top = np.abs(u - u.max()) < 1e-9
        d = np.diff(np.concatenate([[0], at_top.astype(int), [0]]))
        runs = np.flatnonzero(d == -1) - np.flatnonzero(d == 1)
        assert runs.max() >= MIN_RUN and at_top.mean() > 1e-3


def test_constant_nan_and_short_runs_are_not_clipping():
    u = np.column_stack([np.full(T.size, 3.0), np.full(T.size, np.nan),
                         np.sin(2 * np.pi * 5 * T)])
    assert not any(s.clipped for s in clipping(u))
    # runs never continue from one stretch into the next
    a = np.concatenate([np.sin(np.linspace(0, 3, 500)), np.full(3, 1.5)])
    b = np.concatenate([np.full(3, 1.5), np.sin(np.linspace(0, 3, 500))])
    assert not clipping([a[:, None], b[:, None]])[0].clipped
    assert clipping([np.concatenate([a, b])[:, None]])[0].clipped


def test_band_below_nyquist():
    check_band([2.0, 49.9], 100.0, where='w')
    msg = _refused(check_band, np.linspace(2.0, 60.0, 30), 100.0, where='bag: /frf/experiment')
    assert msg.startswith('bag: /frf/experiment: band 2-60 Hz reaches the Nyquist frequency 50 '
                          'Hz of the recording (sampled at 100 Hz;')
    assert 'expected every line below fs/2' in msg
    assert 'at or above' in _refused(check_band, [10.0, 50.0], 100.0, where='w')
    assert 'positive' in _refused(check_band, [0.0, 10.0], 100.0, where='w')


def test_periods_and_coverage():
    check_periods(2, where='w')
    msg = _refused(check_periods, 1, where='multisine segment 3.000..9.000 s', hint='more')
    assert msg == ('multisine segment 3.000..9.000 s: 1 whole steady-state period; expected at '
                   'least 2 — more')
    assert 'expected at least 5' in _refused(check_periods, 4, need=5, where='w')
    check_covers(0.0, 9.999, 1.0, 10.0, dt=0.001, where='w')
    msg = _refused(check_covers, 0.0, 5.0, 1.0, 10.0, dt=0.001, where='chirp')
    assert 'segment 1.000..10.000 s but the data cover 0.000..5.000 s' in msg
