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
Identification on a plant: load the model and plant, run the experiments, record a bag.

:func:`run_identify` runs at the model's one operating point; :func:`run_identify_poses` runs
the same procedures at each pose of a poses file on the model's simulation linearised there
(link inertia, coupling and gravity from the robot's URDF), one bag per pose or all poses in
one bag (each pose's record after the other on one clock, every segment descriptor carrying
its ``pose_index`` and ``pose_rad``).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from frf_ident.app.console import LiveLine
from frf_ident.app.outdir import check_out
from frf_ident.core.progress import Progress, sink
from frf_ident.errors import FrfIdentInputError

__all__ = ['ONE_BAG', 'POSE_INDEX', 'concatenate_poses', 'run_identify',
           'run_identify_poses']

#: the file :func:`run_identify_poses` writes beside its bags: pose, bag and link side of each
POSE_INDEX = 'poses.json'

#: name of the one bag of ``run_identify_poses(..., one_bag=True)`` in its folder
ONE_BAG = 'all_poses'

#: pause between two poses' records in the one bag [s]: where the robot would move to the
#: next pose (no data is recorded then; positions stay relative to each pose)
POSE_GAP_S = 1.0

#: share of a torque limit the gravity load of a pose may take: the rest is the experiment's
#: (the plans are checked at 0.95 of the limit with the gravity load included, as identify does)
POSE_GRAVITY_SHARE = 0.95


def run_identify(model_path: str | Path | None, plant_spec: str | None, config: Any,
                 out: str | Path, *, progress: Progress | None = None,
                 foxglove_port: int | None = None):
    """
    Run the identification experiments in closed loop and write the bag.

    Parameters
    ----------
    model_path : str or Path or None
        Model file, or None for the embedded 3-axis model.
    plant_spec : str or None
        Plant plug-in ``'package.module:Class'``, or None for the model's simulation.
    config : IdentificationConfig
        The procedures (:class:`~frf_ident.core.simulation.runner.IdentificationConfig`).
    out : str or Path
        Bag directory to create; an existing path, or one that cannot be created, is
        refused before anything runs (:func:`~frf_ident.app.outdir.check_out`).
    progress : callable, optional
        Called with one line per step; default None: silent. With it, the multisine's live
        estimate after every whole MIMO period is one updating status line
        (:class:`frf_ident.app.live_view.LiveView`).
    foxglove_port : int, optional
        Serve the live estimate on a Foxglove WebSocket at ws://127.0.0.1:PORT (0: a free
        port) during the run and, after it, until Ctrl-C; None: no server.

    Returns
    -------
    Recording
        The recorded run (also written to ``out``).

    Raises
    ------
    FrfIdentInputError
        ``out`` exists, the model file is invalid (:class:`~frf_ident.errors.ModelFileError`)
        or the plant plug-in cannot be loaded; a plan beyond the position bound or predicted
        on the model to reach 0.95 of a torque limit (:class:`~frf_ident.errors.SafetyError`,
        nothing run).

    """
    from frf_ident.bag import write_recording
    from frf_ident.core.simulation.runner import run_identification
    from frf_ident.io.model_file import dry_run_plant, load_model, load_plant
    out = check_out(out, outputs=None, overwrite=False)
    model, robot, ctrl = load_model(model_path)
    plant = load_plant(plant_spec, model)
    view = None
    if config.multisine is not None and (progress is not None or foxglove_port is not None):
        from frf_ident.app.live_view import LiveView
        view = LiveView(list(robot.joint_names), ctrl.torque_limit, config.target,
                        foxglove_port, LiveLine(sink(progress)))
        if view.server is not None:
            sink(progress)(f'live estimate on the Foxglove WebSocket {view.server.url} '
                           f'(the app: Open connection; config/foxglove_layout.json)')
    say = sink(progress)
    if view is not None:
        def say(line: str, _say=say) -> None:     # a stage line closes the status line first
            view.end()
            _say(line)
    try:
        rec = run_identification(plant, ctrl, config, progress=say, on_estimate=view,
                                 meta={'model': model, 'plant': plant_spec or 'model'},
                                 model=robot, dry_run=dry_run_plant(model, robot))
    finally:
        if view is not None:
            view.end()
    write_recording(rec, out)
    if view is not None and view.server is not None:
        sink(progress)(f'bag written; the final estimate stays on {view.server.url} until '
                       f'Ctrl-C')
        view.serve_until_interrupted()
    return rec


def _check_poses(kin, robot, poses, bound_rad: float, path) -> list:
    """Evaluate every pose; refuse one outside the joint limits or that gravity overloads."""
    import numpy as np
    sides = []
    limit = robot.torque_limits()
    for k, q in enumerate(poses):
        q = np.asarray(q)
        out = (q - bound_rad < kin.lower) | (q + bound_rad > kin.upper)
        if out.any():
            j = int(np.argmax(out))
            raise FrfIdentInputError(
                f'{path}: poses[{k}] {kin.joint_names[j]} = {q[j]:.3f} rad: with the travel of '
                f'+-{bound_rad:.3f} rad it leaves the URDF limits [{kin.lower[j]:g}, '
                f'{kin.upper[j]:g}] rad')
        side = kin.at(q)
        over = np.abs(side.gravity) >= POSE_GRAVITY_SHARE * limit
        if over.any():
            j = int(np.argmax(over))
            raise FrfIdentInputError(
                f'{path}: poses[{k}] needs {side.gravity[j]:.0f} N m on {kin.joint_names[j]} '
                f'to hold against gravity, beyond {POSE_GRAVITY_SHARE:g} of its limit '
                f'{limit[j]:g} N m')
        sides.append(side)
    return sides


def concatenate_poses(recs: list, gap_s: float = POSE_GAP_S):
    """
    Put the records of several poses after each other on one clock: one recording.

    Each record is shifted by a whole number of samples, so its samples and segment bounds
    keep their spacing (an estimate over a pose's time range sees that pose's record
    unchanged). ``gap_s`` [s] lies between two records. The segments keep their
    ``pose_index`` and ``pose_rad``; the recording meta of the first record is kept, its
    summary's ``pose_rad`` replaced by ``poses``: per pose its index, pose and time range.

    Parameters
    ----------
    recs : list of Recording
        One per pose, same joints and sample time.
    gap_s : float, optional
        Time between two records [s].

    Returns
    -------
    Recording
        The records one after the other.

    """
    import numpy as np

    from frf_ident.core.recording import Recording, Segment
    dt = recs[0].dt
    parts, segs, spans = [], [], []
    t_next = float(recs[0].t[0])
    for k, rec in enumerate(recs):
        shift = round((t_next - float(rec.t[0])) / dt) * dt
        t = rec.t + shift
        parts.append((t, rec))
        segs += [Segment(sg.t_start + shift, sg.t_end + shift, dict(sg.info))
                 for sg in rec.segments]
        spans.append({'pose_index': k, 'pose_rad': rec.summary.get('pose_rad'),
                      't_start': float(t[0]), 't_end': float(t[-1] + dt)})
        t_next = float(t[-1]) + dt + gap_s

    def cat(name):
        vals = [getattr(r, name) for _, r in parts]
        return None if any(v is None for v in vals) else np.concatenate(vals)
    meta = dict(recs[0].meta)
    meta['summary'] = {k: v for k, v in meta['summary'].items() if k != 'pose_rad'}
    meta['summary']['poses'] = spans
    meta.pop('pose_rad', None)
    return Recording(np.concatenate([t for t, _ in parts]), list(recs[0].joint_names),
                     cat('position'), cat('velocity'), cat('effort'), cat('reference'),
                     cat('excitation'), segs, meta)


def run_identify_poses(model_path: str | Path | None, poses_path: str | Path, config: Any,
                       out: str | Path, *, urdf: str | Path | None = None,
                       one_bag: bool = False,
                       progress: Progress | None = None) -> list[dict]:
    """
    Run the identification experiments at every pose of a poses file, one bag per pose.

    At each pose the model's simulation takes the link side of that pose from the URDF
    (:func:`~frf_ident.core.model.operating_point.robot_at_pose`: inertia matrix, gravity
    load and gradient), so resonances move with the pose as on the robot. Positions in a
    bag are relative to its pose; every segment descriptor and the bag's metadata carry
    the pose (``pose_rad``). Every pose is checked before anything runs, and every pose
    runs before a bag is written.

    Parameters
    ----------
    model_path : str or Path or None
        Model file (drive side, controller), or None for the embedded 3-axis model.
    poses_path : str or Path
        Poses file (:func:`~frf_ident.io.kinematics.read_poses`).
    config : IdentificationConfig
        The procedures, the same at every pose.
    out : str or Path
        Folder to create: ``pose_00``, ``pose_01``... bags and :data:`POSE_INDEX`.
    urdf : str or Path, optional
        The robot's URDF; default the poses file's ``urdf``, else the demo robot's.
    one_bag : bool, optional
        Write all poses into one bag, :data:`ONE_BAG` (:func:`concatenate_poses`), instead
        of one per pose; ``frf-ident estimate`` of it gives the per-pose FRFs.
    progress : callable, optional
        Called with one line per pose.

    Returns
    -------
    list of dict
        Per pose: ``bag``, ``pose_rad``, ``inertia`` [kg m^2], ``gravity`` [N m] (as in
        :data:`POSE_INDEX`); with ``one_bag`` also ``t_range`` [s], its span in the bag.

    Raises
    ------
    FrfIdentInputError
        ``out`` exists, the model, poses file or URDF is invalid, a pose (with the
        multisine's travel) leaves the URDF's position limits or its gravity load reaches
        0.95 of a torque limit, or a plan is refused (:class:`~frf_ident.errors.SafetyError`).

    """
    import json

    import numpy as np

    from frf_ident.bag import write_recording
    from frf_ident.core.model.operating_point import robot_at_pose
    from frf_ident.core.model.schema import robot_to_dict
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    from frf_ident.core.simulation.runner import run_identification
    from frf_ident.io.kinematics import load_kinematics, read_poses
    from frf_ident.io.model_file import load_model
    progress = sink(progress)
    out = check_out(out, outputs=None, overwrite=False)
    _, robot, ctrl = load_model(model_path)
    poses, file_urdf = read_poses(poses_path, robot.n_axes)
    kin = load_kinematics(urdf or file_urdf, robot.joint_names)
    ms = config.multisine
    bound = np.deg2rad(ms.position_bound_deg) if ms is not None else 0.0
    sides = _check_poses(kin, robot, poses, bound, poses_path)
    runs = []
    for k, side in enumerate(sides):
        # every pose runs before any bag is written: a plan refused at a later pose leaves
        # nothing behind (a pose's record is a few MB)
        pose = robot_at_pose(robot, side.inertia, side.gravity, side.gravity_gradient)
        q = [round(float(v), 9) for v in side.q]
        progress(f'pose {k + 1}/{len(sides)} q = {np.round(side.q, 3).tolist()} rad: link '
                 f'inertia diag {np.round(np.diag(side.inertia), 1).tolist()} kg m^2, gravity '
                 f'{np.round(side.gravity, 1).tolist()} N m')
        rec = run_identification(FlexibleJointPlant(pose), ctrl.copy(), config,
                                 meta={'model': robot_to_dict(pose, ctrl), 'plant': 'model',
                                       'pose_rad': q, 'urdf': kin.source}, model=pose)
        for s in rec.segments:
            s.info['pose_rad'] = q
            s.info['pose_index'] = k
        rec.meta['summary']['pose_rad'] = q      # estimate's summary.json carries it on
        runs.append((q, side, rec))
    out.mkdir(parents=True)
    index = [{'bag': f'pose_{k:02d}', 'pose_rad': q, 'inertia': side.inertia.round(6).tolist(),
              'gravity': side.gravity.round(6).tolist()} for k, (q, side, _) in enumerate(runs)]
    if one_bag:
        rec = concatenate_poses([r for _, _, r in runs])
        write_recording(rec, out / ONE_BAG)
        for entry, span in zip(index, rec.meta['summary']['poses']):
            entry.update(bag=ONE_BAG, t_range=[span['t_start'], span['t_end']])
    else:
        for entry, (_, _, rec) in zip(index, runs):
            write_recording(rec, out / entry['bag'])
    (out / POSE_INDEX).write_text(json.dumps({'joints': kin.joint_names, 'urdf': kin.source,
                                              'poses': index}, indent=1))
    progress(f'{len(index)} poses in {"one bag" if one_bag else f"{len(index)} bags"} and '
             f'{POSE_INDEX} in {out}')
    return index
