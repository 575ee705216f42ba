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
The global pose model: per-pose physical fits combined into one model of the workspace.

A ``frf-ident fit --physical`` campaign over the estimate folders of an ``identify --poses``
campaign fits every pose on its own (drive side and link inertia matrix, with Cramer-Rao
errors). :func:`fit_pose_model` then pools the drive side over the poses and fits the links'
inertial parameters of the robot's URDF to the link inertia matrices
(:mod:`frf_ident.core.fit.pose_model`; the regressor from the kinematics,
:meth:`frf_ident.io.kinematics.Kinematics.inertia_regressor`), so M(q) and with it every
axis' FRF follows at any pose. It is validated by leaving each pose out in turn: the model
fitted to the other poses predicts the held-out pose's own-axis FRFs, scored by the median
magnitude error against the measured FRF, beside two baselines of the same poses: the nearest
fitted pose's measured FRF and the pose-independent model (drive side and link inertia matrix
averaged over the poses). Gravity's stiffness on the link side is not in the per-pose fits
(eqs. 20-22), so the prediction leaves it out too.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass, replace
import json
from pathlib import Path
from typing import Any, Sequence

from frf_ident.app.frf_source import axis_channels, read_source
from frf_ident.core.fit.pose_model import (fit_inertial_parameters, InertialFit,
                                           median_db_error, pool_drive)
from frf_ident.core.jsonable import jsonable
from frf_ident.core.model.operating_point import robot_at_pose
from frf_ident.core.model.params import RobotParams
from frf_ident.core.progress import Progress, sink
from frf_ident.core.simulation.analytic import robot_frf
from frf_ident.errors import FrfIdentInputError
import numpy as np

__all__ = ['DRIVE', 'HeldOut', 'MIN_POSES', 'POSE_MODEL_FILES', 'PoseFit', 'PoseModelOutcome',
           'fit_pose_model', 'pose_model_after', 'read_pose_fit']

#: what :func:`fit_pose_model` writes into the campaign folder
POSE_MODEL_FILES = ('pose_model.json', 'pose_model.yaml', 'pose_model.urdf',
                    'pose_validation.csv')

#: the pose-independent (drive-side) parameters of an axis, pooled over the poses
DRIVE = ('motor_inertia', 'stiffness', 'damping', 'viscous_friction')

#: fewest poses for a pose model: leaving one out must leave two to fit
MIN_POSES = 3

#: the upper quantile of the line errors reported beside the median: the lines near the modes,
#: where a model that misses a pose's resonance shift shows (the median mostly sees the rest)
P95 = 0.95

#: a standard error of 0 (an exact fit) is taken as this share of its value, so one pose
#: cannot take all the weight
STD_FLOOR = 1e-9


@dataclass(frozen=True)
class PoseFit:
    """
    One pose's physical fit, as the pose model needs it.

    Attributes
    ----------
    name : str
        The fit's folder name.
    pose : ndarray, shape (n,)
        Joint positions [rad], in ``names`` order.
    names : list of str
        The axes.
    drive : ndarray, shape (4, n)
        :data:`DRIVE` per axis.
    drive_std : ndarray, shape (4, n)
        Their standard errors.
    inertia : ndarray, shape (n (n + 1) / 2,)
        M(q)'s upper triangle (``np.triu_indices``) [kg m^2]; NaN off the diagonal when the
        fit was per axis (no coupling).
    inertia_std : ndarray, shape (n (n + 1) / 2,)
        Their standard errors.
    freq_hz : ndarray, shape (n_freq,)
        The fitted lines.
    measured : ndarray of complex, shape (n, n_freq)
        Each axis' own measured FRF there.
    delay_s : float
        The delay the fit included [s].

    """

    name: str
    pose: np.ndarray
    names: list[str]
    drive: np.ndarray
    drive_std: np.ndarray
    inertia: np.ndarray
    inertia_std: np.ndarray
    freq_hz: np.ndarray
    measured: np.ndarray
    delay_s: float


@dataclass(frozen=True)
class HeldOut:
    """
    One pose predicted by the model fitted to the others.

    Attributes
    ----------
    name : str
        The held-out pose's fit folder.
    pose : ndarray
        Its joint positions [rad].
    model_db : float
        Median |dB| error of the pose model's own-axis FRFs against the measured ones.
    nearest_db : float
        The same for the nearest fitted pose's measured FRF.
    nearest : str
        Which pose that was.
    mean_db : float
        The same for the pose-independent model (parameters averaged over the fitted poses).
    model_p95_db, nearest_p95_db, mean_p95_db : float
        The 95th percentiles of the same errors (the lines near the modes).

    """

    name: str
    pose: np.ndarray
    model_db: float
    nearest_db: float
    nearest: str
    mean_db: float
    model_p95_db: float
    nearest_p95_db: float
    mean_p95_db: float


