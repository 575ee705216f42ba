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
`frf-ident tune`: PI gains and filters per axis, shaped on the measured FRFs of a campaign.

Stages of :func:`run_tune` (docs/tune.md):

1. read the FRFs (one, or one per pose/amplitude) and pick the nominal pose
   (:func:`frf_ident.app.tune_inputs.read_campaign`);
2. fit every axis's resonances at every pose (:func:`~frf_ident.app.tune_inputs.axis_modes`)
   and group them into bands a filter must cover (:mod:`frf_ident.core.loop.modes`);
3. fit the uncertainty weight W(s) over the poses and variances
   (:mod:`frf_ident.core.loop.uncertainty`);
4. shape each axis's loop: PI and filters, worst case over the poses
   (:mod:`frf_ident.core.loop.shaping`), and say what binds (:mod:`frf_ident.core.loop.explain`);
5. check the tuned setting (and the model file's controller, "before") on every pose as
   ``loop`` does (:mod:`frf_ident.app.tune_check`);
6. write tune.json, tune.html/tune.png and the exports (:mod:`frf_ident.app.tune_files`);
7. with ``verify``, identify the model's robot again with the tuned controller and compare
   (:mod:`frf_ident.app.tune_verify`).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from frf_ident.app.tune_check import check_controller, ControllerCheck, target_verdicts
from frf_ident.app.tune_inputs import axis_modes, AxisModes, Campaign, read_campaign
from frf_ident.app.tune_judge import reported_judge, shared_bands
from frf_ident.core.loop.check import DRAWS
from frf_ident.core.loop.explain import explain_limit
from frf_ident.core.loop.modes import resonance_bands, ResonanceBand
from frf_ident.core.loop.notch import sections_response
from frf_ident.core.loop.shaping import shape_axis, ShapingResult
from frf_ident.core.loop.targets import TuneTargets
from frf_ident.core.loop.uncertainty import fit_weight, relative_bound, UncertaintyWeight
from frf_ident.core.progress import Progress, sink
from frf_ident.errors import FrfIdentInputError
import numpy as np

__all__ = ['AxisTuning', 'TuneOutcome', 'run_tune', 'summary_lines', 'tune_campaign']


@dataclass
class AxisTuning:
    """
    One axis: its resonances, uncertainty, the chosen setting and why it stops where it does.

    Attributes
    ----------
    modes : AxisModes
        The fitted resonances per pose.
    bands : list of ResonanceBand
        The resonances filtered.
    weight : UncertaintyWeight
        W(s) over the poses and the FRF's variance.
    result : ShapingResult
        The chosen PI and filters, their margins per pose on the lines, what binds.
    reason : str
        One sentence on what binds ('' when everything asked for is met).

    """

    modes: AxisModes
    bands: list[ResonanceBand]
    weight: UncertaintyWeight
    result: ShapingResult
    reason: str

    @property
    def axis(self) -> str:
        """Return the joint."""
        return self.modes.axis


@dataclass
class TuneOutcome:
    """
    What ``tune`` found and wrote.

    Attributes
    ----------
    campaign : Campaign
        The FRFs tuned on.
    targets : TuneTargets
        What was asked.
    sample_rate : float
        The controller's rate [Hz].
    axes : list of AxisTuning
        Per axis, in input order.
    after : ControllerCheck
        The tuned controller on every pose.
    before : ControllerCheck or None
        The model file's controller on every pose (None without a model).
    verdicts : list of dict
        Per axis :func:`~frf_ident.app.tune_check.target_verdicts` of ``after``.
    files : list of Path
        The files written.
    verify : object or None
        :class:`~frf_ident.app.tune_verify.Verification` with ``verify``.

    """

    campaign: Campaign
    targets: TuneTargets
    sample_rate: float
    axes: list[AxisTuning]
    after: ControllerCheck
    before: ControllerCheck | None
    verdicts: list[dict[str, Any]]
    files: list[Path]
    verify: Any = None

    @property
    def met(self) -> bool:
        """Return whether every axis meets every target."""
        return all(v['met'] for d in self.verdicts for v in d.values())

    def settings(self):
        """Return the chosen AxisSetting of every axis."""
        return [a.result.setting for a in self.axes]


def _controller_rate(model, rate: float | None) -> tuple[float, Any]:
    """Return the controller's rate and the model file's (robot, controller), or None."""
    if model is None:
        if rate is None:
            raise FrfIdentInputError('tune: give --model (its sample_rate and controller) or '
                                     '--rate HZ: the filters are discretised at the '
                                     "controller's rate")
        if not (np.isfinite(rate) and rate > 0):
            raise FrfIdentInputError(f'--rate {rate}: expected a positive rate in Hz')
        return float(rate), None
    from frf_ident.io.model_file import load_model
    _, robot, ctrl = load_model(model)
    if rate is not None and abs(rate - robot.sample_rate) > 1e-9 * rate:
        raise FrfIdentInputError(f'--rate {rate:g}: {model} runs at sample_rate '
                                 f'{robot.sample_rate:g} Hz; give one of them')
    return robot.sample_rate, (robot, ctrl)


def _model_order(camp: Campaign, robot, model) -> list[int]:
    """Index of every campaign axis in the model file's axes."""
    names = robot.joint_names
    missing = [a for a, _, _ in camp.channels if a not in names]
    if missing:
        raise FrfIdentInputError(f'{model}: no axes {missing} (the FRF has '
                                 f'{[a for a, _, _ in camp.channels]}, the model {names})')
    return [names.index(a) for a, _, _ in camp.channels]


def tune_campaign(camp: Campaign, targets: TuneTargets, sample_rate: float, *,
                  modes: str = 'physical', order: int | None = None,
                  progress: Progress | None = None) -> list[AxisTuning]:
    """
    Shape every axis's loop on a campaign (stages 2-4 of the module doc).

    Parameters
    ----------
    camp : Campaign
        The FRFs.
    targets : TuneTargets
        What to meet.
    sample_rate : float
        The controller's rate [Hz].
    modes : {'physical', 'rational'}, optional
        How the resonances are fitted.
    order : int, optional
        Rational order (default: by the cost test).
    progress : callable, optional
        One line per stage.

    Returns
    -------
    list of AxisTuning
        One per axis.

    """
    say = sink(progress)
    f = camp.freq_hz
    dt = 1.0 / sample_rate
    fits = [axis_modes(camp, j, modes, order) for j in range(len(camp.channels))]
    own = [resonance_bands(am.modes, camp.nominal, (f[0], f[-1])) for am in fits]
    out, fixed = [], []
    for j, (axis, _, _) in enumerate(camp.channels):
        am = fits[j]
        bands = shared_bands(own, j)
        p, var = camp.axis_responses(j)
        weight = fit_weight(f, relative_bound(p, var, camp.nominal))
        res = shape_axis(axis, f, p, camp.nominal, bands, dt, targets,
                         np.abs(weight.response(f)),
                         accept=reported_judge(camp, j, fixed, dt, targets))
        fixed.append(res.setting.response(f, dt))
        reason = ''
        if res.limit is not None:
            k = res.limit.pose
            reason = explain_limit(res.limit, f, p[k], res.setting, dt, pose=camp.names[k],
                                   delay_s=None if am.delay_s is None else am.delay_s[k],
                                   bands=bands)
        for b in own[j]:
            say(f'  {axis}: {b.summary()}')
        if len(bands) > len(own[j]):
            say(f"  {axis}: also tried at the other axes' resonances "
                + ', '.join(f'{b.centre_hz:.4g} Hz' for b in bands[len(own[j]):]))
        if not own[j]:
            say(f'  {axis}: no lightly damped resonance (damping < 0.2) in the band')
        say(f'  {axis}: {weight.summary()}')
        say(f'  {res.setting.summary()}')
        if reason:
            say(f'  {axis}: {"best achievable; " if not res.feasible else ""}{reason}')
        out.append(AxisTuning(am, bands, weight, res, reason))
    return out


def _check(camp: Campaign, axes: list[AxisTuning], sample_rate: float, draws: int
           ) -> ControllerCheck:
    f = camp.freq_hz
    s = [a.result.setting for a in axes]
    return check_controller(camp, [x.kp for x in s], [x.ki for x in s], 1.0 / sample_rate,
                            np.stack([x.filter_response(f) for x in s]),
                            [np.abs(a.weight.response(f)) for a in axes], draws)


def _before(camp: Campaign, axes: list[AxisTuning], model_ctrl, order: list[int],
            sample_rate: float, draws: int) -> ControllerCheck:
    robot, ctrl = model_ctrl
    f = camp.freq_hz
    filt = None
    if ctrl.n_sections:
        filt = np.stack([sections_response(f, ctrl.sos[k], sample_rate) for k in order])
    return check_controller(camp, ctrl.kp[order], ctrl.ki[order], 1.0 / sample_rate, filt,
                            [np.abs(a.weight.response(f)) for a in axes], draws)


def run_tune(sources: Sequence[str | Path], out: Path, *, targets: TuneTargets | None = None,
             model: str | Path | None = None, rate: float | None = None,
             modes: str = 'physical', order: int | None = None, nominal: str | None = None,
             draws: int = DRAWS, verify: bool = False,
             verify_band: tuple[float, float] | None = None,
             progress: Progress | None = None) -> TuneOutcome:
    """
    Tune the velocity loop of every axis on measured FRFs and write the results.

    Parameters
    ----------
    sources : sequence of str or Path
        One FRF (an estimate folder or FRF file) or a campaign of them (the inputs of
        ``fit``).
    out : Path
        Output directory (created if missing; the caller has checked it).
    targets : TuneTargets, optional
        What to meet; default :class:`~frf_ident.core.loop.targets.TuneTargets`.
    model : str or Path, optional
        Model file: its sample rate, its controller (checked as "before"), and the base of
        tuned_model.yaml.
    rate : float, optional
        Controller rate [Hz] without a model file.
    modes : {'physical', 'rational'}, optional
        How the resonances are fitted.
    order : int, optional
        Rational order of the mode fit.
    nominal : str, optional
        Name of the nominal pose.
    draws : int, optional
        Draws of the nominal FRF for the margins' standard deviations.
    verify : bool, optional
        Identify the model's robot again with the tuned controller and compare (needs
        ``model``).
    verify_band : tuple of float, optional
        Multisine band [Hz] of that identification (default ``identify``'s 2-60 Hz): the one
        the tuned FRF was measured with.
    progress : callable, optional
        One line per stage.

    Returns
    -------
    TuneOutcome
        The settings, checks and files.

    Raises
    ------
    FrfIdentInputError
        Unreadable or inconsistent FRFs, neither model nor rate, a model without the FRF's
        axes, ``verify`` without a model.

    """
    from frf_ident.app.tune_files import write_tune_files
    targets = targets or TuneTargets()
    if verify and model is None:
        raise FrfIdentInputError('--verify: needs --model (the robot identified again)')
    say = sink(progress)
    camp = read_campaign(sources, nominal)
    sample_rate, model_ctrl = _controller_rate(model, rate)
    order_idx = _model_order(camp, model_ctrl[0], model) if model_ctrl else None
    f = camp.freq_hz
    say(f'tune: {len(camp.frfs)} FRF{"s" if len(camp.frfs) > 1 else ""} '
        f'{camp.frfs[0].noutputs}x{camp.frfs[0].ninputs}, {f.size} lines {f[0]:.3g}-'
        f'{f[-1]:.3g} Hz; nominal {camp.names[camp.nominal]}; controller at '
        f'{sample_rate:g} Hz; {targets.summary()}')
    axes = tune_campaign(camp, targets, sample_rate, modes=modes, order=order, progress=say)
    after = _check(camp, axes, sample_rate, draws)
    before = _before(camp, axes, model_ctrl, order_idx, sample_rate, draws) \
        if model_ctrl else None
    verdicts = [target_verdicts(after, j, targets) for j in range(len(axes))]
    outcome = TuneOutcome(camp, targets, sample_rate, axes, after, before, verdicts, [])
    for line in summary_lines(outcome):
        say(line)
    out.mkdir(parents=True, exist_ok=True)
    outcome.files = write_tune_files(outcome, out, model=model, order=order_idx)
    say(f'tune: wrote {", ".join(p.name for p in outcome.files)} to {out}')
    if verify:
        from frf_ident.app.tune_verify import BAND_HZ, verify_tuning
        outcome.verify = verify_tuning(outcome, out / 'tuned_model.yaml', out / 'verify',
                                       band_hz=verify_band or BAND_HZ, progress=say)
    return outcome


def summary_lines(o: TuneOutcome) -> list[str]:
    """Return the few lines ``tune`` prints after shaping: per axis the targets, then MIMO."""
    lines = []
    names = o.campaign.names
    for a, v in zip(o.axes, o.verdicts):
        parts = []
        for key, label, unit in (('phase_margin_deg', 'PM', 'deg'),
                                 ('gain_margin_db', 'GM', 'dB'),
                                 ('modulus_margin', 'MM', ''), ('robust', 'max|WT|', '')):
            if key not in v:
                continue
            x = v[key]
            val = 'none in the band' if x['value'] is None else \
                f'{x["value"]:.3g}{" " + unit if unit else ""}'
            parts.append(f'{label} {val}{"" if x["met"] else " (missed)"}')
        st = v['stability']
        worst = '' if len(names) == 1 else ' worst over the poses'
        lines.append(f'  {a.axis} tuned{worst}: ' + ', '.join(parts)
                     + ('' if st['met'] else f'; not stable with its crossover in the band at '
                        f'{st["value"]} pose(s)'))
    ps = o.after.peak_sensitivity()
    if np.isfinite(ps).any():
        before = '' if o.before is None else (
            f' (model file controller: '
            f'{20 * np.log10(np.nanmax(o.before.peak_sensitivity())):.1f} dB)')
        lines.append(f'  MIMO sensitivity peak, worst pose: {20 * np.log10(np.nanmax(ps)):.1f} '
                     f'dB{before}')
    lines.append('tune: every target met at every pose' if o.met else
                 'tune: some targets missed (tune.json "verdicts"; the reasons above)')
    return lines
