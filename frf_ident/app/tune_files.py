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
The files of ``frf-ident tune`` (docs/CONTRACT.md section 8): tune.json, the page, exports.

- tune.json: the typed results serialised (:func:`tune_doc`);
- tune.png, tune.html: loops before and after with the uncertainty;
- pid_controller.yaml, filters.yaml: ros2_control parameter files
  (:mod:`frf_ident.io.ros2_control`);
- control_objects.pkl: python-control transfer functions (:mod:`frf_ident.io.controller_lti`);
- tuned_model.yaml (with a model file): the model file with the tuned PI and filters, what
  ``identify --model`` runs to close the loop again.
"""
from __future__ import annotations

from dataclasses import asdict
import json
from pathlib import Path
from typing import Any

from frf_ident.app.loop_document import check_dict
from frf_ident.app.outdir import clear_outputs
from frf_ident.core.jsonable import jsonable
from frf_ident.core.loop.notch import Biquad
import numpy as np

__all__ = ['OUTPUT_FILES', 'tune_doc', 'write_tune_files']

#: the files :func:`write_tune_files` may write (tuned_model.yaml: with a model file)
OUTPUT_FILES = ('tune.json', 'tune.png', 'tune.html', 'pid_controller.yaml', 'filters.yaml',
                'control_objects.pkl', 'tuned_model.yaml')


def _num(x: Any) -> Any:
    return float(x) if x is not None and np.isfinite(x) else None


def _filter_dict(b: Biquad, crossover_hz: float | None) -> dict[str, Any]:
    phase = None
    if crossover_hz is not None and np.isfinite(crossover_hz):
        phase = float(np.degrees(np.angle(b.response(np.array([crossover_hz]))[0])))
    return {'kind': b.kind, 'frequency_hz': b.frequency_hz, 'zeta_zero': b.zeta_zero,
            'zeta_pole': b.zeta_pole, 'depth_db': b.depth_db, 'band_hz': list(b.band_hz),
            'continuous': {'num': b.num_s, 'den': b.den_s},
            'discrete': {'sos': b.sos, 'sample_rate_hz': b.sample_rate,
                         'method': 'Tustin, prewarped at frequency_hz'},
            'phase_at_crossover_deg': phase}


def _pose_rows(check, camp, j: int) -> list[dict[str, Any]]:
    out = []
    for k, c in enumerate(check.checks):
        a = c.axes[j]
        out.append({'pose': camp.names[k], 'phase_margin_deg': _num(a.phase_margin_deg.value),
                    'gain_margin_db': _num(a.gain_margin_db.value),
                    'modulus_margin': _num(a.modulus_margin.value),
                    'crossover_hz': _num(a.crossover_hz.value),
                    'stable': bool(check.nyquist[k].stable[j]),
                    'crossover_in_band': bool(check.nyquist[k].in_band[j])})
    return out


def _margins(check, camp, j: int) -> dict[str, Any]:
    nom = check_dict(check.checks[camp.nominal])['axes'][j]
    worst = {}
    for name in ('phase_margin_deg', 'gain_margin_db', 'modulus_margin'):
        v, k = check.worst(j, name)
        worst[name] = {'value': _num(v), 'pose': camp.names[k]}
    r = None if check.robust is None else asdict(check.robust[j])
    return {'nominal': nom, 'worst_pose': worst, 'robust': r,
            'per_pose': _pose_rows(check, camp, j)}


def tune_doc(o) -> dict[str, Any]:
    """Return tune.json's mapping of a TuneOutcome (docs/CONTRACT.md section 8)."""
    camp = o.campaign
    axes = []
    for j, a in enumerate(o.axes):
        s = a.result.setting
        wc = o.after.checks[camp.nominal].axes[j].crossover_hz.value
        num, den = a.weight.num_den()
        lim = a.result.limit
        axes.append({
            'axis': a.axis, 'mode_fit': a.modes.fit,
            'modes': [[asdict(m) for m in ms] for ms in a.modes.modes],
            'delay_s': a.modes.delay_s,
            'bands': [{'low_hz': b.low_hz, 'high_hz': b.high_hz, 'centre_hz': b.centre_hz,
                       'damping': b.damping, 'spread': b.spread} for b in a.bands],
            'weight': {'order': a.weight.order, 'gain': a.weight.gain,
                       'sections': [{'wn_rad_s': x[0], 'zeta_n': x[1], 'wd_rad_s': x[2],
                                     'zeta_d': x[3]} for x in a.weight.sections],
                       'num': num, 'den': den, 'excess_db': a.weight.excess_db(),
                       'bound_max': float(a.weight.bound.max())},
            'setting': {'kp': s.kp, 'ki': s.ki, 'kd': 0.0,
                        'filters': [_filter_dict(b, wc) for b in s.filters]},
            'search': {'feasible': a.result.feasible, 'candidates': a.result.searched,
                       'limit': None if lim is None else _limit_dict(lim, camp),
                       'reason': a.reason},
            'margins': _margins(o.after, camp, j),
            'before': None if o.before is None else _margins(o.before, camp, j),
            'verdicts': {k: {**v, 'pose': None if v['pose'] is None else camp.names[v['pose']]}
                         for k, v in o.verdicts[j].items()}})
    ps = o.after.peak_sensitivity()
    return jsonable({
        'sources': [str(s) for s in camp.sources], 'names': camp.names, 'poses': camp.poses,
        'nominal': camp.names[camp.nominal], 'sample_rate_hz': o.sample_rate,
        'freq_hz': [float(camp.freq_hz[0]), float(camp.freq_hz[-1])],
        'targets': asdict(o.targets), 'met': o.met, 'axes': axes,
        'peak_sensitivity': None if not np.isfinite(ps).any() else {
            'after': [_num(x) for x in ps],
            'before': None if o.before is None else
            [_num(x) for x in o.before.peak_sensitivity()]},
        'files': [p.name for p in o.files] or None})