@dataclass(frozen=True)
class PoseModelOutcome:
    """
    The pose model fitted to all poses and its leave-one-out validation.

    Attributes
    ----------
    inertial : InertialFit
        The links' inertial parameters (pinocchio order, 10 per link).
    drive : ndarray, shape (4, n)
        Pooled :data:`DRIVE` per axis.
    drive_std : ndarray, shape (4, n)
        Their standard errors.
    validation : list of HeldOut
        One per pose.
    files : list of Path
        The files written.

    """

    inertial: InertialFit
    drive: np.ndarray
    drive_std: np.ndarray
    validation: list[HeldOut]
    files: list[Path]


def _floor(std: np.ndarray, value: np.ndarray) -> np.ndarray:
    return np.maximum(np.asarray(std, dtype=float), STD_FLOOR * np.abs(value) + 1e-300)


def read_pose_fit(folder: Path) -> PoseFit:
    """
    Read one pose's physical fit: its fit.json and the measured FRF it names.

    Parameters
    ----------
    folder : Path
        A fit output folder (``fit --physical`` of an estimate folder with a pose).

    Returns
    -------
    PoseFit
        The fit, its pose and the measured own-axis FRFs over the fitted band.

    Raises
    ------
    FrfIdentInputError
        No fit.json, not a physical fit, no pose, or its FRF is not readable.

    """
    p = Path(folder) / 'fit.json'
    try:
        doc = json.loads(p.read_text())
    except (OSError, ValueError) as err:
        raise FrfIdentInputError(f'{p}: not readable as fit.json ({err})') from err
    if doc.get('pose_rad') is None or not (doc.get('coupled') or doc.get('physical')):
        raise FrfIdentInputError(f'{p}: expected a physical fit (--physical) of an FRF '
                                 f'measured at a pose (pose_rad; bags of identify --poses)')
    if doc.get('coupled'):
        axes = doc['coupled']['axes']
        names = [a['axis'] for a in axes]
        coupling = np.asarray(doc['coupled']['link_coupling'], dtype=float)
        coupling_std = np.asarray(doc['coupled']['link_coupling_std'], dtype=float)
    else:
        axes = doc['physical']
        names = [a['axis'] for a in axes]
        coupling = coupling_std = np.full((len(names), len(names)), np.nan)
    n = len(names)
    drive = np.array([[a['parameters'][k] for a in axes] for k in DRIVE])
    drive_std = _floor(np.array([[a['std'][k] for a in axes] for k in DRIVE]), drive)
    m = coupling.copy()
    sd = coupling_std.copy()
    jo = np.array([a['parameters']['link_inertia'] for a in axes])
    m[np.diag_indices(n)] = jo
    sd[np.diag_indices(n)] = [a['std']['link_inertia'] for a in axes]
    iu = np.triu_indices(n)
    frf = read_source(doc['source'])
    lo, hi = doc['freq_hz']
    frf = frf.select((frf.freq_hz >= lo) & (frf.freq_hz <= hi))
    own = {j: (o, i) for j, o, i in axis_channels(frf)}
    if len(doc['pose_rad']) != n or any(a not in own for a in names):
        raise FrfIdentInputError(f'{p}: pose {doc["pose_rad"]} or the FRF {doc["source"]} '
                                 f'does not match the fitted axes {names}')
    return PoseFit(Path(folder).name, np.asarray(doc['pose_rad'], dtype=float), names, drive,
                   drive_std, m[iu], _floor(sd[iu], m[iu]), frf.freq_hz,
                   np.stack([frf.response[own[a]] for a in names]), _delay(doc))


def _delay(doc: dict) -> float:
    """Return a fit.json's model delay [s]: given, the coupled fit's, else the axes' mean."""
    if doc.get('delay_s') is not None:
        return float(doc['delay_s'])
    if doc.get('coupled') and doc['coupled'].get('delay_s') is not None:
        return float(doc['coupled']['delay_s'])
    return float(np.mean([a.get('delay_s') or 0.0 for a in doc['physical']]))


def _with_drive(base: RobotParams, names: Sequence[str], drive: np.ndarray) -> RobotParams:
    axes = [replace(a, **{k: float(max(drive[r, i], 0.0) if k == 'viscous_friction'
                                   else drive[r, i]) for r, k in enumerate(DRIVE)})
            for i, a in enumerate(base.axes)]
    return replace(base, axes=axes)


