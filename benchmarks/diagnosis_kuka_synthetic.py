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
The KUKA KR300 halves repeated on synthetic records of known truth (Monte-Carlo).

What the halves of trajectory A can determine under noise alone: the whole record's extended
model as truth plus white noise at the record's level, each half diagnosed on its own
(:func:`kuka_synthetic_halves`, rows :func:`kuka_synthetic_halves_rows` of section
``diagnosis_real``).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, TYPE_CHECKING

from benchmarks.diagnosis_kuka import estimates, KUKA
import numpy as np

if TYPE_CHECKING:
    from frf_ident.core.diagnosis import DiagnosisResult

ROOT = Path(__file__).resolve().parents[1]


def _report(res: DiagnosisResult) -> dict[str, Any]:
    """Return the effects and rejected candidates of a core result as report.json has them."""
    return {'effects': [e.to_dict() for e in res.effects],
            'rejected': [r.to_dict() for r in res.rejected]}


def kuka_synthetic_halves(runs: int = 20, seed: int = 0) -> dict[str, Any]:
    """
    Diagnose the halves of KUKA trajectory A on synthetic records of known truth.

    The truth is the whole record's extended model: its torque for the recorded motion
    (inverse dynamics) plus white noise at the level the record itself has
    (:func:`noise_level` of its residual), ``runs`` realisations; each half diagnosed on its
    own as in :func:`kuka_halves_rows`. Returns 'truth', 'sigma', 'real' (the real record's
    halves), 'est' ({parameter: per half the list of (value, standard error)}), 'named_both'
    and 'agree' ({parameter: records naming it in both halves, and of these the ones
    within 20 %}). Needs the KUKA data (:data:`KUKA`).
    """
    from frf_ident.app.diagnose import load_data
    from frf_ident.core.diagnosis.prediction import noise_level
    from frf_ident.core.diagnosis.regressors import model_residual
    from frf_ident.core.diagnosis.timeseries import diagnose_timeseries
    from frf_ident.core.recording import Recording
    from frf_ident.io.model_file import load_model
    robot = load_model(ROOT / 'config' / 'model_kuka_kr300_axes123.yaml')[1]
    full = load_data(KUKA, ROOT / 'config' / 'map_kuka_kr300.yaml')
    # the model's axes are the record's first joints (as diagnose maps them)
    rec = full.select_joints(full.joint_names[:robot.n_axes])
    whole = diagnose_timeseries(rec, robot)
    truth = estimates(_report(whole))
    f = model_residual(rec, whole.extended)[0]
    sigma = np.sqrt(noise_level(f, rec.fs) * rec.fs / 2)
    n = rec.t.size // 2

    def halves(effort):
        out = []
        for sl in (slice(0, n), slice(n, None)):
            part = Recording(rec.t[sl] - rec.t[sl][0], rec.joint_names, rec.position[sl],
                             rec.velocity[sl], effort[sl])
            res = diagnose_timeseries(part, robot)
            out.append(estimates(_report(res)))
        return out
    real = halves(rec.effort)
    rng = np.random.default_rng(seed)
    est: dict[tuple, list[list[tuple]]] = {}
    # per parameter: records whose two halves both name it, and of these the ones within 20 %
    named_both: dict[tuple, int] = {}
    agree_k: dict[tuple, int] = {}
    for _ in range(runs):
        u = rec.effort.copy()
        # the truth's torque for the recorded motion (between samples, as the residual)
        u[:-1] = rec.effort[:-1] - f + sigma * rng.standard_normal(f.shape)
        h = halves(u)
        for k in set(h[0]) & set(h[1]):
            named_both[k] = named_both.get(k, 0) + 1
            agree_k[k] = agree_k.get(k, 0) + int(
                bool(h[0][k][0]) and abs(h[1][k][0] / h[0][k][0] - 1) <= 0.2)
        for j in (0, 1):
            for k, x in h[j].items():
                est.setdefault(k, [[], []])[j].append(x)
    return {'truth': truth, 'sigma': sigma, 'real': real, 'est': est,
            'named_both': named_both, 'agree': agree_k}


def kuka_synthetic_halves_rows(runs: int = 20, seed: int = 0) -> list[tuple[str, str, str, str]]:
    """
    Return the rows of the KUKA halves repeated on synthetic records of known truth.

    What can the halves of trajectory A determine at all? The whole record's extended model is
    taken as the truth: its torque for the recorded motion (inverse dynamics) plus white noise
    at the level the record itself has (:func:`noise_level` of its residual), ``runs``
    realisations. Each half is diagnosed on its own as in :func:`kuka_halves_rows`. Rows: the
    share of parameters named in both halves that agree within 20 % (the goal), and per
    parameter the mean and Monte-Carlo spread of each half's estimate against the truth, the
    records whose halves agree within 20 % (of those naming it in both), the mean reported
    standard error against that spread, and the real record's halves. A real
    difference far outside the synthetic spread is no noise: the model lacks a term there.
    """
    if not KUKA.is_file():
        return []
    syn = kuka_synthetic_halves(runs, seed)
    truth, sigma, real, est = syn['truth'], syn['sigma'], syn['real'], syn['est']
    named_both, agree_k = syn['named_both'], syn['agree']
    real_both = set(real[0]) & set(real[1])
    real_agree = sum(abs(real[1][k][0] / real[0][k][0] - 1) <= 0.2 for k in real_both)
    agree, pairs = sum(agree_k.values()), sum(named_both.values())
    rows = [("KUKA A halves on synthetic records (the whole record's extended model as truth, "
             f'white noise {", ".join(f"{s:.2f}" for s in sigma)} N m as measured), '
             f'{runs} records: parameters of both halves within 20 %',
             f'{agree}/{pairs} ({100 * agree / max(pairs, 1):.0f} %)',
             f'real record {real_agree}/{len(real_both)}',
             'what the halves can determine under noise alone')]
    for k in sorted(est, key=lambda k: (k[0], k[1])):
        cells, ratio = [], []
        for j in (0, 1):
            x = np.array([v for v, _ in est[k][j]], float)
            se = np.array([s if s is not None else math.nan for _, s in est[k][j]], float)
            if x.size < 2:
                cells.append(f'named {x.size}/{runs}')
                continue
            sd = float(np.std(x, ddof=1))
            cells.append(f'{x.mean():.3g} +- {sd:.2g} ({x.size}/{runs})')
            if np.isfinite(se).any() and sd > 0:
                ratio.append(f'{np.nanmean(se) / sd:.1f}')
        rr = ' / '.join(f'{real[j][k][0]:.3g}' if k in real[j] else '-' for j in (0, 1))
        rows.append((f'... {k[0]} {k[1]}: each half, mean +- spread (named)',
                     ' / '.join(cells),
                     f'truth {truth[k][0]:.3g}; real halves {rr}' if k in truth else
                     f'truth: none; real halves {rr}',
                     '; '.join(x for x in (
                         f'halves within 20 % {agree_k[k]}/{named_both[k]}'
                         if k in named_both else '',
                         f'reported SE / spread {" / ".join(ratio)}' if ratio else '') if x)))
    return rows
