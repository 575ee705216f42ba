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
Lines above the analysis band: locked to position or to time (issue 55 item 4).

Truth the code did not produce: a one-axis record drawn here, its torque the model's own law
plus a torque ripple of 30 cycles per rad (locked to position: 30, 43.5 and 69 Hz at the
record's three steady speeds) and a 50 Hz line (locked to time), with white noise; and the
real EMPS record, whose residual the diagnosis scans.
"""
import math
from pathlib import Path

from frf_ident.core.diagnosis.line_cause import LineCause, mains_multiple
from frf_ident.core.diagnosis.timeseries.line_lock import steady_speeds
from frf_ident.core.diagnosis.timeseries.pipeline import diagnose_timeseries
from frf_ident.core.model.schema import robot_from_dict
from frf_ident.core.recording import Recording
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]
EMPS = ROOT.parent / 'shared' / 'data' / 'EMPS' / 'DATA_EMPS.mat'
FS = 1000.0
#: one stiff axis (the diagnosis takes it as rigid): the nominal model, exact but for the lines
MODEL = {'frf_ident_model': 1, 'sample_rate': FS, 'axes': [
    {'name': 'joint_1', 'motor_inertia': 0.5, 'link_inertia': 1.0, 'stiffness': 8.22e7,
     'damping': 524.0, 'viscous_friction': 0.5, 'coulomb_friction': 2.0, 'torque_limit': 1e4}],
    'controller': {'kind': 'pi_velocity', 'kp': [50.0], 'ki': [0.0]}}
SPEEDS = (1.0, 1.45, 2.3)       # rad/s
KAPPA = 30.0                    # ripple cycles per rad


def _record(seed: int = 4) -> Recording:
    """Return 36 s of plateaus at SPEEDS (1.5 s each, both ways) joined by 0.3 s cosine ramps."""
    rng = np.random.default_rng(seed)
    levels = [s * d for d in (1, -1) for s in SPEEDS] * 4
    v_parts = [np.zeros(0)]
    prev = 0.0
    for lv in levels:
        ramp = prev + (lv - prev) * 0.5 * (1 - np.cos(np.linspace(0, math.pi, int(0.3 * FS))))
        v_parts += [ramp, np.full(int(1.5 * FS), lv)]
        prev = lv
    v = np.concatenate(v_parts)
    t = np.arange(v.size) / FS
    q = np.cumsum(v) / FS
    a = np.gradient(v, 1 / FS)
    u = (1.5 * a + 0.5 * v + 2.0 * np.sign(v) + 0.4 * np.sin(2 * math.pi * KAPPA * q + 0.3)
         + 0.3 * np.sin(2 * math.pi * 50.0 * t + 1.1) + 0.05 * rng.standard_normal(t.size))
    return Recording(t, ['joint_1'], q[:, None], (v + 1e-4 * rng.standard_normal(t.size))[:, None],
                     u[:, None])


def test_mains_multiples_are_labelled():
    assert mains_multiple(50.3, 0.5) == '1 x 50 Hz'
    assert mains_multiple(120.0, 1.0) == '2 x 60 Hz'
    assert mains_multiple(33.0, 1.0) is None


def test_the_record_steady_speeds_are_found():
    found = steady_speeds(_record().velocity[:, 0], FS)
    assert [round(s, 2) for s, _ in found] == list(SPEEDS), found
    assert all(len(runs) == 8 for _, runs in found)


def test_a_ripple_and_a_fixed_line_in_one_record_are_told_apart():
    """Classify the ripple's lines as locked to position, the 50 Hz line as locked to time."""
    robot = robot_from_dict(MODEL)
    res = diagnose_timeseries(_record(), robot)
    peaks = [u for u in res.unexplained if u.cause is not None]
    for u in peaks:
        print(f'{u.signature.peak_hz:g} Hz ({u.kind}): {u.cause.describe()}')
    by_hz = {round(u.signature.peak_hz): u.cause for u in peaks}
    ripple = [KAPPA * s for s in SPEEDS]
    assert 50 in by_hz, by_hz
    assert by_hz[50].locked_to == 'time' and by_hz[50].mains_multiple == '1 x 50 Hz'
    for f in ripple:
        hit = [c for hz, c in by_hz.items() if abs(hz - f) <= 1.0]
        assert hit, (f, by_hz)
        assert hit[0].locked_to == 'position', hit[0]
        assert hit[0].cycles_per_unit == pytest.approx(KAPPA, rel=0.03)
    # nothing else: the scan's false alarms would be lines of their own
    assert len(peaks) == 4, by_hz


@pytest.mark.skipif(not EMPS.is_file(), reason='shared EMPS data not present')
def test_emps_lines_with_their_cause():
    """
    Name what locks each of the EMPS residual's lines.

    The record holds two steady speeds, 0.083 and 0.125 m/s (8 times each): the 33 Hz line
    at the first moves to 50 Hz at the second (400 cycles per metre: 2.5 mm of travel per
    cycle), so both are locked to position, and the 50 Hz line, a mains multiple by its
    frequency, is not the mains. The 445 Hz resonance stays put: locked to time. At 100 Hz
    both hypotheses find a line at the other speed (the ripple's 2nd and 3rd harmonics land
    on 100 Hz at the two speeds, 2 : 3): not determined, and so said.
    """
    from frf_ident.app.diagnose import load_data
    from frf_ident.io.model_file import load_model
    from dataclasses import replace
    rec = load_data(EMPS, ROOT / 'config' / 'map_emps.yaml')
    robot = replace(load_model(ROOT / 'config' / 'model_emps.yaml')[1], sample_rate=rec.fs)
    res = diagnose_timeseries(rec, robot)
    cause = {round(u.signature.peak_hz): u.cause for u in res.unexplained if u.cause}
    for hz, c in sorted(cause.items()):
        print(f'{hz} Hz: {c.describe()}')
    # every line the scan keeps carries its class and the evidence at each steady speed
    lines = [u for u in res.unexplained if u.misfit_share is None]
    assert lines and all(u.cause is not None and u.cause.speeds for u in lines), lines
    assert all(u.cause.to_dict()['speeds'] for u in lines)
    assert cause[33].locked_to == 'position' and cause[50].locked_to == 'position'
    assert cause[33].cycles_per_unit == pytest.approx(400, rel=0.02)
    assert cause[50].cycles_per_unit == pytest.approx(cause[33].cycles_per_unit, rel=0.02)
    assert cause[50].mains_multiple == '1 x 50 Hz' and 'not the mains' in cause[50].describe()
    assert cause[445].locked_to == 'time'
    assert cause[100].locked_to == 'undetermined' and cause[100].mains_multiple == '2 x 50 Hz'


def test_each_class_names_its_causes_in_a_drives_engineers_words():
    """A class says which causes it leaves: what moves with speed, what stays put."""
    ripple = LineCause('position', 30.0, 'r', cycles_per_unit=30.0).describe()
    mains = LineCause('time', 100.0, 'r', mains_multiple='2 x 50 Hz').describe()
    assert 'cogging' in ripple and 'gear mesh' in ripple and 'mains' not in ripple
    assert 'the mains, PWM or a structural mode' in mains and 'at a mains multiple' in mains
    assert 'not determined' in LineCause('undetermined', 100.0, 'r').describe()
