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
Run the ``frf-ident diagnose`` command: diagnose a record against a nominal model.

`frf-ident diagnose DATA --model M.yaml --out DIR [--validate OTHER ...]`
(docs/CONTRACT.md §7): what the nominal simulation gets wrong, which effect causes it, what
stays unexplained, the extended model and its gain on held-out data and on other records.

DATA (and every OTHER) is a bag (identification experiments -> FRF and simulation evidence, or
any bag with /joint_states -> time-series evidence), or a CSV/MAT table read through
:func:`frf_ident.io.importer.import_table` with ``--map``: one route for every format, so a bag,
a CSV and a MAT file of the same data give the same report. Data-set specifics live in the
map and the model file, never in this code.
Writes DIR/report.json, DIR/extended_model.yaml, DIR/report.html and its PNG plots. The
diagnosis itself is :func:`frf_ident.core.diagnosis.diagnose`; this module loads, matches the
data to the model, reads the URDF's kinematics and writes the files.
"""
from __future__ import annotations

from dataclasses import replace
import json
from pathlib import Path
from typing import Any, Sequence, TYPE_CHECKING

from frf_ident.app.outdir import clear_outputs
from frf_ident.app.threads import one_blas_thread
from frf_ident.core.model.params import RobotParams, UrdfSource
from frf_ident.core.progress import Progress, sink
from frf_ident.core.recording import Recording
from frf_ident.errors import FrfIdentInputError

if TYPE_CHECKING:   # the diagnosis is loaded when a diagnosis runs, not with the command table
    from frf_ident.core.diagnosis.pipeline import Diagnosis
    from frf_ident.io.mjcf.candidate import MjcfModels

__all__ = ['OUTPUT_FILES', 'diagnose', 'diagnose_columns', 'load_data']

#: the files :func:`diagnose` writes into its output directory (report.html's figures: an
#: experiments diagnosis draws bode.png and residual.png, a time-series one residual.png)
OUTPUT_FILES = ('report.json', 'extended_model.yaml', 'extended_model.xml', 'report.html',
                'bode.png', 'residual.png', 'residual_spectrum.png')


def load_data(path: Path, map_path: Path | None = None) -> Recording:
    """
    Load DATA as a Recording: a bag directory or .mcap directly, a CSV/MAT table with a map.

    Parameters
    ----------
    path
        Bag directory, .mcap file, or .csv/.mat table.
    map_path
        Import map (frf_ident.io.importer) for tables.

    Returns
    -------
    The recording.

    """
    path = Path(path)
    if not path.exists():
        raise FrfIdentInputError(f'{path}: no such bag or file')
    if path.is_dir() or path.suffix == '.mcap':
        from frf_ident.bag import read_recording

        # gaps a recorder lost are kept as missing rows (the reader's default, gaps='mark'):
        # the diagnosis leaves them out
        rec, _ = read_recording(path)
        return rec
    if map_path is None:
        raise FrfIdentInputError(f'{path}: a {path.suffix or "table"} file needs --map MAP.yaml '
                                 f'(column/variable names and units; see config/map_*.yaml); '
                                 f'expected a bag directory or .mcap otherwise')
    from frf_ident.io.importer import import_table
    return import_table(path, map_path)


def _match_axes(rec: Recording, robot, model_path: Path, progress, data: Path) -> Recording:
    if robot.joint_names == list(rec.joint_names):
        return rec
    if set(robot.joint_names) <= set(rec.joint_names):
        return rec.select_joints(robot.joint_names)
    if robot.n_axes <= len(rec.joint_names):
        progress(f'note: {data}: model axes {robot.joint_names} taken in order for the data '
                 f'joints {rec.joint_names[:robot.n_axes]}')
        return rec.select_joints(rec.joint_names[:robot.n_axes])
    raise FrfIdentInputError(f'--model {model_path}: axes {robot.joint_names} do not match the '
                             f'data joints {rec.joint_names}')


@one_blas_thread()
def diagnose(data: Path, model_path: Path, out: Path, *, map_path: Path | None = None,
             validate: Sequence[Path] = (), urdf: Path | None = None,
             progress: Progress | None = None, jobs: int | None = None,
             fd_fit: bool = True) -> Diagnosis:
    """
    Run the diagnosis and write DIR/report.json, extended_model.yaml, report.html.

    Parameters
    ----------
    data
        The record to fit on (bag, or CSV/MAT with ``map_path``).
    model_path
        Nominal model file (docs/CONTRACT.md §5).
    out
        Output directory; its :data:`OUTPUT_FILES` of an earlier run are removed before
        the new ones are written.
    map_path
        Import map for CSV/MAT records (DATA and every OTHER).
    validate
        Other records of the same robot: baseline and extended metrics on each; a gravity
        or ripple term that does not generalise to them is dropped.
    urdf
        The robot's URDF: the time-series route fits the gravity its kinematics imply
        (:mod:`frf_ident.core.diagnosis.crosscheck.kinematic_gravity`; pinocchio reads it)
        and offers each axis shares of its inertia and Coriolis torque, a pose-dependent
        inertia, and of its gravity (``urdf_inertia``, ``urdf_gravity``, written with the
        URDF's path as the model's ``urdf``).
    jobs
        Processes that simulate independent candidate models at once (experiments route);
        None: :data:`frf_ident.core.diagnosis.thresholds.SIM_JOBS`; 1: one after the other
        (the same result).
    fd_fit
        Experiments route: stage 0, the frequency-domain physical fit that names a linear
        parameter mismatch before the simulation search (default); False: the path without
        it (for the before/after benchmark).
    progress
        Called with one line per step for the lines people read (what was read, the route,
        the effects found with their values, where the files went); None: silent. The
        diagnosis' own stages log to ``logging.getLogger('frf_ident.core.diagnosis.*')``: a few
        INFO lines per stage, the search trace at DEBUG level.

    Returns
    -------
    Diagnosis
        The diagnosis (:class:`frf_ident.core.diagnosis.Diagnosis`): the result, the
        cross-checks and the diagnosed record, its joints matched to the model's axes.

    """
    from frf_ident.core.diagnosis import diagnose as diagnose_record
    from frf_ident.core.diagnosis.thresholds import SIM_JOBS
    from frf_ident.io.model_file import load_model
    progress = sink(progress)
    model, robot, ctrl = load_model(model_path)
    rec, others = load_records(data, validate, robot, model_path, map_path, progress)
    robot = at_record_rate(robot, rec, model_path, data, progress)
    gravity = None
    if urdf is not None:
        from frf_ident.core.diagnosis import GravityBasis
        from frf_ident.io.kinematics import load_kinematics
        kin = load_kinematics(urdf, robot.joint_names)
        gravity = GravityBasis(str(urdf), kin.gravity_basis)
        # its inertia, Coriolis and gravity torques: each axis' candidate shares of them
        robot = replace(robot, urdf=UrdfSource(str(Path(urdf).resolve()), kin))
    mjcf = mjcf_models(robot)
    diag = diagnose_record(rec, robot, ctrl, others=others, gravity=gravity,
                           jobs=SIM_JOBS if jobs is None else jobs, fd_fit=fd_fit,
                           name=str(data), progress=progress, simulator=mjcf)
    write_diagnosis(out, diag, model, ctrl, data, mjcf=mjcf, progress=progress)
    return diag


def mjcf_models(robot: RobotParams) -> MjcfModels | None:
    """Return the MuJoCo simulator of a model naming an MJCF (None for a model of ours)."""
    if robot.mjcf is None:
        return None
    from frf_ident.io.mjcf.candidate import MjcfModels
    return MjcfModels(robot)


def load_records(data: Path, validate: Sequence[Path], robot: RobotParams, model_path: Path,
                 map_path: Path | None, progress: Progress
                 ) -> tuple[Recording, list[tuple[str, Recording]]]:
    """
    Load DATA and every OTHER, their joints matched to the model's axes; name their gaps.

    Raises
    ------
    FrfIdentInputError
        An OTHER record names other joints than DATA (another robot?).

    """
    rec = _match_axes(load_data(data, map_path), robot, model_path, progress, data)
    others = [(str(p), _match_axes(load_data(p, map_path), robot, model_path, progress, p))
              for p in validate]
    for p, o in others:
        # another record of the same robot names the same joints; matched in order, a
        # record of another robot would be judged with this robot's model and look like
        # evidence
        if list(o.joint_names) != list(rec.joint_names):
            raise FrfIdentInputError(
                f'--validate {p}: joints {list(o.joint_names)} are not the joints '
                f'{list(rec.joint_names)} of {data} (another robot? name them alike in the '
                f'import map)')
    for p, r in [(str(data), rec)] + others:
        gaps = r.gaps
        if gaps:
            progress(f'{p}: {len(gaps)} gap(s) in the joint states '
                     f'({sum(b - a for a, b in gaps):.3f} s, first at {gaps[0][0]:.3f} s) left '
                     f'out of fit and validation')
    return rec, others


def at_record_rate(robot: RobotParams, rec: Recording, model_path: Path, data: Path,
                   progress: Progress) -> RobotParams:
    """Return the model at the record's sample rate, saying so where the model file differs."""
    if abs(robot.sample_rate - rec.fs) <= 1e-6 * rec.fs:
        return robot
    fs = float(f'{rec.fs:.9g}')     # 999.9999999952 from float stamps is 1000
    progress(f'{model_path}: sample_rate {robot.sample_rate:g} Hz, the record {data} is '
             f'sampled at {fs:g} Hz: the diagnosis and extended_model.yaml use {fs:g} Hz')
    return replace(robot, sample_rate=fs)