def _limit_dict(lim, camp) -> dict[str, Any]:
    return {'target': lim.target, 'pose': camp.names[lim.pose], 'value': _num(lim.value),
            'wanted': _num(lim.wanted), 'frequency_hz': _num(lim.frequency_hz),
            'because': None if lim.because is None else _limit_dict(lim.because, camp)}


def _tuned_model(o, model, order: list[int], path: Path) -> Path:
    from frf_ident.core.model.schema import PASS_SECTION
    from frf_ident.io.model_file import load_model, save_model
    _, robot, ctrl = load_model(model)
    tuned = ctrl.copy()
    m = max([len(s.filters) for s in o.settings()] + [0])
    sos = np.tile(PASS_SECTION, (robot.n_axes, m, 1)).astype(float)
    for s, k in zip(o.settings(), order):
        tuned.kp[k], tuned.ki[k] = s.kp, s.ki
        sos[k, :len(s.filters)] = s.sos()
    tuned.sos, tuned.filter_state = sos, np.zeros(sos.shape[:2] + (2,))
    return save_model(path, robot, tuned, extra={
        'description': f'{robot.joint_names} velocity PI and filters tuned by frf-ident tune on '
                       f'{", ".join(o.campaign.names)}; the rest as {model}'})


def _page(o, out: Path, files: list[str]) -> Path:
    from frf_ident.report.tune_page import write_tune_page
    camp = o.campaign
    rows = []
    for a, v in zip(o.axes, o.verdicts):
        s = a.result.setting
        rows.append([a.axis, s.kp, s.ki, '; '.join(b.summary() for b in s.filters) or 'none']
                    + [('n/a' if v[k]['value'] is None else f'{v[k]["value"]:.3g}')
                       + ('' if v[k]['met'] else ' (missed)') for k in
                       ('phase_margin_deg', 'gain_margin_db', 'modulus_margin', 'robust')]
                    + ['yes' if v['stability']['met'] else 'no'])
    verdicts = (['axis', 'kp [N m s/rad]', 'ki [N m/rad]', 'filters', 'phase margin [deg]',
                 'gain margin [dB]', 'modulus margin', 'max |W T|', 'stable'], rows)
    frows = []
    for a in o.axes:
        wc = o.after.checks[camp.nominal].axes[o.axes.index(a)].crossover_hz.value
        for b in a.result.setting.filters:
            d = _filter_dict(b, wc)
            frows.append([a.axis, b.kind, b.frequency_hz, f'{b.band_hz[0]:.4g}-{b.band_hz[1]:.4g}',
                          b.zeta_zero, b.zeta_pole, b.depth_db, d['phase_at_crossover_deg'],
                          ', '.join(f'{x:.6g}' for x in b.sos)])
    filters = (['axis', 'kind', 'centre [Hz]', 'band [Hz]', 'zeta zeros', 'zeta poles',
                'depth [dB]', 'phase at crossover [deg]', 'sos b0 b1 b2 1 a1 a2'], frows)
    prow = []
    ps, pb = o.after.peak_sensitivity(), None if o.before is None else \
        o.before.peak_sensitivity()
    for k, name in enumerate(camp.names):
        r = [name]
        for j in range(len(o.axes)):
            c = o.after.checks[k].axes[j]
            r.append(f'{c.phase_margin_deg.value:.3g} / {c.gain_margin_db.value:.3g} / '
                     f'{c.modulus_margin.value:.2g}'
                     + ('' if o.after.nyquist[k].stable[j] and o.after.nyquist[k].in_band[j]
                        else ' (not judged stable)'))
        r += [ps[k], None if pb is None else pb[k]]
        prow.append(r)
    poses = (['pose'] + [f'{a.axis}: PM deg / GM dB / MM' for a in o.axes]
             + ['MIMO peak |S| after', 'before'], prow)
    wrows = [[a.axis, a.weight.order, float(a.weight.bound.max()), a.weight.excess_db(),
              o.after.robust[j].peak, o.after.robust[j].modulus_margin]
             for j, a in enumerate(o.axes)]
    weights = (['axis', 'order', 'max bound r', 'median excess [dB]', 'max |W T| tuned',
                'robust modulus margin'], wrows)
    intro = (f'{len(camp.frfs)} FRF(s) ({", ".join(camp.names)}), nominal '
             f'{camp.names[camp.nominal]}, controller at {o.sample_rate:g} Hz; '
             f'{o.targets.summary()}.')
    return write_tune_page(out / 'tune.html', title='Tuned velocity loop', intro=intro,
                           verdicts=verdicts, filters=filters, poses=poses, weights=weights,
                           after=o.after.checks[camp.nominal],
                           before=None if o.before is None else o.before.checks[camp.nominal],
                           figure='tune.png', files=files,
                           reasons=[f'{a.axis}: {a.reason}' if a.reason else ''
                                    for a in o.axes])


