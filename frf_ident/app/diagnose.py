"""`frf-ident diagnose DATA --model M.yaml --out DIR` (docs/CONTRACT.md §7): what the nominal
simulation gets wrong, which effect causes it, the extended model and its gain on held-out data.

DATA is a bag (identification experiments -> FRF and simulation evidence, or any bag with
/joint_states -> time-series evidence), or a CSV/MAT table: with ``--map`` through
:func:`frf_ident.io.importer.import_table`; without a map the two real data sets of the project
are recognised (EMPS ``DATA_EMPS.mat``, KUKA KR300 ``recorded_FF_*.mat``, axes 1-3).
Writes DIR/report.json, DIR/extended_model.yaml, DIR/report.html and its PNG plots.
"""
from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import Any, Callable

import numpy as np

from frf_ident.core.recording import Recording
from frf_ident.errors import FrfIdentInputError

KUKA_AXES = 3


def load_emps_mat(path: Path) -> tuple[Recording, dict[str, Any]]:
    """EMPS estimation run (SOURCE.md): qm [m], force = gtau * vir [N], 1 kHz; velocity by
    central differences of qm."""
    import scipy.io as sio
    d = sio.loadmat(path)
    t = d['t'].ravel()
    q = d['qm'].ravel()
    dt = float(np.median(np.diff(t)))
    t = t[0] + dt * np.arange(t.size)
    u = float(np.squeeze(d['gtau'])) * d['vir'].ravel()
    v = np.gradient(q, dt)
    return Recording(t, ['emps'], q, v, u, meta={'source': str(path), 'kind': 'emps'}), {}


def load_kuka_mat(path: Path) -> tuple[Recording, dict[str, Any]]:
    """KUKA KR300 recorded trajectory (SOURCE.md), axes 1-3: motor position/velocity scaled to
    the joint side [deg -> rad], measured motor torque act_torque_abs_nm [N m], link-side
    encoder act_pos_se_deg; gravity regressors sin/cos of q2 and q2 + q3."""
    import scipy.io as sio
    d = sio.loadmat(path, squeeze_me=True, struct_as_record=False)
    r = d['rec']
    t = np.asarray(r.time_cont, float)
    sl = slice(0, KUKA_AXES)
    q = np.radians(np.asarray(r.act_pos_mot_deg, float)[sl].T)
    v = np.radians(np.asarray(r.act_vel_mot_deg_per_s, float)[sl].T)
    u = np.asarray(r.act_torque_abs_nm, float)[sl].T
    qo = np.radians(np.asarray(r.act_pos_se_deg, float)[sl].T)
    dt = float(np.median(np.diff(t)))
    t = t[0] + dt * np.arange(t.size)
    q2, q23 = q[:, 1], q[:, 1] + q[:, 2]
    nuis = np.column_stack([np.sin(q2), np.cos(q2), np.sin(q23), np.cos(q23)])
    rec = Recording(t, ['joint_1', 'joint_2', 'joint_3'], q, v, u,
                    meta={'source': str(path), 'kind': 'kuka_kr300'})
    return rec, {'nuisance': nuis, 'link_position': qo}


def load_data(path: Path, map_path: Path | None = None) -> tuple[Recording, dict[str, Any]]:
    """DATA -> (Recording, extras). Extras: 'nuisance' regressors, 'link_position'."""
    path = Path(path)
    if not path.exists():
        raise FrfIdentInputError(f'{path}: no such bag or file')
    if path.is_dir() or path.suffix == '.mcap':
        from frf_ident.bag import read_recording
        rec, _ = read_recording(path)
        return rec, {}
    if map_path is not None:
        try:
            from frf_ident.io.importer import import_table
        except ImportError:
            raise FrfIdentInputError(f'--map {map_path}: the importer (frf_ident.io.importer) '
                                     f'is not available in this installation') from None
        return import_table(path, map_path), {}
    if path.suffix.lower() == '.mat':
        import scipy.io as sio
        try:
            names = {n for n, *_ in sio.whosmat(path)}
        except Exception:  # whosmat trips over MATLAB objects (function handles)
            try:
                names = {k for k in sio.loadmat(path) if not k.startswith('__')}
            except Exception as exc:
                raise FrfIdentInputError(f'{path}: not a readable MAT file ({exc})') from None
        if {'qm', 'vir', 'gtau', 't'} <= names:
            return load_emps_mat(path)
        if 'rec' in names:
            return load_kuka_mat(path)
        raise FrfIdentInputError(f'{path}: unknown MAT layout (variables {sorted(names)}); '
                                 f'give --map MAP.yaml (see frf-ident import)')
    raise FrfIdentInputError(f'{path}: expected a bag directory, .mcap, or a .csv/.mat with '
                             f'--map MAP.yaml')