def write_diagnosis(out: Path, diag: Diagnosis, model: dict[str, Any], ctrl: Any,
                    data: Path, *, mjcf: Any = None, progress: Progress | None = None) -> None:
    """
    Write extended_model.yaml, report.json and report.html (its figures) into ``out``.

    With ``mjcf`` (the :class:`~frf_ident.io.mjcf.candidate.MjcfModels` of a model naming an
    MJCF) also extended_model.xml, its gain measured by MuJoCo (report.json ``mjcf``).
    """
    from frf_ident.io.model_file import save_model
    from frf_ident.report.diagnosis_page import write_diagnosis_report
    out.mkdir(parents=True, exist_ok=True)
    clear_outputs(out, OUTPUT_FILES)
    res = diag.result
    found = ', '.join(e.name for e in res.effects) or 'none'
    save_model(out / 'extended_model.yaml', res.extended, ctrl,
               extra={'description': f'{model.get("description", "nominal model")} + diagnosed '
                                     f'effects: {found}'})
    report = diag.report()
    written = None
    if mjcf is not None:
        from frf_ident.core.diagnosis.pipeline import strict_json
        from frf_ident.io.mjcf.diagnosed import write_extended
        written = write_extended(mjcf, diag, ctrl, out)
        report['mjcf'] = strict_json(written.to_dict())
        for line in written.lines():
            sink(progress)(line)
    (out / 'report.json').write_text(json.dumps(report, indent=1))
    write_diagnosis_report(out, diag, data, mjcf=written)


