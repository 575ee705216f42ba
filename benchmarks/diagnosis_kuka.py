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
The KUKA KR300 diagnosis of measured data: halves of trajectory A, trajectories A, B, C.

Rows of section ``diagnosis_real``: the two halves of trajectory A diagnosed each on its own
(:func:`kuka_halves_rows`), the three trajectories each fitted and checked on the others
(:func:`kuka_trajectories_rows`, with the viscous slope per direction), and the reading of a
report's parameters and standard errors (:func:`estimates`) the other KUKA rows share
(benchmarks/diagnosis_kuka_baseline.py, benchmarks/diagnosis_kuka_synthetic.py).
"""
from __future__ import annotations

import math
import os
from pathlib import Path
import tempfile
from typing import Any, TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from frf_ident.core.model.params import RobotParams
    from frf_ident.core.recording import Recording

ROOT = Path(__file__).resolve().parents[1]
KUKA = ROOT.parent / 'shared' / 'data' / 'KUKA_KR300_Weigand2021' / 'recorded_FF_A_2020-10-21.mat'


def kuka_halves_rows() -> list[tuple[str, str, str, str]]:
    """
    Return the rows comparing the KUKA KR300 diagnosis of the two halves of trajectory A.

    Each half (5 s) is diagnosed on its own against config/model_kuka_kr300_axes123.yaml; rows:
    the effects each half names, every gravity term found in both halves (amplitude ratio,
    phase difference) and, as independent truth, the correlation of each half's fitted
    gravity torque of axis 3 with the authors' rigid-body gravity torque stored in the file
    (``tau_g_all``) over the whole trajectory. Empty when the data are not present.
    """
    if not KUKA.is_file():
        return []
    from frf_ident.app.diagnose import diagnose, load_data
    from frf_ident.bag import write_recording
    from frf_ident.core.recording import Recording
    from frf_ident.io.model_file import load_model
    from scipy.io import loadmat
    cfg = ROOT / 'config'
    rec = load_data(KUKA, cfg / 'map_kuka_kr300.yaml')
    tau_g = np.asarray(loadmat(KUKA, squeeze_me=True)['tau_g_all'])[:3].T
    n = rec.t.size // 2
    fits, errs, names, corr, unphysical = [], [], [], [], []
    # on an axis moving one way only the constant is load + Coulomb friction forward and
    # load - Coulomb backward: a different parameter in each half, per axis and direction
    consts: dict[str, dict[str, float]] = {}
    cross = []
    with tempfile.TemporaryDirectory() as tmp:
        bags = []
        for k, sl in enumerate((slice(0, n), slice(n, None), slice(0, None))):
            part = Recording(rec.t[sl] - rec.t[sl][0], rec.joint_names, rec.position[sl],
                             rec.velocity[sl], rec.effort[sl], meta=dict(rec.meta))
            bags.append(write_recording(part, Path(tmp) / f'half{k}'))
        for k, bag in enumerate(bags):
            # each half's extended model predicts the other half (data not used for fitting)
            res = diagnose(bag, cfg / 'model_kuka_kr300_axes123.yaml', Path(tmp) / f'd{k}',
                           validate=[bags[1 - k]] if k < 2 else [], progress=lambda _m: None)
            if k < 2:
                cross.append(res.report()['metrics']['validation_records'][0])
            one_way = one_way_axes(res.report())
            est = estimates(res.report())
            fit = {key: v for key, (v, _) in est.items()}
            err = {key: se for key, (_, se) in est.items()}
            for e in res.report()['effects']:
                if 'gravity_torque' in e['parameters'] and e['axis'] in one_way:
                    consts.setdefault(e['axis'], {})[one_way[e['axis']]] = float(
                        e['parameters']['gravity_torque'])
            fits.append(fit)
            errs.append(err)
            if k < 2:
                names.append(sorted(f'{e["name"]}@{e["axis"]}'
                                    for e in res.report()['effects']))
                unphysical.append(', '.join(
                    f'{r["name"]}@{r["axis"]} {r["fitted_value"]:.3g}'
                    for r in res.report().get('rejected', []) if 'fitted_value' in r)
                    or 'none')
            robot = load_model(Path(tmp) / f'd{k}' / 'extended_model.yaml')[1]
            g3 = robot.gravity_load(rec.position[:, :3])[:, 2]
            corr.append(float(np.corrcoef(g3, tau_g[:, 2])[0, 1]) if np.std(g3) > 0
                        else math.nan)
    rows = [('KUKA A halves: effects of the first half', ', '.join(names[0]), '', ''),
            ('... of the second half', ', '.join(names[1]), '', '')]
    both = sorted(set(fits[0]) & set(fits[1]))
    z = {}
    for key in both:
        a, b = fits[0][key], fits[1][key]
        sa, sb = errs[0].get(key), errs[1].get(key)
        if sa is not None and sb is not None and (sa or sb):
            z[key] = abs(a - b) / math.hypot(sa, sb)
        rows.append((f'... {key[0]} {key[1]} (standard error)',
                     f'{a:.3g} ({sa:.2g}) / {b:.3g} ({sb:.2g})' if key in z else
                     f'{a:.3g} / {b:.3g}',
                     (f'ratio {b / a:.2f}' if a else '')
                     + (f', difference {z[key]:.1f} combined SE' if key in z else ''),
                     'goal within 20 %'))
    agree = sum(abs(fits[1][k] / fits[0][k] - 1) <= 0.2 for k in both if fits[0][k])
    rows.append(('... parameters of both halves within 20 %', f'{agree}/{len(both)}',
                 f'named in one half only: {len(set(fits[0]) ^ set(fits[1]))}', ''))
    # the record's own uncertainty (block-robust standard errors of each half) against the
    # other half: a difference beyond it is no noise, the model lacks a term there
    rows.append(('... differences within 2 combined standard errors',
                 f'{sum(v <= 2.0 for v in z.values())}/{len(z)}',
                 'relative standard error of each half: ' + ', '.join(
                     f'{100 * errs[0][k] / abs(fits[0][k]):.0f}/'
                     f'{100 * errs[1][k] / abs(fits[1][k]):.0f} %' for k in z),
                 'beyond 2: more than noise'))
    # the two one-way constants of an axis that goes out in one half and back in the other
    # hold Coulomb friction and load separately: (forward - backward) / 2 and their mean
    for ax, c in sorted(consts.items()):
        if len(c) < 2:
            continue
        full = fits[2].get((ax, 'coulomb_friction'))
        fc = (c['forward'] - c['backward']) / 2
        rows.append((f'... {ax} Coulomb from the two one-way constants',
                     f'{fc:.3g} (load {(c["forward"] + c["backward"]) / 2:+.3g})',
                     f'whole record {full:.3g}' if full else 'whole record: none',
                     f'ratio {fc / full:.2f}' if full else ''))
    for k, v in enumerate(cross):
        per = ' '.join(f'{v["baseline"]["per_axis"][a]["time_nrmse"]:.2f}->'
                       f'{v["extended"]["per_axis"][a]["time_nrmse"]:.2f}'
                       for a in v['baseline']['per_axis'])
        rows.append((f'... model of the {("first", "second")[k]} half on the '
                     f'{("second", "first")[k]}: time NRMSE nominal -> extended',
                     f'{v["baseline"]["time_nrmse"]:.3f} -> {v["extended"]["time_nrmse"]:.3f}',
                     f'axes 1-3: {per}', 'held out: the other half'))
    rows.append(('... fitted outside the physical range, dropped (each half)',
                 ' / '.join(unphysical), '', ''))
    rows.append(("... axis-3 gravity vs the authors' tau_g (r, each half)",
                 ' / '.join(f'{c:.3f}' for c in corr[:2]), f'whole record {corr[2]:.3f}', ''))
    # what the authors' rigid-body gravity depends on: sinusoids of the model's joint sets
    # leave part of it, the wrist's pitch (record joint 5) the rest
    shares = []
    for extra in ((), (4,)):
        cols = [np.ones(rec.t.size)]
        for js in [(1,), (1, 2)] + ([(1, 2) + extra] if extra else []):
            arg = rec.position[:, list(js)].sum(axis=1)
            cols += [np.sin(arg), np.cos(arg)]
        X = np.column_stack(cols)
        res = [tau_g[:, i] - X @ np.linalg.lstsq(X, tau_g[:, i], rcond=None)[0] for i in (1, 2)]
        shares.append(' / '.join(f'{100 * np.std(r) / np.std(tau_g[:, i]):.1f}'
                                 for r, i in zip(res, (1, 2))))
    rows.append(("... authors' tau_g of axes 2 / 3 left by sinusoids of q2, q2 + q3 [% of RMS]",
                 shares[0], f'adding q2 + q3 + q5 (the wrist): {shares[1]}',
                 'the 3-axis model cannot hold the wrist load'))
    # why the halves cannot agree: the trajectory goes out and back, so within a half an axis
    # whose velocity keeps one sign cannot tell Coulomb friction from a constant load, and
    # its gravity curve is seen over one sweep of its angle only
    share = []
    for sl in (slice(0, n), slice(n, None)):
        v = rec.velocity[sl, :3]
        moving = np.abs(v) > math.radians(1.0)
        share.append(' '.join(f'{100 * np.mean(v[moving[:, i], i] > 0):.0f}'
                              for i in range(3)))
    rows.append(('... share of moving samples with positive velocity, axes 1-3 [%]',
                 ' / '.join(share), 'one-signed: Coulomb = constant offset in that half', ''))
    return rows


#: directory with the authors' other trajectories, B.mat and C.mat (not in ../shared/data:
#: JonasWeigand/Robot_Identification, commit 9e403c07, data/recorded_trajectories/
#: "2020-10-21 10s FF {B,C} 08ms"/data.mat, MIT), e.g. KUKA_BC=<dir with B.mat and C.mat>
KUKA_BC_ENV = 'KUKA_BC'


def kuka_trajectories_rows() -> list[tuple[str, str, str, str]]:
    """
    Return the rows of the KUKA diagnosis of trajectories A, B and C, each on the others.

    Each whole trajectory is diagnosed against config/model_kuka_kr300_axes123.yaml with the
    other two as ``--validate`` records (experiments not used for fitting). Rows: each fit's
    held-out NRMSE and its nominal -> extended NRMSE on the other two, and per parameter the
    three fits (standard error) with how many of B and C lie within 20 % of A. Empty unless
    the environment variable KUKA_BC names a directory holding B.mat and C.mat.
    """
    if not os.environ.get(KUKA_BC_ENV):
        return []
    bc = Path(os.environ[KUKA_BC_ENV])
    paths = {'A': KUKA, 'B': bc / 'B.mat', 'C': bc / 'C.mat'}
    if not all(p.is_file() for p in paths.values()):
        return []
    from frf_ident.app.diagnose import diagnose
    cfg = ROOT / 'config'
    est, rows, slopes = {}, [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for x, p in paths.items():
            others = [q for y, q in paths.items() if y != x]
            res = diagnose(p, cfg / 'model_kuka_kr300_axes123.yaml', Path(tmp) / x,
                           map_path=cfg / 'map_kuka_kr300.yaml', validate=others,
                           progress=lambda _m: None)
            rep = res.report()
            est[x] = estimates(rep)
            slopes[x] = _slopes_by_direction(res.recording, res.result.extended)
            m = rep['metrics']
            rows.append((f'KUKA trajectory {x} fitted: held-out NRMSE nominal -> extended',
                         f'{m["baseline"]["time_nrmse"]:.3f} -> {m["extended"]["time_nrmse"]:.3f}',
                         '; '.join(f'on {y}: {v["baseline"]["time_nrmse"]:.3f} -> '
                                   f'{v["extended"]["time_nrmse"]:.3f}'
                                   for y, v in zip([y for y in paths if y != x],
                                                   m['validation_records'])),
                         'other experiments, not used for fitting'))
    rows += _direction_rows(paths, slopes)
    keys = sorted(set().union(*(set(e) for e in est.values())))
    agree = named = 0
    for k in keys:
        cells = [f'{est[x][k][0]:.3g} ({est[x][k][1]:.2g})'
                 if k in est[x] and est[x][k][1] is not None else
                 (f'{est[x][k][0]:.3g}' if k in est[x] else '-') for x in 'ABC']
        near = [abs(est[x][k][0] / est['A'][k][0] - 1) <= 0.2 for x in 'BC'
                if k in est['A'] and k in est[x] and est['A'][k][0]]
        agree, named = agree + sum(near), named + len(near)
        rows.append((f'... {k[0]} {k[1]}: A / B / C (standard error)', ' / '.join(cells),
                     f'B, C within 20 % of A: {sum(near)}/{len(near)}', ''))
    rows.append(('... parameters of B and C within 20 % of A', f'{agree}/{named}', '', ''))
    return rows


def _slopes_by_direction(rec: Recording, robot: RobotParams
                         ) -> dict[str, tuple[float, float, float]]:
    """
    Return per axis the viscous slope forward and backward that a record's residual shows.

    The residual of the extended model ``robot`` on ``rec`` (its joints the model's axes, as
    diagnose returns it; low-passed, moving rows) regressed on an offset, v and |v|: forward
    slope b + c_v + c_|v|, backward b + c_v - c_|v| (b the model's viscous friction), and the
    block-robust standard error of c_|v|, half their difference.
    """
    from frf_ident.core.diagnosis.regressors import model_residual, moving
    from frf_ident.core.diagnosis.residual import lowpass
    from frf_ident.core.diagnosis.selection import block_standard_errors
    from frf_ident.core.diagnosis.thresholds import FC_HZ
    f, _, v, _ = model_residual(rec, robot)
    rows = moving(v, rec.velocity, rec.fs, FC_HZ)
    out = {}
    for i, ax in enumerate(robot.axes):
        g = {k: lowpass(x, rec.fs, FC_HZ)[:, None] for k, x in (
            ('offset', np.ones(v.shape[0])), ('v', v[:, i]), ('abs', np.abs(v[:, i])))}
        y = lowpass(f[:, i], rec.fs, FC_HZ)
        X = np.column_stack(list(g.values()))[rows[:, i]]
        c = np.linalg.lstsq(X, y[rows[:, i]], rcond=None)[0]
        se = block_standard_errors(g, list(g), y, rows[:, i], rec.fs)['abs'][0]
        b = ax.viscous_friction + c[1]
        out[ax.name] = (b + c[2], b - c[2], float(se))
    return out


def _direction_rows(paths: dict[str, Path], slopes: dict[str, dict]
                    ) -> list[tuple[str, str, str, str]]:
    """Return per axis the rows of :func:`_slopes_by_direction` of each trajectory."""
    return [(f'... {ax} viscous slope forward / backward (half-difference SE): '
             + ' / '.join(paths), ' ; '.join(
                 '{:.3g} / {:.3g} ({:.2g})'.format(*slopes[x][ax]) for x in paths),
             'residual of each extended model on offset, v, |v|',
             'a one-way half measures one of them') for ax in slopes[next(iter(paths))]]


def one_way_axes(report: dict[str, Any]) -> dict[str, str]:
    """Return {axis: 'forward' or 'backward'} of the axes a report found moving one way only."""
    return {r['axis']: 'forward' if r['forward_share'] > 0.5 else 'backward'
            for r in report.get('rejected', []) if 'forward_share' in r}


def estimates(report: dict[str, Any]) -> dict[tuple[str, str], tuple]:
    """
    Return {(axis, parameter): (value, standard error)} of a time-series report.

    One entry per scalar parameter and per gravity term (its amplitude); not the constant of
    an axis that moves one way only (load + the Coulomb friction of its direction, a different
    parameter in each half).
    """
    one_way = one_way_axes(report)
    out = {}
    for e in report['effects']:
        for key, val in e['parameters'].items():
            se = (e.get('standard_error') or {}).get(key)
            if key == 'gravity':
                for t, t_se in zip(val, se or [None] * len(val)):
                    out[e['axis'], 'gravity sin(' + ' + '.join(t['joints']) + ' + phi)'] = (
                        t['amplitude'], (t_se or {}).get('amplitude'))
            elif isinstance(val, (int, float)) and not (
                    key == 'gravity_torque' and e['axis'] in one_way):
                out[e['axis'], key] = (float(val), se)
    return out