def has_experiments(rec: Recording) -> bool:
    return rec.reference is not None and any(
        s.info.get('design') in ('multisine', 'chirp') for s in rec.segments)


def _select_joints(rec, names):
    """The recording restricted to the named joints, in that order."""
    from frf_ident.core.recording import Recording
    idx = [list(rec.joint_names).index(n) for n in names]

    def pick(a):
        return None if a is None else a[:, idx]
    return Recording(rec.t, list(names), pick(rec.position), pick(rec.velocity),
                     pick(rec.effort), pick(rec.reference), pick(rec.excitation),
                     list(rec.segments), dict(rec.meta))


def diagnose(data: Path, model_path: Path, out: Path, *, map_path: Path | None = None,
             progress: Callable[[str], None] = print) -> dict[str, Any]:
    """Run the diagnosis and write DIR/report.json, extended_model.yaml, report.html."""
    from frf_ident.core.diagnosis import diagnose_experiments, diagnose_timeseries
    from frf_ident.io.model_file import load_model, save_model
    model, robot, ctrl = load_model(model_path)
    rec, extras = load_data(data, map_path)
    if robot.joint_names != list(rec.joint_names):
        if set(robot.joint_names) <= set(rec.joint_names):
            rec = _select_joints(rec, robot.joint_names)
        elif robot.n_axes < len(rec.joint_names):
            progress(f'note: model axes {robot.joint_names} taken in order for the first '
                     f'{robot.n_axes} data joints {rec.joint_names[:robot.n_axes]}')
            rec = _select_joints(rec, rec.joint_names[:robot.n_axes])
        elif robot.n_axes != len(rec.joint_names):
            raise FrfIdentInputError(f'--model {model_path}: axes {robot.joint_names} do not '
                                     f'match the data joints {rec.joint_names}')
        else:
            progress(f'note: model axes {robot.joint_names} taken in order for data joints '
                     f'{rec.joint_names}')
    if abs(robot.sample_rate - rec.fs) > 1e-6 * rec.fs:
        from dataclasses import replace
        robot = replace(robot, sample_rate=rec.fs)
    if has_experiments(rec):
        progress('identification experiments found: FRF and closed-loop simulation evidence')
        res = diagnose_experiments(rec, robot, ctrl, progress=progress)
        mode = 'experiments'
    else:
        progress('no identification experiments: time-series (inverse-dynamics) evidence')
        res = diagnose_timeseries(rec, robot, nuisance=extras.get('nuisance'),
                                  progress=progress)
        mode = 'timeseries'
        if extras.get('link_position') is not None:
            res['elasticity'] = elasticity(rec, extras['link_position'], robot,
                                           res['effects'], progress)
    from frf_ident.core.diagnosis import apply_effect
    for e in res['effects']:
        if e.name == 'parameter_mismatch' and 'stiffness' in e.parameters and mode == 'timeseries':
            res['extended'] = apply_effect(res['extended'], e)
    out.mkdir(parents=True, exist_ok=True)
    save_model(out / 'extended_model.yaml', res['extended'], ctrl,
               extra={'description': f'{model.get("description", "nominal model")} + diagnosed '
                                     f'effects: {", ".join(e.name for e in res["effects"]) or "none"}'})
    report = {'effects': [e.to_dict() for e in res['effects']],
              'metrics': res['metrics'], 'extended_model': 'extended_model.yaml'}
    (out / 'report.json').write_text(json.dumps(report, indent=1))
    write_html(out, report, res, rec, mode, data)
    return {'report': report, 'result': res, 'mode': mode}


