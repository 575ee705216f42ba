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
The KUKA KR300 diagnosis of trajectory A beside the least-squares baseline, on B and C.

Rows of section ``diagnosis_real`` (issue #41): per axis and pooled the NRMSE of the nominal
model, the least-squares baseline and the extended model on A's held-out blocks and on the
other trajectories B and C (:func:`kuka_baseline_rows`).
"""
from __future__ import annotations

import os
from pathlib import Path
import tempfile
from typing import Any

from benchmarks.diagnosis_kuka import KUKA, KUKA_BC_ENV

ROOT = Path(__file__).resolve().parents[1]


def kuka_baseline_rows() -> list[tuple[str, str, str, str]]:
    """
    Return per axis and pooled the NRMSE of nominal / least squares / extended on B and C.

    KUKA trajectory A diagnosed with B and C as ``--validate`` records (issue #41), with the
    gravity the diagnosis fits per axis and, beside it, with the gravity of
    urdf/kuka_kr300_axes123.urdf (``--urdf``: base parameters fitted jointly): the extended
    model as fitted on A (after its gravity and ripple terms were kept or dropped on B and C)
    beside the 4-parameter least-squares baseline fitted on the same data, on A's held-out
    blocks and on B and C; per axis what became of its position-dependent terms and whether
    its effects were kept; the standard errors against the spread between A, B and C. Empty
    unless KUKA_BC names a directory holding B.mat and C.mat.
    """
    bc = Path(os.environ.get(KUKA_BC_ENV, '') or '/nonexistent')
    others = [bc / 'B.mat', bc / 'C.mat']
    if not all(p.is_file() for p in others):
        return []
    from frf_ident.app.diagnose import diagnose
    cfg = ROOT / 'config'
    rows = []
    for label, urdf in (('', None), (' --urdf', ROOT / 'urdf' / 'kuka_kr300_axes123.urdf')):
        with tempfile.TemporaryDirectory() as tmp:
            res = diagnose(KUKA, cfg / 'model_kuka_kr300_axes123.yaml', Path(tmp) / 'A',
                           map_path=cfg / 'map_kuka_kr300.yaml', validate=others, urdf=urdf,
                           progress=lambda _m: None)
        rows += _baseline_rows(res.report()['metrics'], others, label)
    return rows


def _baseline_rows(m: dict[str, Any], others: list[Path], label: str
                   ) -> list[tuple[str, str, str, str]]:
    """Return the rows of :func:`kuka_baseline_rows` of one report's metrics."""
    from frf_ident.core.diagnosis.thresholds import LS_BASELINE_MARGIN
    ls, rows = m['least_squares'], []
    names = {str(others[0]): 'B', str(others[1]): 'C'}
    for s in ls['held_out_as_fitted']:
        name = names.get(s['record'], 'A held out')
        t = s['time_nrmse']
        rows.append((f'KUKA A{label} fitted, on {name}: NRMSE nominal / LS / extended',
                     f'{t["nominal"]:.3f} / {t["least_squares"]:.3f} / {t["extended"]:.3f}',
                     'pooled over axes 1-3', ''))
        for ax, v in s['per_axis'].items():
            rows.append((f'... {ax}', f'{v["nominal"]:.3f} / {v["least_squares"]:.3f} / '
                                      f'{v["extended"]:.3f}', '',
                         'extended at or below LS' if v['extended'] <= v['least_squares']
                         else 'tie (within the 10 % margin)' if v['extended'] <= (
                             1 + LS_BASELINE_MARGIN) * v['least_squares']
                         else 'least squares wins'))
    for ax, v in m.get('position_terms_on_validate', {}).items():
        rows.append((f'KUKA A{label}: {ax} gravity/ripple on B / C, NRMSE with -> without',
                     ' / '.join(f'{a:.3f} -> {b:.3f}' for a, b in zip(v['with'], v['without'])),
                     'dropped: does not generalise' if v['dropped'] else 'kept', ''))
    for ax, v in ls['extended_vs_baseline'].items():
        rows.append((f'KUKA A{label}: {ax} extended vs baseline', v.split(';')[0][:26],
                     "effects replaced by the baseline's terms" if 'replaced' in v
                     else 'effects rejected' if 'rejected' in v else 'effects kept', ''))
    for s in ls['held_out']:
        name = names.get(s['record'], 'A held out')
        rows.append((f'KUKA A{label} after the baseline rule, on {name}: LS / extended',
                     ', '.join(f'{v["least_squares"]:.3f} / {v["extended"]:.3f}'
                               for v in s['per_axis'].values()),
                     f'pooled {s["time_nrmse"]["least_squares"]:.3f} / '
                     f'{s["time_nrmse"]["extended"]:.3f}',
                     'at or below LS (10 % margin) on every axis' if all(
                         v['extended'] <= (1 + LS_BASELINE_MARGIN) * v['least_squares']
                         for v in s['per_axis'].values()) else 'least squares wins on an axis'))
    se = m.get('standard_errors_across') or {}
    if se.get('rms_z') is not None:
        rows.append((f'KUKA A{label}: parameter differences A - B, A - C [combined standard '
                     f'errors], RMS', f'{se["rms_z"]:.2f}',
                     f'{len(se["pairs"])} pairs, chi-square p = {se["p_value"]:.2g}',
                     f'standard errors widened x{se["factor"]:.2g}' if se['factor'] > 1
                     else 'standard errors hold'))
    return rows
