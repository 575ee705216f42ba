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
What on KUKA A -> B, C a model beyond the 4-parameter baseline would have to hold.

``KUKA_BC=DIR python -m benchmarks.kuka_rigid_body`` (DIR holds the authors' trajectories
B.mat and C.mat; JonasWeigand/Robot_Identification on GitHub, not in ../shared/data).

Outside fits with nothing of the diagnosis, as test/app/test_diagnose_baseline_real.py's:
per axis on all of A's moving samples (speed above 5 % of its 95th percentile), velocity and
acceleration from the motor positions low-passed at 20 Hz (4th-order Butterworth, zero
phase), torque alike; each predicts B and C, scored by the report's ``time_nrmse`` (the
first row is that test's outside fit). Rows: the 4 parameters (inertia, viscous,
tanh-Coulomb, offset); with one column more per axis, the link-side inertia torque (M(q)
qdd)_i / gear_i of urdf/kuka_kr300_axes123.urdf (pinocchio; the file's masses are assumed,
its lengths the data sheet's), scaled by a fitted factor; with its gravity g_i(q) / gear_i
as well; and the authors' own rigid-body torques stored in the records (``tau_a_all``
inertia, ``tau_c_all`` Coriolis, ``tau_g_all`` gravity), each scaled per axis. Axis 1's
link inertia changes with the reach of the arm (the authors' ``m_all``: 1206-1856 kg m^2
over A, 729-1351 over B); a constant inertia fitted on A cannot follow it. The diagnosis
offers the inertia torque with ``--urdf`` (effect ``pose_dependent_inertia``); the gravity
scaled per axis it does not.
"""
from __future__ import annotations

import os
from pathlib import Path
import sys

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
KUKA_A = (ROOT.parent / 'shared' / 'data' / 'KUKA_KR300_Weigand2021'
          / 'recorded_FF_A_2020-10-21.mat')
AXES = 3


def _signals(rec):
    """Return q, qd, qdd and torque of the first three joints, low-passed (the outside fit's)."""
    from scipy import signal
    sos = signal.butter(4, 20.0, fs=rec.fs, output='sos')
    q = signal.sosfiltfilt(sos, rec.position[:, :AXES], axis=0)
    v = np.gradient(q, rec.dt, axis=0)
    u = signal.sosfiltfilt(sos, rec.effort[:, :AXES], axis=0)
    return q, v, np.gradient(v, rec.dt, axis=0), u


def _urdf_torques(q: np.ndarray, a: np.ndarray) -> dict[str, np.ndarray]:
    """Return the URDF's link-side inertia and gravity torques on the motor side, (N, 3) each."""
    from frf_ident.io.kinematics import load_kinematics
    kin = load_kinematics(ROOT / 'urdf' / 'kuka_kr300_axes123.urdf',
                          [f'joint_{i + 1}' for i in range(AXES)])
    inertia, gravity = np.zeros_like(q), np.zeros_like(q)
    for k in range(q.shape[0]):
        side = kin.at(q[k])
        inertia[k], gravity[k] = side.inertia @ a[k], side.gravity
    return {'urdf_inertia': inertia / kin.reduction, 'urdf_gravity': gravity / kin.reduction}


def _columns(sig, extra: dict[str, np.ndarray], names: tuple[str, ...], i: int) -> np.ndarray:
    _, v, a, _ = sig
    cols = [a[:, i], v[:, i], np.tanh(v[:, i] / 0.01), np.ones(v.shape[0])]
    return np.column_stack(cols + [extra[n][:, i] for n in names])


def _moving(v: np.ndarray) -> np.ndarray:
    return np.abs(v) > 0.05 * np.percentile(np.abs(v), 95, axis=0)


def rows(bc: Path) -> list[tuple[str, list[float]]]:
    """Return per model the time_nrmse on B and C of axes 1-3 (B1 B2 B3 C1 C2 C3)."""
    from frf_ident.app.diagnose import load_data
    from frf_ident.core.diagnosis.common import bridge_gaps
    from frf_ident.core.diagnosis.prediction import torque_metrics
    from scipy.io import loadmat
    mp = ROOT / 'config' / 'map_kuka_kr300.yaml'
    paths = {'A': KUKA_A, 'B': bc / 'B.mat', 'C': bc / 'C.mat'}
    recs, sig, extra = {}, {}, {}
    for name, path in paths.items():
        recs[name] = load_data(path, mp)
        sig[name] = _signals(recs[name])
        mat = loadmat(path, squeeze_me=True)
        extra[name] = {k: np.asarray(mat[k])[:AXES].T
                       for k in ('tau_a_all', 'tau_c_all', 'tau_g_all')}
        extra[name].update(_urdf_torques(sig[name][0], sig[name][2]))
    models = [('4 parameters', ()), ('+ URDF inertia M(q) qdd', ('urdf_inertia',)),
              ('+ URDF inertia and gravity', ('urdf_inertia', 'urdf_gravity')),
              ("+ the authors' inertia, Coriolis, gravity",
               ('tau_a_all', 'tau_c_all', 'tau_g_all'))]
    names = recs['A'].joint_names[:AXES]
    out = []
    for label, cols in models:
        move = _moving(sig['A'][1])
        coef = [np.linalg.lstsq(_columns(sig['A'], extra['A'], cols, i)[move[:, i]],
                                sig['A'][3][move[:, i], i], rcond=None)[0] for i in range(AXES)]
        errors = []
        for other in 'BC':
            e = np.column_stack([sig[other][3][:, i]
                                 - _columns(sig[other], extra[other], cols, i) @ coef[i]
                                 for i in range(AXES)])
            rec, lost = bridge_gaps(recs[other].select_joints(names))
            per = torque_metrics(rec, lost, e[:-1], names).scores.per_axis
            errors += [per[n].time_nrmse for n in names]
        out.append((label, errors))
    return out


def main() -> int:
    """Print the table (nothing without KUKA_BC)."""
    bc = Path(os.environ.get('KUKA_BC', '') or '/nonexistent')
    if not ((bc / 'B.mat').is_file() and (bc / 'C.mat').is_file() and KUKA_A.is_file()):
        print('KUKA_BC must name a directory with B.mat and C.mat (and ../shared/data KUKA A)',
              file=sys.stderr)
        return 2
    print("fitted on A; time_nrmse on B and C (the report's definition)")
    head = ' '.join(f'{r}{i + 1:d}'.rjust(6) for r in 'BC' for i in range(AXES))
    print(f'{"model":44s} {head}')
    for label, errors in rows(bc):
        print(f'{label:44s} ' + ' '.join(f'{e:6.3f}' for e in errors))
    from scipy.io import loadmat
    for name, path in (('A', KUKA_A), ('B', bc / 'B.mat'), ('C', bc / 'C.mat')):
        m = np.asarray(loadmat(path, squeeze_me=True)['m_all'])[0]
        print(f"axis 1 link inertia over {name} (the authors' m_all): {m.min():.0f}-{m.max():.0f} "
              f'kg m^2')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