def elasticity(rec: Recording, link_position: np.ndarray, robot, effects: list,
               progress: Callable[[str], None]) -> list[dict[str, Any]]:
    """What the joint elasticity changes: deflection q_m - q_o, its correlation with torque,
    the stiffness it implies, and the rigid-model residual with motor- vs link-side motion.
    Adds a parameter_mismatch effect (stiffness) per axis where the deflection follows the
    torque (r > 0.5)."""
    from frf_ident.core.diagnosis.common import Effect
    from frf_ident.core.diagnosis.residual import lowpass
    fs = rec.fs
    out = []
    for i, ax in enumerate(robot.axes):
        defl = lowpass(rec.position[:, i] - link_position[:, i], fs, 10.0)
        tau = lowpass(rec.effort[:, i], fs, 10.0)
        d0, t0 = defl - defl.mean(), tau - tau.mean()
        r = float(d0 @ t0 / math.sqrt((d0 @ d0) * (t0 @ t0)))
        k = float((t0 @ t0) / (d0 @ t0)) if d0 @ t0 != 0 else float('inf')
        vo = np.gradient(link_position[:, i], rec.dt)
        dv = rec.velocity[:, i] - vo
        item = {'axis': ax.name, 'deflection_rms_deg': math.degrees(float(np.std(defl))),
                'deflection_range_deg': math.degrees(float(np.ptp(defl))),
                'torque_correlation': r, 'stiffness_torque_per_rad': k,
                'velocity_difference_rms': float(np.std(lowpass(dv, fs, 10.0)))}
        out.append(item)
        progress(f'{ax.name}: motor-link deflection RMS {item["deflection_rms_deg"]:.4f} deg, '
                 f'correlation with torque r = {r:.2f}, apparent stiffness {k:.4g} per rad')
        if r > 0.5 and math.isfinite(k) and k > 0:
            effects.append(Effect('parameter_mismatch', ax.name, 0.05 * min(r ** 2, 1.0),
                                  {'stiffness': k},
                                  f'the rigid model ignores joint elasticity: motor minus link '
                                  f'encoder deflection ({item["deflection_rms_deg"]:.3g} deg RMS, '
                                  f'range {item["deflection_range_deg"]:.3g} deg) follows the motor '
                                  f'torque (r = {r:.2f}), i.e. a stiffness of about {k:.3g} '
                                  f'(torque units)/rad at the motor', i))
    effects.sort(key=lambda e: -e.score)
    return out


# --- human report -----------------------------------------------------------------------------