def _figure(o, out: Path) -> Path:
    from frf_ident.report.tune_figures import tune_figure
    camp = o.campaign
    f = camp.freq_hz
    c = np.stack([s.response(f, 1.0 / o.sample_rate) for s in o.settings()])
    after = np.stack([[frf.response[oi, ii] * c[j] for j, (_, oi, ii) in
                       enumerate(camp.channels)] for frf in camp.frfs])
    before = None
    if o.before is not None:
        b = o.before
        from frf_ident.core.loop.check import pi_response
        cb = np.stack([pi_response(f, b.kp[j], b.ki[j], 1.0 / o.sample_rate)
                       * (1 if b.filters is None else b.filters[j]) for j in range(len(c))])
        nom = camp.frfs[camp.nominal]
        before = np.stack([nom.response[oi, ii] * cb[j]
                           for j, (_, oi, ii) in enumerate(camp.channels)])
    w = np.stack([np.abs(a.weight.response(f)) for a in o.axes])
    return tune_figure(f, after, camp.nominal, w, before, [a.axis for a in o.axes],
                       o.targets.modulus_margin, out / 'tune.png')


def write_tune_files(o, out: Path, *, model=None, order: list[int] | None = None
                     ) -> list[Path]:
    """
    Write every file of a TuneOutcome into ``out`` (module doc); return them.

    Parameters
    ----------
    o : TuneOutcome
        The outcome (its ``files`` are filled in by the caller).
    out : Path
        The output directory.
    model : str or Path, optional
        The model file (tuned_model.yaml is written from it).
    order : list of int, optional
        Index of every tuned axis in the model file.

    Returns
    -------
    list of Path
        The files written.

    """
    from frf_ident.io.controller_lti import write_control_objects
    from frf_ident.io.ros2_control import (filter_chain_params, pid_controller_params,
                                           write_params)
    clear_outputs(out, OUTPUT_FILES)
    settings = o.settings()
    limits = None
    files = []
    if model is not None:
        files.append(_tuned_model(o, model, order, out / 'tuned_model.yaml'))
        from frf_ident.io.model_file import load_model
        robot = load_model(out / 'tuned_model.yaml')[1]
        limits = [robot.torque_limits()[k] for k in order]
    src = ', '.join(o.campaign.names)
    files.append(write_params(pid_controller_params(settings, limits), out / 'pid_controller.yaml',
                              f'ros2_controllers pid_controller (Jazzy) parameters: velocity PI '
                              f'tuned by frf-ident tune on {src}\nat {o.sample_rate:g} Hz; run '
                              f'filters.yaml in front of it on the measured velocity'))
    files.append(write_params(filter_chain_params(settings), out / 'filters.yaml',
                              f'ros2_controllers chained_filter_controller parameters: the '
                              f'velocity filters tuned by frf-ident tune,\nsecond-order '
                              f'sections discrete at {o.sample_rate:g} Hz (filters/'
                              f'TransferFunctionFilterDouble b, a)'))
    files.append(write_control_objects(settings, [a.weight for a in o.axes],
                                       1.0 / o.sample_rate, out / 'control_objects.pkl'))
    files.append(_figure(o, out))
    names = [p.name for p in files] + ['tune.html', 'tune.json']
    files.append(_page(o, out, names))
    o.files = files + [out / 'tune.json']
    (out / 'tune.json').write_text(json.dumps(tune_doc(o), indent=1))
    return o.files