def _predict(robot: RobotParams, inertia: np.ndarray, fit: PoseFit) -> np.ndarray:
    """Own-axis FRFs of ``robot`` with link inertia matrix ``inertia`` on ``fit``'s lines."""
    n = len(fit.names)
    at = robot_at_pose(robot, inertia, np.zeros(n), np.zeros((n, n)))
    p = robot_frf(at, fit.freq_hz) * np.exp(-2j * np.pi * fit.freq_hz * fit.delay_s)
    return np.stack([p[i, i] for i in range(n)])


def _full(tri: np.ndarray, n: int) -> np.ndarray:
    m = np.zeros((n, n))
    iu = np.triu_indices(n)
    m[iu] = np.nan_to_num(tri)
    return m + np.triu(m, 1).T


def _fit(kin, fits: Sequence[PoseFit]):
    reg = np.stack([kin.inertia_regressor(f.pose) for f in fits])
    inertial = fit_inertial_parameters(reg, np.stack([f.inertia for f in fits]),
                                       np.stack([f.inertia_std for f in fits]),
                                       kin.parameters())
    drive, drive_std = pool_drive(np.stack([f.drive for f in fits]),
                                  np.stack([f.drive_std for f in fits]))
    return inertial, drive, drive_std


def _held_out(kin, base: RobotParams, fits: Sequence[PoseFit], h: int) -> HeldOut:
    train = [f for k, f in enumerate(fits) if k != h]
    test = fits[h]
    n = len(test.names)
    inertial, drive, _ = _fit(kin, train)
    robot = _with_drive(base, test.names, drive)
    model = _predict(robot, _full(kin.inertia_regressor(test.pose) @ inertial.value, n), test)
    tri, _ = pool_drive(np.stack([np.nan_to_num(f.inertia) for f in train]),
                        np.stack([f.inertia_std for f in train]))
    mean = _predict(robot, _full(tri, n), test)
    near = min(train, key=lambda f: float(np.linalg.norm(f.pose - test.pose)))
    interp = np.stack([np.interp(test.freq_hz, near.freq_hz, r.real)
                       + 1j * np.interp(test.freq_hz, near.freq_hz, r.imag)
                       for r in near.measured])
    err = {q: [median_db_error(p, test.measured, q) for p in (model, interp, mean)]
           for q in (0.5, P95)}
    return HeldOut(test.name, test.pose, err[0.5][0], err[0.5][1], near.name, err[0.5][2],
                   *err[P95])