def _plots(out: Path, res: dict[str, Any], rec: Recording, mode: str) -> list[tuple[str, str]]:
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    figs: list[tuple[str, str]] = []
    if mode == 'experiments':
        est = res['estimates']
        n = rec.velocity.shape[1]
        fig, ax = plt.subplots(3, n, figsize=(5 * n, 9), squeeze=False, sharex=True)
        for i in range(n):
            for key, style in (('multisine', '-'), ('chirp', '--')):
                if key not in est['measured']:
                    continue
                f = est['measured'][key].freq_hz
                for lab, col in (('measured', 'k'), ('nominal', 'tab:red'),
                                 ('extended', 'tab:green')):
                    p = est[lab][key].response[i, i]
                    ax[0, i].semilogx(f, 20 * np.log10(np.abs(p)), style, color=col,
                                      label=f'{lab} {key}')
                    ax[1, i].semilogx(f, np.degrees(np.unwrap(np.angle(p))), style, color=col)
                for lab, col in (('nominal', 'tab:red'), ('extended', 'tab:green')):
                    r = est['measured'][key].response[i, i] / est[lab][key].response[i, i]
                    ax[2, i].semilogx(f, 20 * np.log10(np.abs(r)), style, color=col,
                                      label=f'{key}: measured/{lab}')
            ax[0, i].set_title(f'{rec.joint_names[i]}: dq_m/tau_m (held-out data)')
            ax[0, i].set_ylabel('dB')
            ax[1, i].set_ylabel('deg')
            ax[2, i].set_ylabel('residual dB')
            ax[2, i].set_xlabel('Hz')
            ax[0, i].legend(fontsize=6)
            ax[2, i].legend(fontsize=6)
        fig.tight_layout()
        fig.savefig(out / 'bode.png', dpi=80)
        plt.close(fig)
        figs.append(('bode.png', 'Measured vs nominal vs extended FRF (diagonal), and the '
                                 'residual spectrum |P_measured / P_model|'))
        sims = res['sims']
        fig, ax = plt.subplots(2, n, figsize=(5 * n, 6), squeeze=False)
        step = max(1, rec.t.size // 20000)
        for i in range(n):
            for lab, col in (('nominal', 'tab:red'), ('extended', 'tab:green')):
                du = rec.effort[::step, i] - sims[lab].effort[::step, i]
                ax[0, i].plot(rec.velocity[::step, i], du, '.', ms=1, color=col, label=lab)
                ax[1, i].plot(rec.position[::step, i], du, '.', ms=1, color=col, label=lab)
            ax[0, i].set_xlabel('motor velocity [rad/s]')
            ax[1, i].set_xlabel('motor position [rad]')
            ax[0, i].set_ylabel('torque residual [N m]')
            ax[0, i].legend(markerscale=8, fontsize=7)
            ax[0, i].set_title(rec.joint_names[i])
        fig.tight_layout()
        fig.savefig(out / 'residual.png', dpi=80)
        plt.close(fig)
        figs.append(('residual.png', 'Measured minus simulated torque (same reference, same '
                                     'controller) against velocity and position'))
    else:
        r = res['residual']
        n = r['f'].shape[1]
        from frf_ident.core.diagnosis.residual import lowpass
        ff = lowpass(r['f'], rec.fs, 20.0)
        fig, ax = plt.subplots(3, n, figsize=(5 * n, 9), squeeze=False)
        for i in range(n):
            ax[0, i].plot(r['t'], ff[:, i], 'k', lw=0.6, label='nominal residual')
            ax[0, i].plot(r['t'], ff[:, i] - (r['pred_extended'][:, i] - r['pred_baseline'][:, i]),
                          color='tab:green', lw=0.6, label='extended residual')
            ax[0, i].axvspan(r['t'][r['val_mask']][0], r['t'][-1], color='0.9', label='held out')
            ax[0, i].set_title(rec.joint_names[i])
            ax[0, i].set_xlabel('t [s]')
            ax[0, i].legend(fontsize=6)
            ax[1, i].plot(r['v'][:, i], ff[:, i], '.', ms=1, color='tab:red')
            ax[1, i].set_xlabel('velocity')
            ax[1, i].set_ylabel('inverse-dynamics residual')
            ax[2, i].plot(r['q'][:, i], ff[:, i], '.', ms=1, color='tab:blue')
            ax[2, i].set_xlabel('position')
        fig.tight_layout()
        fig.savefig(out / 'residual.png', dpi=80)
        plt.close(fig)
        figs.append(('residual.png', 'Inverse-dynamics residual of the nominal model (tau - M '
                                     'ddq - Fv dq, low-passed) in time, against velocity and '
                                     'position; grey: held-out part'))
    return figs


def write_html(out: Path, report: dict[str, Any], res: dict[str, Any], rec: Recording,
               mode: str, data: Path) -> Path:
    """DIR/report.html: ranked effects with evidence, metrics, plots."""
    figs = _plots(out, res, rec, mode)
    e = html.escape
    rows = ''.join(f'<tr><td>{k + 1}</td><td>{e(x["name"])}</td><td>{e(x["axis"])}</td>'
                   f'<td>{x["score"]:.2f}</td><td><code>{e(json.dumps(x["parameters"]))}</code>'
                   f'</td><td>{e(x["evidence"])}</td></tr>'
                   for k, x in enumerate(report['effects']))
    if not rows:
        rows = ('<tr><td colspan=6>none: the nominal model explains the data within its '
                'noise</td></tr>')
    m = report['metrics']
    el = ''
    if res.get('elasticity'):
        el = '<h2>Joint elasticity (motor vs link encoder)</h2><ul>' + ''.join(
            f'<li>{e(x["axis"])}: deflection {x["deflection_rms_deg"]:.4f} deg RMS '
            f'(range {x["deflection_range_deg"]:.3f} deg), correlation with torque '
            f'{x["torque_correlation"]:.2f}, apparent stiffness '
            f'{x["stiffness_torque_per_rad"]:.4g} per rad</li>' for x in res['elasticity']) + \
            '</ul>'
    doc = f"""<!doctype html><html><head><meta charset="utf-8"><title>frf-ident diagnosis</title>
<style>body{{font-family:sans-serif;max-width:1200px}}td,th{{border:1px solid #ccc;padding:4px;
vertical-align:top}}table{{border-collapse:collapse}}</style></head><body>
<h1>Diagnosis of {e(str(data))}</h1>
<p>Evidence: {'identification experiments (FRF of multisine and chirp, closed-loop simulation of the same reference)' if mode == 'experiments' else 'time series (inverse-dynamics residual regression)'}.</p>
<h2>Effects (most likely first)</h2>
<table><tr><th>#</th><th>effect</th><th>axis</th><th>score</th><th>parameters</th><th>evidence</th></tr>{rows}</table>
<h2>Gain on held-out data</h2>
<table><tr><th></th><th>frf_error_db</th><th>time_nrmse</th></tr>
<tr><td>nominal</td><td>{m['baseline']['frf_error_db']}</td><td>{m['baseline']['time_nrmse']}</td></tr>
<tr><td>extended</td><td>{m['extended']['frf_error_db']}</td><td>{m['extended']['time_nrmse']}</td></tr></table>
<p>{e(m['validation'])}</p>{el}
<p>Extended model: <a href="extended_model.yaml">extended_model.yaml</a></p>
""" + ''.join(f'<h3>{e(cap)}</h3><img src="{e(fn)}">' for fn, cap in figs) + '</body></html>'
    p = out / 'report.html'
    p.write_text(doc)
    return p
