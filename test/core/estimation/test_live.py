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
The live multisine estimate, the uncertainty target and the early warnings.

- fed sample by sample from a closed-loop run, the estimate after the last period equals the
  offline estimate of the recording (and of its bag, written and read back) to 1e-9;
- the multiple coherence equals |mean X|^2 / mean |X|^2 on periodic SISO data;
- on the 3-axis robot with noise a 0.5 dB target ends the multisine before its configured
  periods, and the FRF is within 0.5 dB of the analytic one on >= 95 % of the lines;
- the predicted periods left follow sd ~ 1/sqrt(periods);
- a dead output channel raises ``low_coherence``, a normal run none; the torque warning;
- a vibration growing on one output at a non-excited line raises ``rising_distortion`` for
  that output and line, the same run without it none;
- the offline runner's live estimates (``on_estimate``) leave the run as it was.
"""
from __future__ import annotations

from frf_ident.core.estimation.described import estimate_recording
from frf_ident.core.estimation.early_warnings import FAR_BELOW_DB, NEAR_LIMIT, WarningMonitor
from frf_ident.core.estimation.live import LiveMultisine, multiple_coherence
from frf_ident.core.estimation.target import MIN_STOP_PERIODS, UncertaintyTarget
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.model.schema import default_model_dict, robot_from_dict
from frf_ident.core.simulation.analytic import robot_frf_sampled
from frf_ident.core.simulation.controller import controller_from_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.core.simulation.runner import IdentificationConfig, run_identification
from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest


def _robot(noise: float):
    """Return the 3-axis model (linear: no gravity) with velocity noise, and its PI."""
    d = default_model_dict()
    rob = robot_from_dict(d)
    for a in rob.axes:
        a.velocity_noise = noise
        a.gravity_torque = 0.0
    return rob, controller_from_dict(d, rob)


def _feed(rec, live: LiveMultisine, dead: int | None = None, add=None):
    """
    Stream a recording into ``live`` sample by sample; return every estimate.

    ``dead``: that output is replaced by noise; ``add(t)``: added to the measured outputs.
    """
    k_of = lambda t: int(round(t * rec.fs))     # noqa: E731
    starts = {}
    for s in rec.segments:
        starts.setdefault(k_of(s.t_start), []).append(s)
    rng = np.random.default_rng(5)
    out = []
    for k in range(rec.t.size):
        for s in starts.get(k, []):
            live.start(s.info, k_of(s.t_start), k_of(s.t_end))
        live.excitation(k, rec.excitation[k])
        y = rec.velocity[k].copy()
        if dead is not None:
            y[dead] = 1e-3 * rng.standard_normal()
        if add is not None:
            y += add(rec.t[k])
        for done in live.sample(k, rec.position[k], y, rec.effort[k]):
            est = live.update(done)
            if est is not None:
                out.append(est)
    return out


@pytest.fixture(scope='module')
def run():
    rob, ctrl = _robot(4.5e-6)
    ms = MultisineConfig(n_realisations=2, n_periods=3, resolution_hz=1.0, settle_s=0.3,
                         return_s=1.0)
    return run_identification(FlexibleJointPlant(rob), ctrl, IdentificationConfig(ms, None))


def test_live_after_last_period_equals_offline_and_bag(run, tmp_path):
    from frf_ident.bag import read_recording, write_recording
    ests = _feed(run, LiveMultisine(run.joint_names, run.fs, 0))
    # one estimate per MIMO period from the second on: 3 + 3 periods, the first refused
    assert [e.periods for e in ests] == [2, 3, 4, 5, 6]
    offline = estimate_recording(run)['multisine']
    bag = write_recording(run, tmp_path / 'bag')
    from_bag = estimate_recording(read_recording(bag)[0])['multisine']
    last = ests[-1].frf
    for ref in (offline, from_bag):
        assert np.max(np.abs(last.response - ref.response) / np.abs(ref.response)) < 1e-9
        for a, b in ((last.total_variance, ref.total_variance),
                     (last.noise_variance, ref.noise_variance)):
            assert np.max(np.abs(a - b) / b) < 1e-9


def test_multiple_coherence_periodic_siso():
    rng = np.random.default_rng(0)
    n_q, F = 6, 7
    R = np.exp(2j * np.pi * rng.random(F))
    Y = 0.8 * R[None] + 0.3 * (rng.standard_normal((n_q, F))
                               + 1j * rng.standard_normal((n_q, F)))
    coh = multiple_coherence([Y[:, :, None, None]],
                             [np.broadcast_to(R, (n_q, F))[:, :, None, None]])
    expect = np.abs(Y.mean(axis=0)) ** 2 / np.mean(np.abs(Y) ** 2, axis=0)
    assert np.allclose(coh[0], expect, rtol=1e-12)
    # one record per reference: undefined
    assert np.all(np.isnan(multiple_coherence([Y[:1, :, None, None]],
                                              [np.ones((1, F, 1, 1))])))


def test_target_stops_early_within_half_a_db():
    rob, ctrl = _robot(1e-4)
    ms = MultisineConfig(n_realisations=4, n_periods=5, resolution_hz=1.0, settle_s=0.3,
                         return_s=1.0)
    target = UncertaintyTarget(0.5)
    rec = run_identification(FlexibleJointPlant(rob), ctrl, IdentificationConfig(ms, None, target))
    stop = rec.meta['summary']['multisine']['target']
    configured = ms.n_realisations * ms.n_periods
    print(f'\nstopped after {stop["periods"]} of {configured} periods, worst sd '
          f'{stop["worst_sd_db"]:.2f} dB')
    assert stop['stopped'] and MIN_STOP_PERIODS <= stop['periods'] < configured
    assert stop['worst_sd_db'] <= 0.5
    frf = estimate_recording(rec)['multisine']
    err = np.abs(20 * np.log10(np.abs(frf.response / robot_frf_sampled(rob, frf.freq_hz))))
    diag = err[np.arange(3), np.arange(3)]
    print(f'diagonal lines within 0.5 dB: {np.mean(diag <= 0.5):.1%} (max {diag.max():.2f} dB)')
    assert np.mean(diag <= 0.5) >= 0.95
    # the stopped segment says so, and the recording holds fewer periods than planned
    last = [s for s in rec.segments if s.info.get('design') == 'multisine'][-1]
    assert last.info['periods'] < last.info['periods_planned'] == ms.n_periods


@settings(max_examples=50, deadline=None)
@given(periods=st.integers(1, 200), ratio=st.floats(1.0, 30.0))
def test_periods_left_follow_inverse_sqrt(periods, ratio):
    target = UncertaintyTarget(0.5)
    sd = np.full((2, 2, 3), 0.5 * ratio)
    left = target.periods_left(sd, periods)
    # with `left` more periods the sd would fall below the target, with one fewer not
    assert 0.5 * ratio * np.sqrt(periods / (periods + left)) <= 0.5 * (1 + 1e-9)
    if left > 0:
        assert 0.5 * ratio * np.sqrt(periods / (periods + left - 1)) > 0.5


def test_dead_output_warns_normal_run_does_not(run):
    normal = _feed(run, LiveMultisine(run.joint_names, run.fs, 0))
    mon = WarningMonitor(run.joint_names, np.full(3, 400.0))
    assert [w for e in normal for w in mon.estimate(e)] == []
    dead = _feed(run, LiveMultisine(run.joint_names, run.fs, 0), dead=1)
    mon = WarningMonitor(run.joint_names, np.full(3, 400.0))
    got = [w for e in dead for w in mon.estimate(e)]
    assert [(w.kind, w.channel) for w in got] == [('low_coherence', 'dq_m/joint_2')]
    assert got[0].value < got[0].threshold
    print(f'\n{got[0].message} (rule: {FAR_BELOW_DB:g} dB below)')


def test_torque_warning_once_per_axis():
    mon = WarningMonitor(['a', 'b'], np.array([100.0, 200.0]))
    assert mon.torque(np.array([89.0, 10.0]), 1.0) == []
    got = mon.torque(np.array([-NEAR_LIMIT * 100.0, 10.0]), 2.0)
    assert [(w.kind, w.channel) for w in got] == [('near_torque_limit', 'a')]
    assert mon.torque(np.array([95.0, 10.0]), 3.0) == []


def test_growing_vibration_on_a_detection_line_warns_rising_distortion(run):
    from frf_ident.core.estimation.early_warnings import RISE_DB
    clean = _feed(run, LiveMultisine(run.joint_names, run.fs, 0))
    d = clean[-1].frf.meta['distortion']
    freq, kind = np.asarray(d['freq_hz']), np.asarray(d['kind'])
    f0 = freq[0]                      # the detection grid: every multiple of 1 / period
    assert np.allclose(freq, f0 * np.arange(1, freq.size + 1))
    line = 15                         # 16 f0 = 10.4 Hz: an even line, never excited
    assert kind[line] == 'even'
    fd = freq[line]

    def vibration(t):                 # on joint_2's velocity, growing e-fold every 10 s
        return np.array([0.0, 1e-6 * np.exp(t / 10.0) * np.sin(2 * np.pi * fd * t), 0.0])

    found = {}
    for name, ests in (('clean', clean),
                       ('growing', _feed(run, LiveMultisine(run.joint_names, run.fs, 0),
                                         add=vibration))):
        monitor = WarningMonitor(run.joint_names, np.full(3, 1e9))
        found[name] = [w for e in ests for w in monitor.estimate(e)
                       if w.kind == 'rising_distortion']
    assert found['clean'] == []
    assert len(found['growing']) == 1
    w = found['growing'][0]
    assert w.channel == d['outputs'][1] and f'{fd:.2f} Hz' in w.message
    assert w.value >= RISE_DB


def test_live_estimates_of_the_offline_runner_leave_the_run_as_it_was(run):
    rob, ctrl = _robot(4.5e-6)
    ms = MultisineConfig(n_realisations=2, n_periods=3, resolution_hz=1.0, settle_s=0.3,
                         return_s=1.0)
    seen = []
    rec = run_identification(FlexibleJointPlant(rob), ctrl, IdentificationConfig(ms, None),
                             on_estimate=seen.append)
    for k in ('position', 'velocity', 'effort', 'reference', 'excitation'):
        assert np.array_equal(getattr(rec, k), getattr(run, k)), k
    assert [(s.t_start, s.t_end, s.info) for s in rec.segments] == \
        [(s.t_start, s.t_end, s.info) for s in run.segments]
    # one estimate per MIMO period from the second on, the design's 2 x 3 periods
    assert [(e.periods, e.planned_periods) for e in seen] == [(p, 6) for p in range(2, 7)]
    off = estimate_recording(run)['multisine']
    assert np.allclose(seen[-1].frf.response, off.response, rtol=1e-9, atol=0)
