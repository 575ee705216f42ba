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
Writes DIR/report.json, DIR/extended_model.yaml, DIR/report.html and its PNG plots.
"""
from __future__ import annotations

from dataclasses import replace
import json
from pathlib import Path
from typing import Any, Sequence

from frf_ident.app.outdir import clear_outputs
from frf_ident.app.threads import one_blas_thread
from frf_ident.core.progress import Progress, sink
from frf_ident.core.recording import Recording
from frf_ident.errors import FrfIdentInputError

__all__ = ['OUTPUT_FILES', 'diagnose', 'diagnose_columns', 'has_experiments', 'load_data']

#: the files :func:`diagnose` writes into its output directory (report.html's figures: an
#: experiments diagnosis draws bode.png and residual.png, a time-series one residual.png)
OUTPUT_FILES = ('report.json', 'extended_model.yaml', 'report.html', 'bode.png',
                'residual.png', 'residual_spectrum.png')


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


def has_experiments(rec: Recording) -> bool:
    """
    Return whether the record holds identification experiments.

    Parameters
    ----------
    rec : Recording
        The record to inspect.

    Returns
    -------
    bool
        True when it has a reference column and at least one multisine or chirp segment (the
        experiments route of the diagnosis), else False (time-series route).

    """
    return rec.reference is not None and any(
        s.info.get('design') in ('multisine', 'chirp') for s in rec.segments)


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
             fd_fit: bool = True) -> dict[str, Any]:
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
        (:mod:`frf_ident.core.diagnosis.crosscheck.kinematic_gravity`; pinocchio reads it).
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
    {'report': report.json content, 'result': the :class:`DiagnosisResult`, 'mode': its mode,
    'recording': the diagnosed data, its joints matched to the model's axes}

    """
    progress = sink(progress)
    from frf_ident.core.diagnosis import diagnose_experiments, diagnose_timeseries
    from frf_ident.io.model_file import load_model, save_model
    from frf_ident.report.html import write_diagnosis_report
    model, robot, ctrl = load_model(model_path)
    rec = _match_axes(load_data(data, map_path), robot, model_path, progress, data)
    others = [(p, _match_axes(load_data(p, map_path), robot, model_path, progress, p))
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
    for p, r in [(data, rec)] + others:
        gaps = r.meta.get('gaps') or []
        if gaps:
            progress(f'{p}: {len(gaps)} gap(s) in the joint states '
                     f'({sum(b - a for a, b in gaps):.3f} s, first at {gaps[0][0]:.3f} s) left '
                     f'out of fit and validation')
    if abs(robot.sample_rate - rec.fs) > 1e-6 * rec.fs:
        fs = float(f'{rec.fs:.9g}')     # 999.9999999952 from float stamps is 1000
        progress(f'{model_path}: sample_rate {robot.sample_rate:g} Hz, the record {data} is '
                 f'sampled at {fs:g} Hz: the diagnosis and extended_model.yaml use {fs:g} Hz')
        robot = replace(robot, sample_rate=fs)
    if has_experiments(rec):
        progress('identification experiments found: FRF and closed-loop simulation evidence')
        from frf_ident.core.diagnosis.thresholds import SIM_JOBS
        res = diagnose_experiments(rec, robot, ctrl, jobs=SIM_JOBS if jobs is None else jobs,
                                   fd_fit=fd_fit)
    else:
        progress('no identification experiments: time-series (inverse-dynamics) evidence')
        res = diagnose_timeseries(rec, robot)
    mode = res.mode
    if urdf is not None:
        res = _kinematic_gravity(res, rec, robot, Path(urdf), progress)
    res = _position_terms_on_others(res, rec, others, robot, progress)
    res = _standard_errors_across(res, rec, others, robot, progress)
    res = _against_least_squares(res, rec, others, robot, progress)
    if others:
        from frf_ident.core.diagnosis.timeseries.extrapolation import beyond_fitted_range
        res.metrics['validation_records'] = [
            validate_on(str(p), o, robot, res.extended, ctrl) for p, o in others]
        for (p, o), v in zip(others, res.metrics['validation_records']):
            far = beyond_fitted_range(rec, res.fit_rows, o, robot.joint_names)
            v['beyond_fitted_range'] = far
            if far:
                progress(f'warning: --validate {p} leaves the configuration range fitted on '
                         f'{data}: ' + '; '.join(
                             f'{ax} reaches {r["reached_deg"][0]:.1f}..{r["reached_deg"][1]:.1f}'
                             f' deg, fitted {r["fitted_deg"][0]:.1f}..{r["fitted_deg"][1]:.1f}'
                             f' deg ({r["beyond_deg"]:.1f} deg beyond)'
                             for ax, r in far.items())
                         + ': position-dependent terms are extrapolated there')
    out.mkdir(parents=True, exist_ok=True)
    clear_outputs(out, OUTPUT_FILES)
    found = ', '.join(e.name for e in res.effects) or 'none'
    save_model(out / 'extended_model.yaml', res.extended, ctrl,
               extra={'description': f'{model.get("description", "nominal model")} + diagnosed '
                                     f'effects: {found}'})
    report = {'effects': [e.to_dict() for e in res.effects],
              'metrics': _plain_metrics(res.metrics),
              'unexplained': res.unexplained,
              'rejected': res.rejected,
              'extended_model': 'extended_model.yaml'}
    if res.discretisation is not None:
        report['discretisation'] = res.discretisation
    if res.band is not None:
        report['analysis_band'] = res.band.to_dict()
    if rec.meta.get('gaps'):
        report['gaps'] = rec.meta['gaps']
    (out / 'report.json').write_text(json.dumps(report, indent=1))
    write_diagnosis_report(out, report, res, rec, mode, data)
    _summary(res, progress)
    return {'report': report, 'result': res, 'mode': mode, 'recording': rec}


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
    res = diagnose(data, model_path, out, progress=progress, **options)
    rep = res['report']
    m = rep['metrics']
    return {'mode': res['mode'],
            'effects': ' '.join(f"{e['name']}@{e['axis']}" for e in rep['effects']) or 'none',
            # an axis once, also with several resonances above the analysis band
            'unexplained': ' '.join(dict.fromkeys(u['axis'] for u in rep['unexplained']))
            or 'none',
            'baseline_frf_error_db': m['baseline']['frf_error_db'],
            'extended_frf_error_db': m['extended']['frf_error_db'],
            'baseline_time_nrmse': m['baseline']['time_nrmse'],
            'extended_time_nrmse': m['extended']['time_nrmse']}


def _kinematic_gravity(res, rec: Recording, robot, urdf: Path, progress):
    """
    Replace the diagnosis' free gravity sinusoids with the gravity of the URDF's kinematics.

    pinocchio (:mod:`frf_ident.io.kinematics`) gives the gravity's base regressor at the
    record's positions and at poses spread over the configuration space; the core fits its
    base parameters jointly over the axes.
    """
    if res.mode != 'timeseries':
        progress(f'note: --urdf {urdf} is used by the time-series route only')
        return res
    from frf_ident.core.diagnosis.crosscheck.kinematic_gravity import fit_kinematic_gravity
    from frf_ident.io.kinematics import load_kinematics
    import numpy as np
    kin = load_kinematics(urdf, robot.joint_names)
    q = 0.5 * (rec.position[1:] + rec.position[:-1])
    poses = np.random.default_rng(0).uniform(-np.pi, np.pi, (64, robot.n_axes))
    res = fit_kinematic_gravity(res, rec, robot, kin.gravity_basis(q),
                                (poses, kin.gravity_basis(poses)), source=str(urdf))
    k = res.metrics['kinematic_gravity']
    progress(f'{urdf}: gravity of the kinematics, {len(k["base_parameters"])} base '
             f'parameters fitted jointly over the axes (held-out time_nrmse '
             f'{k["free_sinusoids_held_out"]:.3f} with free sinusoids per axis, '
             f'{res.metrics["extended"]["time_nrmse"]:.3f} with these)')
    return res


def _position_terms_on_others(res, rec: Recording, others: list, robot, progress):
    """
    Drop the gravity and ripple terms that do not generalise to the ``--validate`` records.

    :func:`frf_ident.core.diagnosis.crosscheck.generalisation.drop_terms_not_generalising`; adds
    ``metrics['position_terms_on_validate']`` (per axis the time_nrmse on each record with
    and without its terms, and whether they were dropped) and prints one line per axis.
    """
    from frf_ident.core.diagnosis.crosscheck.generalisation import drop_terms_not_generalising
    res, verdict = drop_terms_not_generalising(res, rec, robot,
                                               [(str(p), o) for p, o in others])
    for ax, v in verdict.items():
        progress(f'{ax}: position-dependent terms on the --validate records, time_nrmse '
                 f'{" / ".join(f"{x:.3f}" for x in v["with"])} with, '
                 f'{" / ".join(f"{x:.3f}" for x in v["without"])} without: '
                 + ('dropped (they do not generalise)' if v['dropped'] else 'kept'))
    if verdict:
        res.metrics['position_terms_on_validate'] = verdict
    return res


def _standard_errors_across(res, rec: Recording, others: list, robot, progress):
    """
    Check the standard errors against the spread between records; widen them if it is larger.

    Time-series route (:mod:`frf_ident.core.diagnosis.crosscheck.spread`): each ``--validate`` record
    diagnosed on its own against the fit record's parameters, or without such records the
    two halves of the record against each other. Adds ``metrics['standard_errors_across']``.
    """
    from frf_ident.core.diagnosis import diagnose_timeseries
    from frf_ident.core.diagnosis.crosscheck.spread import estimates, spread_check, widened
    from frf_ident.errors import EstimationError
    if res.mode != 'timeseries':
        return res
    if others:
        what, recs = 'the --validate records', [o for _, o in others]
        runs = [estimates(res.effects)]
    else:
        n = rec.t.size // 2
        what, runs = 'the two halves of the record', []
        recs = [Recording(rec.t[sl] - rec.t[sl][0], rec.joint_names, rec.position[sl],
                          rec.velocity[sl], rec.effort[sl], meta=dict(rec.meta))
                for sl in (slice(0, n), slice(n, None))]
    try:
        runs += [estimates(diagnose_timeseries(o, replace(robot, sample_rate=o.fs)).effects)
                 for o in recs]
    except EstimationError as err:
        progress(f'standard errors not checked across records ({what}: {err})')
        return res
    check = spread_check(runs)
    check['compared'] = what
    res.metrics['standard_errors_across'] = check
    if check['rms_z'] is None:
        return res
    progress(f'standard errors against the spread between {what}: RMS of the differences '
             f'{check["rms_z"]:.2g} combined standard errors over {len(check["pairs"])} '
             f'parameter(s) (chi-square p = {check["p_value"]:.2g}): '
             + (f'standard errors widened x{check["factor"]:.2g}' if check['factor'] > 1
                else 'they hold'))
    return replace(res, effects=widened(res.effects, check['factor']))


def _against_least_squares(res, rec: Recording, others: list, robot, progress):
    """
    Judge the extended model against the 4-parameter least-squares baseline.

    The baseline (:mod:`frf_ident.core.diagnosis.crosscheck.baseline`) is fitted on the diagnosis' fit
    rows and compared on its held-out rows and on every ``--validate`` record. Time-series
    route: an axis whose extended model is not below the baseline on every held-out set is
    refitted with the baseline's terms in the model (inertia, viscous and Coulomb friction, a
    constant load); where that ties or beats the baseline the axis takes it, else its effects
    are rejected (the nominal axis). The held-out metrics are then taken again. Experiments
    route: the verdict is reported, nothing dropped (not calibrated against the sweep yet).
    Adds ``metrics['least_squares']``.
    """
    from frf_ident.core.diagnosis import diagnose_timeseries
    from frf_ident.core.diagnosis.crosscheck.baseline import (axes_not_beating, BASELINE_GROUPS,
                                                              fit_least_squares,
                                                              held_out_comparison, with_axes_of,
                                                              without_axes)
    from frf_ident.core.diagnosis.prediction import predict_metrics
    ls = fit_least_squares(rec, res.fit_rows, names=robot.joint_names)
    sets = [('held out', rec, res.held_out_rows)] + [(str(p), o, None) for p, o in others]
    comp = fitted = held_out_comparison(robot, res.extended, ls, sets)
    lost = axes_not_beating(comp)
    named = {ax: ', '.join(sorted({e.name for e in res.effects if e.axis == ax})) for ax in lost}
    took: dict[str, list[str]] = {}
    if res.mode == 'timeseries' and lost:
        alt = diagnose_timeseries(rec, robot, fc=res.band.fc_hz if res.band else None,
                                  only={ax: BASELINE_GROUPS for ax in lost})
        still = axes_not_beating(held_out_comparison(robot, alt.extended, ls, sets))
        took = {ax: v for ax, v in lost.items() if ax not in still}
        res = without_axes(with_axes_of(res, alt, took, comp), robot,
                           {ax: v for ax, v in lost.items() if ax not in took}, comp)
        m = predict_metrics(rec, res.extended, mask=res.held_out_rows)
        res.metrics['extended'] = {k: m[k] for k in ('frf_error_db', 'time_nrmse', 'per_axis')}
        comp = held_out_comparison(robot, res.extended, ls, sets)

    def verdict(ax: str) -> str:
        if ax not in lost:
            return 'beats the baseline (or ties it) on every held-out set'
        head = f'does not beat the baseline on {", ".join(lost[ax])}'
        if ax in took:
            return (f"{head}; its effects ({named[ax] or 'none'}) are replaced by the "
                    f"baseline's terms refitted in the model, which tie or beat it")
        if res.mode == 'timeseries' and named[ax]:
            return f'{head}; its effects ({named[ax]}) are rejected'
        return head
    res.metrics['least_squares'] = {
        'model': 'per axis: motor torque ~ inertia*qdd + viscous*qd + coulomb*tanh(qd/0.01) '
                 '+ offset, velocity and acceleration from the motor positions, low-passed '
                 f'at {ls.fc:g} Hz, fitted on the fit rows of the diagnosis',
        'metric': 'time_nrmse of the torque predicted from the measured motion (time-series '
                  'definition and sample mask)',
        'parameters': ls.parameters(), 'held_out': comp,
        # the extended model as the diagnosis fitted it, before the baseline rule
        'held_out_as_fitted': fitted,
        'extended_vs_baseline': {ax: verdict(ax) for ax in ls.names}}
    return res


def _summary(res, progress) -> None:
    """Print the held-out comparison with the least-squares baseline (the CLI prints the rest)."""
    ls = res.metrics['least_squares']
    progress('held-out time_nrmse (torque predicted from the measured motion), nominal / '
             'least squares / extended as fitted:')
    for s in ls['held_out_as_fitted']:
        progress(f'  {s["record"]}: ' + '; '.join(
            f'{ax} {v["nominal"]:.3f} / {v["least_squares"]:.3f} / {v["extended"]:.3f}'
            for ax, v in s['per_axis'].items()))
    for ax, v in ls['extended_vs_baseline'].items():
        if v.startswith('does not'):
            progress(f'  {ax}: the extended model {v}')


def _plain_metrics(m: Any) -> Any:
    """Return the metrics as strict JSON: NaN (no line to compare) becomes null."""
    if isinstance(m, dict):
        return {k: _plain_metrics(v) for k, v in m.items()}
    if isinstance(m, (list, tuple)):
        return [_plain_metrics(v) for v in m]
    if isinstance(m, float) and m != m:
        return None
    return m


def validate_on(name: str, other: Recording, robot, ext, ctrl) -> dict[str, Any]:
    """
    Return baseline and extended metrics of the two models on another record.

    Baseline and extended metrics of the two model files on another record (no refit):
    simulation of its experiments when it has them, else the time-series torque prediction.
    """
    from dataclasses import replace as _r
    robot = _r(robot, sample_rate=other.fs)
    ext = _r(ext, sample_rate=other.fs)
    if has_experiments(other):
        from frf_ident.core.diagnosis import Evaluator
        ev = Evaluator(other, ctrl)
        b, e = ev.metrics(robot), ev.metrics(ext)
    else:
        from frf_ident.core.diagnosis.prediction import predict_metrics
        b, e = (predict_metrics(other, m) for m in (robot, ext))
    keep = ('frf_error_db', 'time_nrmse', 'per_axis')
    return {'record': name, 'baseline': {k: b[k] for k in keep},
            'extended': {k: e[k] for k in keep}}