def fit_pose_model(folders: Sequence[Path], out: Path, *, urdf: str | Path | None = None,
                   model: str | Path | None = None,
                   progress: Progress | None = None) -> PoseModelOutcome:
    """
    Fit the global pose model to per-pose physical fits, validate it, write it.

    Parameters
    ----------
    folders : sequence of Path
        Fit output folders, one per pose (:func:`read_pose_fit`), at least :data:`MIN_POSES`.
    out : Path
        Where :data:`POSE_MODEL_FILES` go (the fit campaign's folder).
    urdf : str or Path, optional
        The robot's URDF (prior inertial parameters and kinematics); default the demo's.
    model : str or Path, optional
        Model file whose other keys (limits, controller) pose_model.yaml keeps.
    progress : callable, optional
        Called with a few lines.

    Returns
    -------
    PoseModelOutcome
        The model fitted to all poses and the leave-one-out validation.

    Raises
    ------
    FrfIdentInputError
        Fewer than :data:`MIN_POSES` fits, a fit that is not physical or has no pose, fits of
        different axes, a URDF that does not match them, or a fitted link mass <= 0.

    """
    from frf_ident.io.kinematics import load_kinematics
    from frf_ident.io.model_file import load_model, save_model
    progress = sink(progress)
    fits = [read_pose_fit(Path(f)) for f in folders]
    if len(fits) < MIN_POSES:
        raise FrfIdentInputError(f'a pose model needs physical fits at >= {MIN_POSES} poses; '
                                 f'got {len(fits)}')
    names = fits[0].names
    if any(f.names != names for f in fits):
        raise FrfIdentInputError(f'pose model: the fits are of different axes '
                                 f'({sorted({tuple(f.names) for f in fits})})')
    _, base, ctrl = load_model(model)
    if base.joint_names != names:
        raise FrfIdentInputError(f'{model or "the default model"}: axes {base.joint_names}; '
                                 f'the fits are of {names}')
    kin = load_kinematics(urdf, names)
    inertial, drive, drive_std = _fit(kin, fits)
    masses = inertial.value[::10]
    if np.any(masses <= 0):
        raise FrfIdentInputError(f'pose model: fitted link masses {masses.round(3).tolist()} '
                                 f'kg; a mass <= 0 means the poses do not determine it')
    progress(f'pose model: {len(fits)} poses, {inertial.rank} of {inertial.value.size} inertial '
             f'parameter combinations determined by M(q); link inertia residual '
             f'{inertial.rms_before:.3g} (URDF) -> {inertial.rms_after:.3g} (fitted) standard '
             f'errors RMS')
    for i, a in enumerate(names):
        progress(f'  {a} pooled: ' + ', '.join(
            f'{k} {drive[r, i]:.5g} +- {drive_std[r, i]:.2g}' for r, k in enumerate(DRIVE)))
    validation = [_held_out(kin, base, fits, h) for h in range(len(fits))]
    med = {k: float(np.median([getattr(v, k) for v in validation]))
           for k in ('model_db', 'nearest_db', 'mean_db', 'model_p95_db', 'nearest_p95_db',
                     'mean_p95_db')}
    worst = max(validation, key=lambda v: v.model_db)
    progress(f'  leave one pose out, median over the held-out poses of their median (95th '
             f'percentile) |dB| error: pose model {med["model_db"]:.2f} '
             f'({med["model_p95_db"]:.2f}) dB, worst pose {worst.model_db:.2f} dB '
             f'({worst.name}); nearest pose {med["nearest_db"]:.2f} '
             f'({med["nearest_p95_db"]:.2f}) dB; pose-independent mean model '
             f'{med["mean_db"]:.2f} ({med["mean_p95_db"]:.2f}) dB')
    fitted = kin.with_parameters(inertial.value)
    files = [out / n for n in POSE_MODEL_FILES]
    fitted.write_urdf(files[2], comment=f'link inertial parameters fitted by frf-ident fit to '
                                        f'{len(fits)} poses; prior {kin.source}')
    home = fitted.at(np.zeros(len(names)))
    robot = robot_at_pose(_with_drive(base, names, drive), home.inertia, home.gravity,
                          home.gravity_gradient)
    save_model(files[1], robot, ctrl, extra={
        'description': f'drive side pooled over {len(fits)} poses and link side at the home '
                       f'pose (q = 0) of {files[2].name} by frf-ident fit; for other poses '
                       f'use identify --poses --urdf {files[2].name}'})
    with open(files[3], 'w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(['held_out'] + [f'pose_rad_{a}' for a in names]
                   + ['model_db', 'nearest_db', 'nearest', 'mean_db', 'model_p95_db',
                      'nearest_p95_db', 'mean_p95_db'])
        for v in validation:
            w.writerow([v.name] + [round(float(q), 6) for q in v.pose]
                       + [round(v.model_db, 4), round(v.nearest_db, 4), v.nearest,
                          round(v.mean_db, 4), round(v.model_p95_db, 4),
                          round(v.nearest_p95_db, 4), round(v.mean_p95_db, 4)])
    doc: dict[str, Any] = {
        'poses': [{'fit': f.name, 'pose_rad': f.pose} for f in fits], 'urdf': kin.source,
        'joint_order': list(fitted.model.names[1:]),
        'inertial_parameters': {'value': inertial.value, 'prior': inertial.prior,
                                'std': inertial.std, 'rank': inertial.rank,
                                'n_obs': inertial.n_obs, 'rms_before': inertial.rms_before,
                                'rms_after': inertial.rms_after},
        'drive': {a: {k: {'value': drive[r, i], 'std': drive_std[r, i]}
                      for r, k in enumerate(DRIVE)} for i, a in enumerate(names)},
        'validation': {'median_db': med, 'held_out': [vars(v) for v in validation]},
        'files': list(POSE_MODEL_FILES)}
    files[0].write_text(json.dumps(jsonable(doc), indent=1))
    progress(f'pose model: wrote {", ".join(POSE_MODEL_FILES)} to {out}')
    return PoseModelOutcome(inertial, drive, drive_std, validation, files)


def pose_model_after(res: Any, *, urdf: str | Path | None = None,
                     model: str | Path | None = None,
                     progress: Progress | None = None) -> list[Path]:
    """
    Fit the pose model after a ``fit --physical`` campaign, when its FRFs carry poses.

    Parameters
    ----------
    res : CampaignResult
        The fit campaign; its rows that succeeded with ``pose_rad_*`` columns are used.
    urdf, model : str or Path, optional
        As :func:`fit_pose_model`.
    progress : callable, optional
        Called with a few lines.

    Returns
    -------
    list of Path
        The files written; none (and a line saying why) with fewer than :data:`MIN_POSES`
        posed fits.

    """
    progress = sink(progress)
    rows = [r for r in res.rows if r.ok and any(k.startswith('pose_rad_') for k in r.columns)]
    if len(rows) < MIN_POSES:
        progress(f'no pose model: {len(rows)} physical fits of FRFs measured at a pose '
                 f'(needs >= {MIN_POSES})')
        return []
    return fit_pose_model([res.out / r.out for r in rows], res.out, urdf=urdf, model=model,
                          progress=progress).files