def diagnose_columns(data: Path, out: Path, progress: Progress | None, *,
                     model_path: Path, **options) -> dict[str, Any]:
    """
    Diagnose one record of a campaign (:func:`diagnose`) and return its summary columns.

    The task :func:`frf_ident.app.campaign.run_campaign` maps over the records: the report
    stays in ``out``, the worker returns only these few values.

    Parameters
    ----------
    data : Path
        The record (bag, or CSV/MAT with ``map_path`` in ``options``).
    out : Path
        Its output folder.
    progress : callable
        Called with one line per step (the record's log).
    model_path : Path
        Nominal model file.
    **options
        Further keyword arguments of :func:`diagnose` (``map_path``, ``validate``, ``jobs``).

    Returns
    -------
    dict
        ``mode``, ``effects`` (names and axes, most likely first), ``unexplained`` (axes),
        and the held-out ``baseline_frf_error_db``, ``extended_frf_error_db``,
        ``baseline_time_nrmse``, ``extended_time_nrmse``.

    """
    res = diagnose(data, model_path, out, progress=progress, **options).result
    m = res.metrics
    return {'mode': res.mode,
            'effects': ' '.join(f'{e.name}@{e.axis}' for e in res.effects) or 'none',
            # an axis once, also with several resonances above the analysis band
            'unexplained': ' '.join(dict.fromkeys(u.axis for u in res.unexplained)) or 'none',
            'baseline_frf_error_db': _finite(m.baseline.frf_error_db),
            'extended_frf_error_db': _finite(m.extended.frf_error_db),
            'baseline_time_nrmse': _finite(m.baseline.time_nrmse),
            'extended_time_nrmse': _finite(m.extended.time_nrmse)}


def _finite(x: float) -> float | None:
    """Return a summary column: None where there was no line to compare (NaN)."""
    return None if x != x else x
