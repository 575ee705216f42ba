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
Diagnosis pieces against truth the diagnosis did not produce.

Diagnosis pieces against truth the diagnosis did not produce: synthetic residuals with known
ripple, rigid multi-axis torques written here from the equations of motion (gravity of a
coupled arm, friction), missing reference samples, and one route for CSV, MAT and bag.
"""
from dataclasses import replace
import json
import math
from pathlib import Path

from frf_ident.bag import write_recording
from frf_ident.cli import main
from frf_ident.core.diagnosis.common import bridge_gaps, GAP_GUARD_S, simulate_like
from frf_ident.core.diagnosis.experiments.evaluator import missing_reference
from frf_ident.core.diagnosis.experiments.unexplained import residual_bands
from frf_ident.core.diagnosis.prediction import noise_level
from frf_ident.core.diagnosis.regression import find_ripple, regress_axis, ripple_range
from frf_ident.core.diagnosis.residual import delayed_effort, effective_samples, lowpass
from frf_ident.core.diagnosis.selection import (block_standard_errors, f_test, select_groups,
                                                split_blocks)
from frf_ident.core.diagnosis.thresholds import FC_HZ
from frf_ident.core.diagnosis.timeseries import diagnose_timeseries
from frf_ident.core.model.schema import robot_from_dict
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.controller import controller_from_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.io.model_file import load_model
from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest
import scipy.io as sio

ROOT = Path(__file__).resolve().parents[3]

RIGID = {'frf_ident_model': 1, 'sample_rate': 500.0, 'axes': [
    {'name': f'joint_{i + 1}', 'motor_inertia': j, 'link_inertia': 1e-3, 'stiffness': 1e9,
     'damping': 0.0, 'viscous_friction': 0.0, 'torque_limit': 1e4}
    for i, j in enumerate((6.0, 4.0, 1.5))],
    'controller': {'kind': 'pi_velocity', 'kp': [50.0] * 3, 'ki': [0.0] * 3}}


@pytest.mark.parametrize('cycles', [1.6, 3.0, 40.0])
def test_ripple_scan_reaches_from_1_5_cycles_to_the_sample_limit(cycles):
    rng = np.random.default_rng(int(cycles * 10))
    n = 6000
    q = np.linspace(0, 0.12, n) + 2e-6 * rng.standard_normal(n)
    mask = np.ones(n, bool)
    s_min, s_max = ripple_range(q, mask)
    assert s_min == pytest.approx(1.5 * 2 * math.pi / np.ptp(q), rel=1e-6)
    assert s_max > 0.5 * math.pi / (0.12 / n)
    s = cycles * 2 * math.pi / 0.12
    if cycles > 10:       # near the top of the range: a few samples per ripple period
        s = 0.8 * s_max
    f = 0.5 * np.sin(s * q + 0.7) + 1.0 * rng.standard_normal(n)
    found, peak, thr = find_ripple(f, q, mask)
    assert found == pytest.approx(s, rel=0.03) and peak > thr


@pytest.mark.parametrize('n, travel', [(4000, 0.05), (20000, 1.0)])
def test_ripple_scan_false_alarms_follow_the_threshold(n, travel):
    """
    Noise alone passes the scan's threshold at the rate it is set for, at testable rates.

    500 white-noise residuals per size (1,800 / 9,000 resolution cells): the share above the
    threshold of alpha = 0.1 and 0.02 within about 2 binomial standard deviations of a factor
    0.5-1.5 of alpha (`python -m benchmarks ripple_threshold`, 1,500 scans per size: 0.3-1.35).
    The threshold ln(M / alpha), which takes the level as exact, is passed by 0.44 / 0.72 of
    the same scans at alpha = 0.1 (same command).
    """
    q, mask = np.linspace(0, travel, n), np.ones(n, bool)
    peaks = np.array([find_ripple(np.random.default_rng(seed).standard_normal(n), q, mask)[1]
                      for seed in range(500)])
    for alpha, lo, hi in ((0.1, 0.03, 0.17), (0.02, 0.002, 0.04)):
        # the threshold depends on the positions only: the scan's own at this alpha
        thr = find_ripple(np.random.default_rng(0).standard_normal(n), q, mask, alpha=alpha)[2]
        share = float(np.mean(peaks > thr))
        assert lo <= share <= hi, (alpha, share)


def test_ripple_scan_finds_a_ripple_at_twice_its_threshold():
    """
    A ripple whose expected peak is twice the threshold is found in nearly every record.

    Amplitude A in white noise of unit variance over n samples: expected peak ratio about
    1 + n A^2 / 4 (its periodogram line over the mean level); A is set so that this is twice
    the scan's threshold at RIPPLE_FALSE_ALARM.
    """
    n, travel = 8000, 0.3
    q, mask = np.linspace(0, travel, n), np.ones(n, bool)
    s_min, s_max = ripple_range(q, mask)
    thr = find_ripple(np.random.default_rng(0).standard_normal(n), q, mask)[2]
    amp = math.sqrt(4 * (2 * thr - 1) / n)
    hits = 0
    for seed in range(40):
        rng = np.random.default_rng(seed)
        s = rng.uniform(3 * s_min, 0.8 * s_max)
        f = amp * np.sin(s * q + rng.uniform(0, 6)) + rng.standard_normal(n)
        found, peak, thr_f = find_ripple(f, q, mask)
        hits += peak > thr_f and found == pytest.approx(s, rel=0.01)
    assert hits >= 36


@settings(max_examples=40, deadline=None)
@given(st.floats(0.0, 4.0), st.integers(0, 2 ** 32 - 1))
def test_delayed_effort_is_the_interval_average_of_the_delayed_hold(d, seed):
    # brute force: the zero-order-held command read at t - delay on a fine grid, averaged
    # over each sample interval (the plant applies exactly this, plant.py)
    dt, n, sub = 0.002, 40, 2000
    u = np.random.default_rng(seed).standard_normal((n, 2))
    got = delayed_effort(u, [d * dt, 0.0], dt)
    t = (np.arange(n * sub) + 0.5) / sub * dt
    k = np.clip(np.floor((t - d * dt) / dt).astype(int), 0, n - 1)
    want = u[k, 0].reshape(n, sub).mean(axis=1)
    assert np.allclose(got[:, 0], want, atol=2e-3 * np.abs(u).max())
    assert np.array_equal(got[:, 1], u[:, 1])


def test_missing_reference_is_left_out_not_commanded_as_zero():
    model, robot, ctrl = load_model(ROOT / 'config' / 'model_3axis.yaml')
    plant = FlexibleJointPlant(robot)
    c = ctrl.copy()
    c.reset(plant.equilibrium_torque())
    n = 4000
    r = np.tile([0.05, -0.04, 0.08], (n, 1)) * np.sin(np.arange(n) / 400)[:, None]
    res = plant.simulate(reference=r, controller=c)
    ref = r.copy()
    ref[1500:2000] = np.nan
    rec = Recording(res.t, robot.joint_names, res.position, res.velocity, res.effort, ref)
    miss = missing_reference(rec)
    assert miss[1500:2000].all() and miss[2000:2000 + int(0.5 * rec.fs)].all()
    assert not miss[:1500].any() and not miss[-100:].any()
    sim = simulate_like(rec, robot, ctrl)
    # the simulation follows the measured motion through the gap (not a zero command)
    assert np.max(np.abs(sim.velocity[1500:2000] - res.velocity[1500:2000])) < \
        0.2 * np.max(np.abs(res.velocity[1500:2000]))
    # joint states lost in a gap of the bag (NaN rows): bridged for the simulation, their
    # reference taken away (widened by the filters' reach), so they are never compared
    pos, vel = res.position.copy(), res.velocity.copy()
    pos[3000:3100] = vel[3000:3100] = np.nan
    lossy = Recording(res.t, robot.joint_names, pos, vel, res.effort, r.copy())
    bridged, lost = bridge_gaps(lossy)
    g = int(round(GAP_GUARD_S * rec.fs))
    assert lost[3000 - g:3100 + g].all() and not lost[:3000 - g].any()
    assert np.isfinite(bridged.position).all() and np.isfinite(bridged.velocity).all()
    miss = missing_reference(bridged)
    assert miss[3000 - g:3100 + g + int(0.5 * rec.fs)].all() and not miss[2500:3000 - g].any()
    assert np.isfinite(simulate_like(bridged, robot, ctrl).velocity).all()


def _arm_record(seed: int, *, disturbance_hz: float = 0.0, cable: float = 0.0):
    """
    Find the gravity of a rigid 3-axis arm from its equations of motion.

    Rigid 3-axis arm (axis 1 vertical, 2-3 horizontal): torques from the equations of
    motion written here, measured with noise; ``cable`` [N m/rad] adds a position-dependent
    torque on axis 1 that is no gravity (a cable carrier's spring).
    """
    rng = np.random.default_rng(seed)
    fs, T = 500.0, 40.0
    t = np.arange(int(T * fs)) / fs
    q = np.zeros((t.size, 3))
    for i in range(3):
        for _ in range(4):
            f = rng.uniform(0.05, 0.6)
            q[:, i] += rng.uniform(0.1, 0.35) * np.sin(2 * np.pi * f * t + rng.uniform(0, 6))
    v = np.gradient(q, 1 / fs, axis=0)
    # the torque u[k] holds over the sample interval (zero-order hold, as a drive applies a
    # command; docs/diagnosis/timeseries.md): the equations of motion at the interval's middle
    qh, vh, th = 0.5 * (q[1:] + q[:-1]), 0.5 * (v[1:] + v[:-1]), t[:-1] + 0.5 / fs
    a = np.diff(v, axis=0) * fs
    J = np.array([6.0, 4.0, 1.5])
    fc = np.array([3.0, 4.0, 2.0])
    g2, p2, g3, p3 = 80.0, 0.4, 25.0, -0.3
    u = J * a + fc * np.sign(vh)
    u[:, 1] += g2 * np.sin(qh[:, 1] + p2) + g3 * np.sin(qh[:, 1] + qh[:, 2] + p3)
    u[:, 2] += g3 * np.sin(qh[:, 1] + qh[:, 2] + p3)
    if disturbance_hz:
        u[:, 0] += 3.0 * np.sin(2 * np.pi * disturbance_hz * th)
    u[:, 0] += cable * qh[:, 0]
    u = np.vstack([u, u[-1:]])
    u += 0.2 * rng.standard_normal(u.shape)
    vm = v + 1e-4 * rng.standard_normal(v.shape)
    truth = {'fc': fc, 'g2': g2, 'g3': g3}
    return Recording(t, ['joint_1', 'joint_2', 'joint_3'], q, vm, u), truth


def test_timeseries_names_gravity_of_a_coupled_arm_and_friction():
    rec, truth = _arm_record(5)
    robot = replace(robot_from_dict(RIGID), sample_rate=rec.fs)
    res = diagnose_timeseries(rec, robot)
    found = {(e.name, e.axis): e.parameters for e in res.effects}
    # exactly the effects of the equations of motion: no false alarm beside them
    assert sorted(found) == [('coulomb_friction', 'joint_1'), ('coulomb_friction', 'joint_2'),
                             ('coulomb_friction', 'joint_3'), ('gravity', 'joint_2'),
                             ('gravity', 'joint_3')]
    grav2 = found[('gravity', 'joint_2')]['gravity']
    grav3 = found[('gravity', 'joint_3')]['gravity']
    sets2 = sorted(tuple(g['joints']) for g in grav2)
    assert sets2 == [('joint_2',), ('joint_2', 'joint_3')], grav2
    assert [tuple(g['joints']) for g in grav3] == [('joint_2', 'joint_3')]
    amp = {tuple(g['joints']): g['amplitude'] for g in grav2}
    # 0.2 N m noise on 80 / 25 / 2-4 N m: the fit is within 0.1 % of the truth (seeds 5-8)
    assert amp[('joint_2',)] == pytest.approx(truth['g2'], rel=0.02)
    assert amp[('joint_2', 'joint_3')] == pytest.approx(truth['g3'], rel=0.02)
    assert grav3[0]['amplitude'] == pytest.approx(truth['g3'], rel=0.02)
    for i, name in enumerate(rec.joint_names):
        assert found[('coulomb_friction', name)]['coulomb_friction'] == \
            pytest.approx(truth['fc'][i], rel=0.02)
    m = res.metrics
    assert m.extended.time_nrmse < 0.3 < m.baseline.time_nrmse
    assert res.unexplained == []


def test_position_dependent_torque_of_a_vertical_axis_does_not_tilt_the_links_beyond():
    """
    Keep the gravity arguments of axes 2-3 free of joint 1.

    Axis 1 carries a position-dependent torque of its own (a cable spring); the sets of axes 2
    and 3 are still the link angles q2 and q2 + q3 (their residual does not improve with q1).
    """
    rec, truth = _arm_record(6, cable=30.0)
    robot = replace(robot_from_dict(RIGID), sample_rate=rec.fs)
    res = diagnose_timeseries(rec, robot)
    found = {(e.name, e.axis): e.parameters for e in res.effects}
    for ax in ('joint_2', 'joint_3'):
        assert all('joint_1' not in g['joints'] for g in found[('gravity', ax)]['gravity'])
    grav3 = found[('gravity', 'joint_3')]['gravity']
    assert [tuple(g['joints']) for g in grav3] == [('joint_2', 'joint_3')]
    assert grav3[0]['amplitude'] == pytest.approx(truth['g3'], rel=0.02)


def test_unexplained_disturbance_gets_its_band_and_axis():
    """
    Report a torque no candidate explains as unexplained, with its band.

    A 7 Hz torque that no candidate effect explains: listed as unexplained on its axis
    with a band around 7 Hz, not as a named effect's false parameters.
    """
    rec, _ = _arm_record(6, disturbance_hz=7.0)
    robot = replace(robot_from_dict(RIGID), sample_rate=rec.fs)
    res = diagnose_timeseries(rec, robot)
    un = {u.axis: u for u in res.unexplained}
    assert 'joint_1' in un, res.unexplained
    f1, f2 = un['joint_1'].signature.band_hz
    assert f1 <= 7.0 <= f2 and f2 - f1 < 3.0
    assert 'joint_2' not in un and 'joint_3' not in un


def test_csv_mat_and_bag_of_the_same_data_give_the_same_report(tmp_path):
    rec, _ = _arm_record(7)
    cols = {'t': rec.t}
    for i in range(3):
        cols[f'q{i}'], cols[f'v{i}'], cols[f'u{i}'] = (rec.position[:, i], rec.velocity[:, i],
                                                       rec.effort[:, i])
    csv = tmp_path / 'arm.csv'
    csv.write_text(','.join(cols) + '\n' + '\n'.join(
        ','.join(repr(float(x)) for x in row) for row in np.column_stack(list(cols.values()))))
    mat = tmp_path / 'arm.mat'
    sio.savemat(mat, cols)
    mp = tmp_path / 'map.yaml'
    mp.write_text('frf_ident_map: 1\ntime: {column: t}\njoints:\n' + ''.join(
        f'  - {{name: joint_{i + 1}, position: q{i}, velocity: v{i}, effort: u{i}}}\n'
        for i in range(3)))
    model = tmp_path / 'model.yaml'
    model.write_text(json.dumps(dict(RIGID, sample_rate=500.0)))
    bag = tmp_path / 'bag'
    assert main(['import', str(csv), '--map', str(mp), '--out', str(bag)]) == 0
    reps = []
    for data in (csv, mat, bag):
        out = tmp_path / f'diag_{data.name}'
        args = ['diagnose', str(data), '--model', str(model), '--out', str(out)]
        if data != bag:
            args += ['--map', str(mp)]
        assert main(args) == 0
        reps.append(json.loads((out / 'report.json').read_text()))
    for r in reps[1:]:
        assert [(e['name'], e['axis']) for e in r['effects']] == \
            [(e['name'], e['axis']) for e in reps[0]['effects']]
        for e, e0 in zip(r['effects'], reps[0]['effects']):
            assert json.dumps(e['parameters']) == json.dumps(e0['parameters'])
        assert r['metrics']['extended']['time_nrmse'] == \
            pytest.approx(reps[0]['metrics']['extended']['time_nrmse'], rel=1e-3)


def test_bag_with_lost_stretches_is_diagnosed_without_them(tmp_path, capsys):
    """
    Diagnose a bag that lost stretches of joint states (a recorder's drops).

    Three stretches of 0.3 s are missing from the bag (their messages were never written):
    the diagnosis reads them as gaps, leaves them out of fit and validation and names the
    same effects with the true parameters as without the gaps (it refused the bag before).
    """
    rec, truth = _arm_record(5)
    keep = np.ones(rec.t.size, bool)
    for t0 in (7.1, 19.4, 31.7):
        keep[(rec.t >= t0) & (rec.t < t0 + 0.3)] = False
    lossy = Recording(rec.t[keep], rec.joint_names, rec.position[keep], rec.velocity[keep],
                      rec.effort[keep])
    bag = write_recording(lossy, tmp_path / 'lossy')
    model = tmp_path / 'model.yaml'
    model.write_text(json.dumps(dict(RIGID, sample_rate=500.0)))
    out = tmp_path / 'diag'
    assert main(['diagnose', str(bag), '--model', str(model), '--out', str(out)]) == 0
    assert '3 gap(s) in the joint states' in capsys.readouterr().out
    rep = json.loads((out / 'report.json').read_text())
    assert [round(a, 1) for a, _ in rep['gaps']] == [7.1, 19.4, 31.7]
    found = {(e['name'], e['axis']): e['parameters'] for e in rep['effects']}
    full = diagnose_timeseries(rec, replace(robot_from_dict(RIGID), sample_rate=rec.fs))
    assert set(found) == {(e.name, e.axis) for e in full.effects}
    g3 = found[('gravity', 'joint_3')]['gravity'][0]['amplitude']
    assert g3 == pytest.approx(truth['g3'], rel=0.02)
    for i, name in enumerate(rec.joint_names):
        assert found[('coulomb_friction', name)]['coulomb_friction'] == \
            pytest.approx(truth['fc'][i], rel=0.02)
    m = rep['metrics']
    assert math.isfinite(m['extended']['time_nrmse'])
    assert m['extended']['time_nrmse'] < 0.3 < m['baseline']['time_nrmse']


def test_table_without_map_is_refused_with_one_line(tmp_path, capsys):
    csv = tmp_path / 'x.csv'
    csv.write_text('t,q\n0,0\n')
    rc = main(['diagnose', str(csv), '--model', str(ROOT / 'config' / 'model_3axis.yaml'),
               '--out', str(tmp_path / 'o')])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and 'x.csv' in err[0] and '--map' in err[0]


def test_controller_reset_uses_the_gravity_load():
    m, _, _ = load_model(ROOT / 'config' / 'model_3axis.yaml')
    m['axes'][1]['gravity'] = [{'amplitude': 100.0, 'phase': 0.5}]
    rob = robot_from_dict(m)
    ctrl = controller_from_dict(m, rob)
    assert ctrl.integral[1] == pytest.approx(120.0 + 100.0 * math.sin(0.5))


def test_residual_bands_list_each_concentration_strongest_first():
    """
    List separated concentrations strongest first; two grids count what both show.

    Two separated bumps give two bands around their centres; one below a quarter of the
    strongest none. On two offset line grids (multisine and chirp) the same bumps give the
    same bands, while a peak only one grid shows (a noisy line, however large) gives none and
    no longer sets the quarter the others are measured against. Where the grids share no
    misfit, each one's own concentrations are listed.
    """
    f = np.arange(1.0, 60.0, 0.5)
    f2 = np.arange(1.25, 60.0, 0.5)

    def bump(x, fc, a):
        return a * np.exp(-((x - fc) / 1.0) ** 2)
    w = bump(f, 15.0, 1.0) + bump(f, 35.0, 0.5) + bump(f, 50.0, 0.2)
    bands = residual_bands([(f, w)])
    assert len(bands) == 2
    assert bands[0][0] < 15.0 < bands[0][1] and bands[1][0] < 35.0 < bands[1][1]
    assert bands[0][1] < bands[1][0]
    w2 = bump(f2, 15.1, 1.1) + bump(f2, 35.2, 0.6) + bump(f2, 50.0, 0.2)
    spike = np.where(np.isclose(f2, 5.25), 8.0, 0.0)
    both = residual_bands([(f, w), (f2, w2 + spike)])
    assert len(both) == 2
    assert both[0][0] < 15.0 < both[0][1] and both[1][0] < 35.0 < both[1][1]
    assert all(abs(x - y) <= 0.5 for b, c in zip(both, bands) for x, y in zip(b, c))
    assert residual_bands([(f, w + np.where(np.isclose(f, 5.0), 8.0, 0.0))])[0] == [4.5, 5.5]
    apart = residual_bands([(f, 4.0 * bump(f, 15.0, 1.0)), (f2, 2.0 * bump(f2, 40.0, 1.0))])
    assert apart[0][0] < 15.0 < apart[0][1] and apart[1][0] < 40.0 < apart[1][1]
    assert residual_bands([(f, np.zeros_like(f))]) == []


def _resting_record(seed: int):
    """
    Return a rigid-arm record that stops between moves, with the torque static friction holds.

    Axes 1-3 move in bursts separated by rests of 0.5-1.5 s. At rest the joint sticks and its
    torque is gravity plus what static friction holds: here 0.9 of the Coulomb level in the
    direction of the last motion (the drive's integrator keeps pushing where it stopped), which
    no friction law of the model predicts.
    """
    rng = np.random.default_rng(seed)
    fs, T = 500.0, 40.0
    t = np.arange(int(T * fs)) / fs
    w = np.zeros((t.size, 3))
    for i in range(3):
        k, on = 0, True
        while k < t.size:
            m = int(fs * (rng.uniform(2.0, 4.0) if on else rng.uniform(0.5, 1.5)))
            if on:
                w[k:k + m, i] = np.sin(np.pi * np.arange(min(m, t.size - k)) / m) ** 2
            k, on = k + m, not on
    v = np.zeros((t.size, 3))
    for i in range(3):
        for _ in range(3):
            v[:, i] += rng.uniform(0.1, 0.3) * np.sin(2 * np.pi * rng.uniform(0.2, 0.8) * t
                                                      + rng.uniform(0, 6))
    v *= w
    q = np.cumsum(v, axis=0) / fs
    q -= q.mean(axis=0)
    a = np.gradient(v, 1 / fs, axis=0)
    J = np.array([6.0, 4.0, 1.5])
    fc = np.array([3.0, 4.0, 2.0])
    g3, p3 = 25.0, -0.3
    moving = np.abs(v) > 1e-6
    last = np.zeros(3)
    hold = np.zeros_like(v)
    for k in range(t.size):
        last = np.where(moving[k], np.sign(v[k]), last)
        hold[k] = np.where(moving[k], np.sign(v[k]), 0.9 * last)
    u = J * a + fc * hold
    u[:, 1] += 60.0 * np.sin(q[:, 1] + 0.4) + g3 * np.sin(q[:, 1] + q[:, 2] + p3)
    u[:, 2] += g3 * np.sin(q[:, 1] + q[:, 2] + p3)
    u += 0.2 * rng.standard_normal(u.shape)
    vm = v + 1e-4 * rng.standard_normal(v.shape)
    return Recording(t, ['joint_1', 'joint_2', 'joint_3'], q, vm, u), {'fc': fc, 'g3': g3}


def test_torque_held_at_rest_is_neither_fitted_nor_scored():
    """
    Read friction and gravity from the moving samples only, and score those.

    A robot that stops between moves holds at rest whatever torque static friction allows;
    fitted as if sgn(0 + noise) chose the friction, the rests bias the Coulomb level and
    make the extended model look worse than it is (the KUKA record rests 1.5 s at each end).
    """
    rec, truth = _resting_record(11)
    robot = replace(robot_from_dict(RIGID), sample_rate=rec.fs)
    res = diagnose_timeseries(rec, robot)
    found = {(e.name, e.axis): e.parameters for e in res.effects}
    for i, name in enumerate(rec.joint_names):
        assert found[('coulomb_friction', name)]['coulomb_friction'] == \
            pytest.approx(truth['fc'][i], rel=0.03)
    grav3 = found[('gravity', 'joint_3')]['gravity']
    assert grav3[0]['amplitude'] == pytest.approx(truth['g3'], rel=0.03)
    ext = res.metrics.extended
    assert ext.time_nrmse < 0.15
    for name in rec.joint_names:
        assert 0.4 < ext.per_axis[name].moving_share < 0.95


def _sweep_arm(rng, fs, T, two_way, f_hi, sweep):
    """
    Return t, q, v, a of a rigid 3-axis arm whose other axes sweep one way.

    Axes ``two_way`` move back and forth (three random sines up to ``f_hi`` Hz); ``sweep``
    maps each other axis to its one-way position as a function of t.
    """
    t = np.arange(int(T * fs)) / fs
    q = np.zeros((t.size, 3))
    for i in two_way:
        for _ in range(3):
            q[:, i] += rng.uniform(0.1, 0.3) * np.sin(2 * np.pi * rng.uniform(f_hi - 0.4, f_hi)
                                                      * t + rng.uniform(0, 6))
    for i, f in sweep.items():
        q[:, i] = f(t)
    v = np.gradient(q, 1 / fs, axis=0)
    return t, q, v, np.gradient(v, 1 / fs, axis=0)


def _diagnose_arm(rng, t, q, v, u, g2, g3, p3, fs=500.0):
    """Add the coupled gravity of axes 2-3 and noise to u and diagnose it against RIGID."""
    u[:, 1] += g2 * np.sin(q[:, 1] + 0.4) + g3 * np.sin(q[:, 1] + q[:, 2] + p3)
    u[:, 2] += g3 * np.sin(q[:, 1] + q[:, 2] + p3)
    u += 0.2 * rng.standard_normal(u.shape)
    rec = Recording(t, ['joint_1', 'joint_2', 'joint_3'], q,
                    v + 1e-4 * rng.standard_normal(v.shape), u)
    res = diagnose_timeseries(rec, replace(robot_from_dict(RIGID), sample_rate=fs))
    return res, {(e.name, e.axis): e.parameters for e in res.effects}


def test_axis_moving_one_way_keeps_friction_out_of_the_gravity_shape():
    """
    Fit Coulomb friction of a one-way axis as the constant it is there, never as gravity.

    Axis 3 sweeps one way through 1 rad (as each half of the KUKA record does): sgn(v) is a
    constant, so Coulomb friction cannot be told from a constant load, and a sinusoid without
    that constant bends its amplitude and phase to carry the friction torque. The constant is
    always fitted on such an axis, Coulomb friction is listed as not separable, and the
    gravity amplitude comes out right.
    """
    rng = np.random.default_rng(3)
    t, q, v, a = _sweep_arm(rng, 500.0, 20.0, (0, 1), 0.5,
                            {2: lambda t: -t / 20.0 - 0.02 * np.sin(2 * np.pi * 0.3 * t)})
    assert (v[50:-50, 2] < 0).all()
    J, fc, g3, p3 = np.array([6.0, 4.0, 1.5]), np.array([3.0, 4.0, 6.0]), 25.0, -1.9
    res, found = _diagnose_arm(rng, t, q, v, J * a + fc * np.sign(v), 60.0, g3, p3)
    assert ('coulomb_friction', 'joint_3') not in found
    assert any(r.name == 'coulomb_friction' and r.axis == 'joint_3' and 'one way' in
               (r.reason or '') for r in res.rejected)
    grav3 = found[('gravity', 'joint_3')]['gravity']
    assert grav3[0]['amplitude'] == pytest.approx(g3, rel=0.03)
    # the constant carries the friction: -Fc plus no load
    assert found[('parameter_mismatch', 'joint_3')]['gravity_torque'] == \
        pytest.approx(-fc[2], abs=1.5)
    # ... and says so: it was not F-tested, so no p value
    const = next(e for e in res.effects if e.axis == 'joint_3'
                 and 'gravity_torque' in e.parameters)
    assert 'one way' in const.evidence and 'p =' not in const.evidence
    assert found[('coulomb_friction', 'joint_2')]['coulomb_friction'] == \
        pytest.approx(fc[1], rel=0.03)


@pytest.mark.parametrize('seed', [11, 12])
def test_sinusoid_of_a_one_way_angle_is_not_taken_for_gravity(seed):
    """
    Test no gravity on an axis whose angle the record sweeps one way only.

    Axis 1 (vertical: no gravity) sweeps once through 0.8 rad with a bell-shaped speed and
    has a Stribeck friction peak the candidates lack: along a single sweep the friction is a
    function of q1, so sin(q1 + phi) plus a constant fits it. That is no evidence of a load
    that depends on the configuration: the sinusoid is not a candidate there and the
    rejected list says why. Axes 2-3 (coupled gravity, both ways) keep theirs.
    """
    rng = np.random.default_rng(seed)
    t, q, v, a = _sweep_arm(rng, 500.0, 12.0, (1, 2), 0.6,
                            {0: lambda t: 0.4 * (1 - np.cos(np.pi * t / 12.0))})
    vs = 0.3 * v[:, 0].max()
    u = np.array([6.0, 4.0, 1.5]) * a + np.array([3.0, 4.0, 2.0]) * np.sign(v)
    u[:, 0] += 40.0 * v[:, 0] + rng.uniform(3.0, 5.0) * np.exp(-(v[:, 0] / vs) ** 2)
    g3 = 25.0
    res, found = _diagnose_arm(rng, t, q, v, u, 80.0, g3, -0.3)
    assert ('gravity', 'joint_1') not in found, found
    assert all('joint_1' not in g['joints'] for ax in ('joint_2', 'joint_3')
               for g in found[('gravity', ax)]['gravity'])
    assert any(r.name == 'gravity' and r.axis == 'joint_1'
               and 'q_joint_1 moves one way only' in (r.reason or '')
               for r in res.rejected)
    assert found[('gravity', 'joint_3')]['gravity'][0]['amplitude'] == \
        pytest.approx(g3, rel=0.03)


def test_group_dropped_on_held_out_data_lets_the_one_it_kept_out_in():
    """
    Test the stepwise selection: a stand-in removed on held-out data no longer blocks.

    The residual is viscous friction (velocity times 5) plus noise. A stand-in column equals
    the residual on the fit rows (up to a little noise of its own) and is noise on the
    held-out rows: the forward pass takes it first (velocity adds nothing to it there), the
    held-out check removes it, and velocity must then enter.
    """
    rng = np.random.default_rng(4)
    n = 4000
    v = np.sin(np.linspace(0, 40, n)) + 0.3 * rng.standard_normal(n)
    y = 5.0 * v + rng.standard_normal(n)
    fit = np.arange(n) % 3 != 2
    stand_in = np.where(fit, y + 0.05 * rng.standard_normal(n), 5.0 * rng.standard_normal(n))
    groups = {'stand_in': stand_in[:, None], 'viscous_friction': v[:, None]}
    chosen, info = select_groups(groups, y, fit, ~fit, n_eff=300.0)
    assert chosen == ['viscous_friction']
    assert info['stand_in']['held_out_gain'] < 0


@pytest.mark.parametrize('fs, sigma', [(250.0, 0.6), (1000.0, 0.05)])
def test_noise_level_is_the_white_level_beside_the_motion(fs, sigma):
    """
    Read the white noise level of a residual that also holds slow motion torque.

    White noise of standard deviation sigma has the one-sided level 2 sigma^2 / fs; a torque
    below a tenth of the Nyquist frequency, 30 times the noise, must not raise it.
    """
    rng = np.random.default_rng(int(fs))
    t = np.arange(int(20 * fs)) / fs
    slow = 30 * sigma * np.sin(2 * np.pi * 0.05 * fs * t)
    f = np.column_stack([slow + sigma * rng.standard_normal(t.size),
                         2 * sigma * rng.standard_normal(t.size)])
    level = noise_level(f, fs)
    assert level == pytest.approx([2 * sigma ** 2 / fs, 8 * sigma ** 2 / fs], rel=0.1)


def test_f_test_of_a_low_passed_residual_keeps_its_false_alarm_rate():
    """
    Test the F test's calibration by Monte Carlo: noise alone passes at the nominal rate.

    White noise low-passed at FC_HZ as the diagnosis low-passes its residual, a slow
    two-column group (sinusoids of a random smooth path, as a gravity group) added on top of a
    constant: the share of runs with p < 0.05 (< 0.01) must be the nominal 5 % (1 %). Counting
    the effective sample count twice (in the variance and again as a factor of F) made the
    test pass noise almost never and miss real effects of the same size; the count uses the
    filter's noise bandwidth (0.9 fc), not the cut-off.
    """
    rng = np.random.default_rng(11)
    fs, n, runs = 250.0, 1500, 1500
    n_eff = effective_samples(n, fs, FC_HZ)
    t = np.arange(n) / fs
    lp = []
    for _ in range(runs):
        y = lowpass(rng.standard_normal(n), fs, FC_HZ)
        path = np.cumsum(lowpass(rng.standard_normal(n), fs, 0.5))
        path *= rng.uniform(0.3, 1.5) / np.ptp(path)
        X0 = np.ones((n, 1))
        X1 = np.column_stack([X0, np.sin(path), np.cos(path + t)])
        rss = [float(np.sum((y - X @ np.linalg.lstsq(X, y, rcond=None)[0]) ** 2))
               for X in (X0, X1)]
        lp.append(f_test(rss[0], rss[1], 2, 3, n_eff))
    lp = np.array(lp)
    assert 0.035 <= np.mean(lp < math.log(0.05)) <= 0.065
    assert 0.003 <= np.mean(lp < math.log(0.01)) <= 0.02


def test_t_statistics_of_the_friction_regression_keep_their_false_alarm_rate():
    """
    Test the experiments route's t statistics by Monte Carlo: noise alone passes at 5 %.

    White torque noise at 1 kHz regressed (as the friction and gravity-slope readings do) on
    sgn(v), v and q - q0 of a random smooth motion with velocity reversals: |t| > 1.96 of the
    viscous and slope coefficients must occur in 5 % of the runs. The variance used to be
    multiplied by N / n_eff on top of rss / (n_eff - p), which made every t statistic
    sqrt(fs / 2 fc) = 5 times too small here.
    """
    rng = np.random.default_rng(5)
    fs, n, runs = 1000.0, 3000, 400
    hits = []
    for _ in range(runs):
        v = lowpass(rng.standard_normal(n), fs, 1.0)
        v *= rng.uniform(0.5, 2.0) / np.std(v)
        q = np.cumsum(v) / fs
        reg = regress_axis(rng.standard_normal(n), q, v, np.gradient(v, 1 / fs),
                           np.zeros(n), np.ones(n, bool), fs, ripple=False,
                           nuisance=(q - q.mean())[:, None])
        hits += [abs(reg.tstat[k]) > 1.96 for k in ('viscous_friction', 'nuisance_0')]
    assert 0.03 <= np.mean(hits) <= 0.075


def test_held_out_removal_takes_the_worst_of_two_collinear_groups_first():
    """
    Test stepwise removal on two groups that each look useless next to the other.

    F is the signal s itself; S is s plus a column w that the fit blocks' residual carries
    (with the opposite sign) and that is 1.5 times larger, with the other sign, in the
    held-out blocks. Both pass the forward F test (S explains the fit blocks' w), and on the
    held-out blocks the pair is worse than either alone, so each group's removal "helps".
    F alone is the better model there: removal must take S first (its absence helps most)
    and then keep F. Taken in list order (before commit d825159), F, which explains
    the fit blocks better alone and so entered first, went first.
    """
    rng = np.random.default_rng(11)
    n = 300
    fit = np.arange(n) < 200
    s, w = rng.standard_normal(n), rng.standard_normal(n)
    groups = {'F': s[:, None], 'S': (s + 1.25 * np.where(fit, w, -1.5 * w))[:, None]}
    y = s - 1.25 * np.where(fit, w, 0.0) + 0.05 * rng.standard_normal(n)

    def held_out(names):
        c, *_ = np.linalg.lstsq(np.column_stack([groups[k][fit] for k in names]), y[fit],
                                rcond=None)
        r = y[~fit] - np.column_stack([groups[k][~fit] for k in names]) @ c
        return float(r @ r)
    assert held_out(['F']) < held_out(['S']) < held_out(['F', 'S'])
    chosen, info = select_groups(groups, y, fit, ~fit, 200.0)
    assert info['F']['p'] < 1e-3 and info['S']['p'] < 1e-3      # both entered
    assert chosen == ['F']
    assert info['S']['held_out_gain'] < 0


@pytest.mark.parametrize('design', [3, 5])
def test_block_standard_errors_match_the_monte_carlo_spread(design):
    """
    Test the time-series route's standard errors against the spread of 200 noisy repeats.

    One smooth motion (seed ``design``: 1.2 rad of travel with 2 reversals, or 3.0 rad)
    drives a residual of viscous friction 5, Coulomb friction 2 and gravity 10 sin(q + 0.93)
    under noise low-passed at 3 Hz (slower than the diagnosis' 20 Hz filter: the
    correlation a white-noise formula misses). Over repeats of the noise the block-robust
    (CR2) standard error must match the standard deviation of the estimates within 20 %
    (0.92-1.02 on these designs), where the white-noise formula rss / (n_eff - p) (X'X)^-1
    stays below 0.6 of it (0.4).
    """
    rng = np.random.default_rng(design)
    fs, n = 250.0, 2500
    v = lowpass(rng.standard_normal(n), fs, 0.3)
    v *= 0.4 / np.std(v)
    q = np.cumsum(v) / fs
    groups = {k: lowpass(x, fs, FC_HZ) for k, x in (
        ('viscous_friction', v[:, None]), ('coulomb_friction', np.sign(v)[:, None]),
        ('gravity:0', np.column_stack([np.sin(q), np.cos(q)])))}
    clean = (5.0 * groups['viscous_friction'][:, 0] + 2.0 * groups['coulomb_friction'][:, 0]
             + groups['gravity:0'] @ np.array([6.0, 8.0]))
    fit, _ = split_blocks(n, fs, FC_HZ)
    chosen = list(groups)
    X = np.column_stack([groups[k][fit] for k in chosen])
    xtx = np.linalg.pinv(X.T @ X)[0, 0]
    dof = effective_samples(int(fit.sum()), fs, FC_HZ) - X.shape[1]
    est, ses, white = [], [], []
    for _ in range(200):
        y = clean + 3.0 * lowpass(rng.standard_normal(n), fs, 3.0)
        c, *_ = np.linalg.lstsq(X, y[fit], rcond=None)
        est.append([c[0], math.hypot(c[2], c[3])])
        se = block_standard_errors(groups, chosen, y, fit, fs)
        ses.append([se['viscous_friction'][0], se['gravity:0'][0]])
        r = y[fit] - X @ c
        white.append(math.sqrt(float(r @ r) / dof * xtx))
    ratio = np.mean(ses, axis=0) / np.std(est, axis=0)
    print(f'design {design}: standard error / spread (viscous, gravity) {np.round(ratio, 2)}')
    assert np.all((ratio > 0.8) & (ratio < 1.2)), ratio
    assert np.mean(white) / np.std(est, axis=0)[0] < 0.6


def test_rigid_residual_carries_the_link_coupling():
    """
    Test the rigid inverse dynamics against a coupled two-axis arm's torque written by hand.

    Rigid joints (stiffness far above the sample rate): the torque over each sample interval
    is (diag(Jm) + M_link) times the interval's acceleration plus viscous friction, M_link with
    the off-diagonal coupling 2.5 kg m^2. The residual of the model with that coupling is zero;
    without it, it is the coupling torque 2.5 times the other axis' acceleration.
    """
    from frf_ident.core.diagnosis.residual import inverse_dynamics_residual
    from frf_ident.core.model.params import AxisParams, RobotParams
    fs, n = 250.0, 1000
    t = np.arange(n) / fs
    v = np.column_stack([0.4 * np.sin(2 * np.pi * 0.7 * t), 0.3 * np.cos(2 * np.pi * 1.3 * t)])
    q = np.cumsum(v, axis=0) / fs
    axes = [AxisParams(name=f'j{i}', motor_inertia=jm, link_inertia=jo, stiffness=1e9,
                       viscous_friction=b)
            for i, (jm, jo, b) in enumerate(((6.5, 3.0, 3.0), (2.3, 2.5, 2.0)))]
    coupling = np.array([[0.0, 2.5], [2.5, 0.0]])
    m = np.diag([9.5, 4.8]) + coupling
    ah = np.diff(v, axis=0) / (1 / fs)
    u = np.zeros((n, 2))
    u[:-1] = ah @ m + np.array([3.0, 2.0]) * 0.5 * (v[1:] + v[:-1])
    coupled = RobotParams(axes, link_coupling=coupling, sample_rate=fs)
    f, *_ = inverse_dynamics_residual(q, v, u, 1 / fs, coupled)
    assert np.max(np.abs(f)) < 1e-9 * np.max(np.abs(u))
    f0, *_ = inverse_dynamics_residual(q, v, u, 1 / fs, replace(coupled, link_coupling=None))
    np.testing.assert_allclose(f0, ah[:, ::-1] * 2.5, atol=1e-9 * np.max(np.abs(u)))


def test_axis_refitted_with_the_baseline_terms_takes_exactly_those():
    """
    ``only``: an axis refitted with the least-squares baseline's terms and nothing else.

    What the app does with an axis whose selected effects lose to the baseline on held-out
    data. Axis 1 of the arm here has inertia 6 and Coulomb friction 3 (no viscous friction,
    no load): the refit finds them (within 2 %, as the selection does), says in its evidence
    where the terms come from, and leaves axes 2 and 3 as the plain diagnosis has them.
    """
    from frf_ident.core.diagnosis.crosscheck.baseline import BASELINE_GROUPS
    rec, truth = _arm_record(5)
    robot = replace(robot_from_dict(RIGID), sample_rate=rec.fs)
    plain = diagnose_timeseries(rec, robot)
    res = diagnose_timeseries(rec, robot, only={'joint_1': BASELINE_GROUPS})
    mine = [e for e in res.effects if e.axis == 'joint_1']
    assert {k for e in mine for k in e.parameters} <= set(BASELINE_GROUPS)
    assert all("least-squares baseline's terms" in e.evidence for e in mine), mine
    a = res.extended.axes[0]
    assert a.coulomb_friction == pytest.approx(truth['fc'][0], rel=0.02)
    assert a.motor_inertia == pytest.approx(6.0, rel=0.02)
    assert abs(a.gravity_torque) < 0.05 * truth['fc'][0] and a.viscous_friction < 0.1
    assert res.extended.axes[1:] == plain.extended.axes[1:]
    assert sorted((e.name, e.axis) for e in res.effects if e.axis != 'joint_1') == sorted(
        (e.name, e.axis) for e in plain.effects if e.axis != 'joint_1')


def test_axes_taken_from_the_baseline_refit_move_their_effects_to_rejected():
    """:func:`.baseline.with_axes_of`: the lost axis as refitted, its old effects rejected."""
    from frf_ident.core.diagnosis.crosscheck.baseline import (BASELINE_GROUPS, HeldOutSet,
                                                              ThreeModels, with_axes_of)
    rec, _ = _arm_record(6)
    robot = replace(robot_from_dict(RIGID), sample_rate=rec.fs)
    plain = diagnose_timeseries(rec, robot)
    alt = diagnose_timeseries(rec, robot, only={'joint_2': BASELINE_GROUPS})
    comp = [HeldOutSet('B.mat', ThreeModels(0.4, 0.25, 0.5),
                       {'joint_2': ThreeModels(0.4, 0.25, 0.5)})]
    got = with_axes_of(plain, alt, {'joint_2': ['B.mat']}, comp)
    assert got.extended.axes[1] == alt.extended.axes[1]
    assert [got.extended.axes[i] for i in (0, 2)] == [plain.extended.axes[i] for i in (0, 2)]
    assert sorted((e.name, e.axis) for e in got.effects) == sorted(
        [(e.name, e.axis) for e in plain.effects if e.axis != 'joint_2']
        + [(e.name, e.axis) for e in alt.effects if e.axis == 'joint_2'])
    old = [e for e in plain.effects if e.axis == 'joint_2']
    new = got.rejected[len(plain.rejected):]
    assert old and [(r.name, r.axis) for r in new] == [(e.name, e.axis) for e in old]
    assert all('B.mat: extended 0.500, least squares 0.250' in r.reason
               and "the baseline's terms" in r.reason for r in new)
