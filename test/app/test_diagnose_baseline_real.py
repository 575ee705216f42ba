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
Hold the report's least-squares baseline to a plain engineer's fit on the KUKA record.

Issue 55 item 3. The outside fit is computed here, with nothing of the diagnosis: per axis
motor torque ~ inertia qdd + viscous qd + Coulomb tanh(qd / 0.01) + offset, least squares on
every moving sample of the fitted record (speed above 5 % of its 95th percentile), velocity
and acceleration differentiated from the motor positions low-passed at 20 Hz (4th-order
Butterworth, zero phase), torque low-passed alike. Both fits are scored by the one
definition of ``time_nrmse`` (the same rows of the held-out set), so the figures differ by
the fit alone.

Trajectories B and C are not in ../shared/data; what A alone can check: A's own held-out
blocks (the outside fit on the diagnosis' fit rows) and A's two halves as records (each
fitted alone, judged on the other). In each half axes 1 and 3 move one way only: Coulomb
friction and offset are one constant there and no 4-parameter fit is determined (the outside
fit extrapolates axis 3 of the first half 280 times off); those axis-records are printed,
not compared.
"""
import math
import os
from pathlib import Path

from frf_ident.app.diagnose import diagnose, load_data
from frf_ident.bag import write_recording
from frf_ident.core.diagnosis.common import bridge_gaps
from frf_ident.core.diagnosis.prediction import torque_metrics
from frf_ident.core.recording import Recording
import numpy as np
import pytest
from scipy import signal

ROOT = Path(__file__).resolve().parents[2]
KUKA = ROOT.parent / 'shared' / 'data' / 'KUKA_KR300_Weigand2021' / 'recorded_FF_A_2020-10-21.mat'
CFG = ROOT / 'config'
AXES = ['joint_1', 'joint_2', 'joint_3']


def _signals(rec: Recording) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return velocity, acceleration and torque of the first three joints, as the outside fit."""
    sos = signal.butter(4, 20.0, fs=rec.fs, output='sos')
    q = signal.sosfiltfilt(sos, rec.position[:, :3], axis=0)
    v = np.gradient(q, rec.dt, axis=0)
    return v, np.gradient(v, rec.dt, axis=0), signal.sosfiltfilt(sos, rec.effort[:, :3], axis=0)


def _columns(v: np.ndarray, a: np.ndarray, i: int) -> np.ndarray:
    return np.column_stack([a[:, i], v[:, i], np.tanh(v[:, i] / 0.01), np.ones(v.shape[0])])


def _outside_fit(rec: Recording, rows: np.ndarray | None = None):
    """Return per axis the 4 coefficients and the share of its fitted samples moving forward."""
    v, a, u = _signals(rec)
    speed = np.abs(v)
    move = speed > 0.05 * np.percentile(speed, 95, axis=0)
    if rows is not None:
        move[:-1] &= rows[:, None]
        move[-1] = False
    out = []
    for i in range(3):
        m = move[:, i]
        coef = np.linalg.lstsq(_columns(v, a, i)[m], u[m, i], rcond=None)[0]
        out.append((coef, float(np.mean(v[m, i] > 0))))
    return out


def _outside_nrmse(rec: Recording, fit, mask=None) -> dict[str, float]:
    """Return per axis the outside fit's time_nrmse on ``rec`` (the report's definition)."""
    v, a, u = _signals(rec)
    pred = np.column_stack([_columns(v, a, i) @ c for i, (c, _) in enumerate(fit)])
    three = rec.select_joints(rec.joint_names[:3])
    bridged, lost = bridge_gaps(three)
    scores = torque_metrics(bridged, lost, (u - pred)[:-1], AXES, mask=mask).scores
    return {ax: scores.per_axis[ax].time_nrmse for ax in AXES}


@pytest.mark.skipif(not KUKA.is_file(), reason='shared KUKA data not present')
def test_the_baseline_is_as_strong_as_an_outside_fit_on_kuka_a(tmp_path):
    """
    Keep the report's baseline within 5 % of the outside fit on every determined axis-record.

    Before (fitted on the diagnosis' fit rows for the other records too) the second half's
    baseline predicted axis 2 of the first half with 0.524 against the outside fit's 0.475
    (10 % weaker); fitted on every usable row of the half, 0.471.
    """
    full = load_data(KUKA, CFG / 'map_kuka_kr300.yaml')
    model = CFG / 'model_kuka_kr300_axes123.yaml'
    rows = []          # (axis-record, report baseline, outside fit, extended, verdict)
    res = diagnose(KUKA, model, tmp_path / 'A', map_path=CFG / 'map_kuka_kr300.yaml',
                   progress=lambda _m: None)
    ls = res.checks.least_squares
    out = _outside_nrmse(full, _outside_fit(full, res.result.fit_rows),
                         res.result.held_out_rows)
    for v in ls.verdicts:
        rows.append((f'A held out {v.axis}', ls.held_out_as_fitted[0].per_axis[v.axis]
                     .least_squares, out[v.axis], v.extended, v.verdict))
    n = full.t.size // 2
    halves = []
    for k, sl in enumerate((slice(0, n), slice(n, None))):
        part = Recording(full.t[sl] - full.t[sl][0], full.joint_names, full.position[sl],
                         full.velocity[sl], full.effort[sl], meta=dict(full.meta))
        halves.append((part, write_recording(part, tmp_path / f'half{k}')))
    skipped = []
    for k in (0, 1):
        res = diagnose(halves[k][1], model, tmp_path / f'd{k}', validate=[halves[1 - k][1]],
                       progress=lambda _m: None)
        ls = res.checks.least_squares
        fit = _outside_fit(halves[k][0])
        out = _outside_nrmse(halves[1 - k][0], fit)
        report = ls.held_out_as_fitted[1].per_axis
        after = {v.axis: v for v in ls.verdicts if v.record == str(halves[1 - k][1])}
        for i, ax in enumerate(AXES):
            label = f'half {k + 1} -> half {2 - k} {ax}'
            if min(fit[i][1], 1 - fit[i][1]) < 0.05:
                skipped.append(f'{label} (moves one way: {100 * fit[i][1]:.0f} % forward; '
                               f'report {report[ax].least_squares:.3f}, outside {out[ax]:.3g})')
                continue
            rows.append((label, report[ax].least_squares, out[ax], after[ax].extended,
                         after[ax].verdict))
    for r in rows:
        print(f'{r[0]}: time_nrmse report baseline {r[1]:.3f}, outside fit {r[2]:.3f} '
              f'({100 * (r[1] / r[2] - 1):+.1f} %), extended {r[3]:.3f} ({r[4]})')
    print('not determined by a 4-parameter fit:', '; '.join(skipped))
    assert len(rows) == 5, rows
    assert all(r[1] <= 1.05 * r[2] for r in rows), rows
    # the extended model at or below the outside fit: A's held-out blocks and half 1 -> 2;
    # half 2 -> 1 axis 2 loses by 10 % (0.521 against 0.475) and the report says so
    at_or_below = sum(r[3] <= r[2] for r in rows)
    print(f'extended at or below the outside fit on {at_or_below} of {len(rows)}')
    assert at_or_below >= 4, rows
    assert all(r[4] == 'loses' for r in rows if r[3] > 1.1 * r[1]), rows
    assert not any(math.isnan(r[1]) for r in rows)


#: directory with the authors' trajectories B.mat and C.mat (benchmarks.diagnosis_kuka.KUKA_BC_ENV;
#: not in ../shared/data: JonasWeigand/Robot_Identification on GitHub,
#: data/recorded_trajectories/2020-10-21 10s FF {B,C} 08ms/data.mat)
KUKA_BC = Path(os.environ.get('KUKA_BC', '') or '/nonexistent')


NO_BC = not (KUKA.is_file() and (KUKA_BC / 'B.mat').is_file() and (KUKA_BC / 'C.mat').is_file())


def _b_and_c_rows(tmp_path, urdf: Path | None = None) -> list[tuple]:
    """
    Return per axis-record of B and C the report's baseline, the outside fit and the model.

    Rows (axis-record, report baseline, outside fit, extended as written, verdict, extended
    as fitted): A diagnosed with B and C as ``--validate`` records, the outside fit on all of
    A's moving samples (:func:`_outside_fit`), every figure the report's ``time_nrmse``.
    """
    full = load_data(KUKA, CFG / 'map_kuka_kr300.yaml')
    others = [KUKA_BC / 'B.mat', KUKA_BC / 'C.mat']
    res = diagnose(KUKA, CFG / 'model_kuka_kr300_axes123.yaml', tmp_path / 'abc',
                   map_path=CFG / 'map_kuka_kr300.yaml', validate=others, urdf=urdf,
                   progress=lambda _m: None)
    ls = res.checks.least_squares
    fit = _outside_fit(full)
    rows = []
    for path, name in zip(others, 'BC'):
        out = _outside_nrmse(load_data(path, CFG / 'map_kuka_kr300.yaml'), fit)
        final = next(s for s in ls.held_out if s.record == str(path)).per_axis
        fitted = next(s for s in ls.held_out_as_fitted if s.record == str(path)).per_axis
        verdict = {v.axis: v.verdict for v in ls.verdicts if v.record == str(path)}
        for ax in AXES:
            rows.append((f'{name} {ax}', final[ax].least_squares, out[ax], final[ax].extended,
                         verdict[ax], fitted[ax].extended))
    for r in rows:
        print(f'A -> {r[0]}: time_nrmse report baseline {r[1]:.3f}, outside fit {r[2]:.3f} '
              f'({100 * (r[1] / r[2] - 1):+.1f} %), extended as written {r[3]:.3f} ({r[4]}), '
              f'as fitted {r[5]:.3f}')
    print(f'extended at or below the outside fit on {sum(r[3] <= r[2] for r in rows)} of '
          f'{len(rows)}')
    return rows


@pytest.mark.skipif(NO_BC, reason='KUKA_BC (a directory with trajectories B.mat, C.mat) not set')
def test_the_baseline_is_as_strong_as_an_outside_fit_on_kuka_b_and_c(tmp_path):
    """
    Fit on KUKA trajectory A, predict B and C: the report's baseline against the outside fit.

    Issue 55's must-show: the report's baseline within 5 % of the outside 4-parameter fit
    (fitted here on all of A's moving samples) on each of the six axis-records of B and C
    (measured: -0.4 to +0.0 %), and the model the diagnosis writes ties or beats it on each
    (measured: ties, at most 0.9 % above; as fitted, before the rule, axis 1 lost on B and C
    and axis 3 on C by 21-68 %).
    """
    rows = _b_and_c_rows(tmp_path)
    assert len(rows) == 6
    assert all(r[1] <= 1.05 * r[2] for r in rows), rows
    assert all(r[4] in ('beats', 'ties') for r in rows), rows


@pytest.mark.skipif(NO_BC, reason='KUKA_BC (a directory with trajectories B.mat, C.mat) not set')
def test_with_the_urdf_axis_1_beats_the_outside_fit_on_b_and_c(tmp_path):
    """
    Given the robot's URDF, axis 1's pose-dependent inertia beats the outside fit 2.5x over.

    ``--urdf urdf/kuka_kr300_axes123.urdf``: axis 1 carries 1.95 +- 0.28 of the URDF's
    inertia and Coriolis torque (its link inertia follows the arm's reach, the authors'
    m_all 1206-1856 kg m^2 over A, 729-1351 over B) and predicts B and C at 0.122 / 0.090
    against the outside fit's 0.354 / 0.283 (2.9 and 3.1 times lower); nothing loses to it.
    """
    rows = _b_and_c_rows(tmp_path, ROOT / 'urdf' / 'kuka_kr300_axes123.urdf')
    assert all(r[1] <= 1.05 * r[2] for r in rows), rows
    assert all(r[4] in ('beats', 'ties') for r in rows), rows
    axis_1 = [r for r in rows if r[0].endswith('joint_1')]
    assert all(r[3] < r[2] / 2.5 for r in axis_1), axis_1


@pytest.mark.skipif(NO_BC, reason='KUKA_BC (a directory with trajectories B.mat, C.mat) not set')
def test_with_the_urdf_the_written_model_is_at_or_below_the_outside_fit_on_5_of_6(tmp_path):
    """
    Issue 55's must-show: the model written with the URDF at or below the outside fit on 5 of 6.

    Axis 3 as fitted (free gravity sinusoids dropped on B and C) loses on C (0.301 against
    0.210); refitted with the baseline's terms and its shares of the URDF's inertia and
    gravity on all of A's usable rows it predicts B and C at 0.261 / 0.178 against 0.518 /
    0.210. Axis 2 ties on C (0.475 against 0.470): the one axis-record above. Without the
    URDF 2 of 6 (all ties).
    """
    rows = _b_and_c_rows(tmp_path, ROOT / 'urdf' / 'kuka_kr300_axes123.urdf')
    assert sum(r[3] <= r[2] for r in rows) >= 5, rows
