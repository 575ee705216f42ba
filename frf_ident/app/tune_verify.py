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
``tune --verify``: close the loop again with the tuned controller and measure it.

The two-command recipe it runs (docs/tune.md), on the model file's simulation:

    frf-ident identify --model DIR/tuned_model.yaml --procedures multisine --out DIR/verify/bag
    frf-ident estimate DIR/verify/bag --out DIR/verify/estimate

then the tuned controller's margins on the new FRF (what ``loop --model
DIR/tuned_model.yaml`` reports) beside the prediction ``tune`` made on the FRF it was tuned
on: per margin the difference over the combined standard deviation of the two, which should
stay within AGREEMENT_SD. The multisine must be the one the tuned FRF was measured with (its
band; the procedure's line set follows from it): margins read between other lines are other
numbers. A new FRF on other lines is said so in one line.
"""
from __future__ import annotations

from dataclasses import dataclass
import json
from pathlib import Path

from frf_ident.app.loop import loop_check
from frf_ident.app.loop_document import check_dict
from frf_ident.app.tune_inputs import read_campaign
from frf_ident.core.jsonable import jsonable
from frf_ident.core.loop.check import DRAWS, LoopCheck
from frf_ident.core.loop.notch import sections_response
from frf_ident.core.progress import Progress, sink
import numpy as np

__all__ = ['AGREEMENT_SD', 'BAND_HZ', 'VERIFY_PERIODS', 'VERIFY_REALISATIONS', 'Verification',
           'verify_tuning']

#: a measured margin agrees with the prediction within this many combined standard deviations
AGREEMENT_SD = 3.0
#: multisine realisations of the verifying identification (the BLA's variance needs a few)
VERIFY_REALISATIONS = 6
#: periods per realisation (one more is the transient)
VERIFY_PERIODS = 3
#: multisine band of the verifying identification: identify's default
BAND_HZ = (2.0, 60.0)
#: the margins compared
MARGINS = ('phase_margin_deg', 'gain_margin_db', 'modulus_margin', 'crossover_hz')


@dataclass
class Verification:
    """
    The tuned loop measured again beside its prediction.

    Attributes
    ----------
    predicted, measured : LoopCheck
        The tuned controller on the FRF it was tuned on (nominal pose) and on the new one.
    agreement : dict
        ``{axis: {margin: z}}``: |measured - predicted| / sqrt(sd_p^2 + sd_m^2) (NaN where a
        margin or its standard deviation is missing).
    estimate : Path
        The new estimate's folder.

    """

    predicted: LoopCheck
    measured: LoopCheck
    agreement: dict[str, dict[str, float]]
    estimate: Path

    @property
    def agrees(self) -> bool:
        """Return whether every finite z is within AGREEMENT_SD."""
        z = [v for a in self.agreement.values() for v in a.values() if np.isfinite(v)]
        return bool(z) and max(z) <= AGREEMENT_SD

    def lines(self) -> list[str]:
        """Return one line per axis (predicted -> measured) and the MIMO peak."""
        out = []
        for p, m in zip(self.predicted.axes, self.measured.axes):
            parts = [f'{k.split("_")[0]} {getattr(p, k).text("")} -> '
                     f'{getattr(m, k).text("")}'.replace('  ', ' ')
                     for k in MARGINS[:3]]
            out.append(f'  {p.axis} predicted -> measured: ' + ', '.join(parts)
                       + f'; largest z {np.nanmax(list(self.agreement[p.axis].values())):.2g}')
        if self.measured.peak_sensitivity is not None:
            out.append(f'  MIMO sensitivity peak predicted '
                       f'{20 * np.log10(self.predicted.peak_sensitivity.value):.2f} dB, measured '
                       f'{20 * np.log10(self.measured.peak_sensitivity.value):.2f} dB')
        return out


def _z(p, m) -> float:
    sd = np.hypot(p.std, m.std)
    if not (np.isfinite(p.value) and np.isfinite(m.value) and np.isfinite(sd) and sd > 0):
        return float('nan')
    return float(abs(m.value - p.value) / sd)


def verify_tuning(outcome, tuned_model: Path, out: Path, *,
                  band_hz: tuple[float, float] = BAND_HZ, realisations: int = VERIFY_REALISATIONS,
                  periods: int = VERIFY_PERIODS, draws: int = DRAWS,
                  progress: Progress | None = None) -> Verification:
    """
    Identify the model's robot with the tuned controller, estimate, compare (module doc).

    Parameters
    ----------
    outcome : TuneOutcome
        What ``tune`` predicted.
    tuned_model : Path
        tuned_model.yaml.
    out : Path
        Folder for the bag, the estimate and verify.json.
    band_hz : tuple of float, optional
        (f_low, f_high) of the multisine [Hz]: that of the tuned FRF's experiment (default
        ``identify``'s).
    realisations, periods : int, optional
        Of the multisine.
    draws : int, optional
        Draws of the new FRF for the measured margins' standard deviations.
    progress : callable, optional
        One line per stage.

    Returns
    -------
    Verification
        The comparison (also in out/verify.json).

    """
    from frf_ident.app.estimate import estimate_bag
    from frf_ident.app.identify import run_identify
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    from frf_ident.core.simulation.runner import IdentificationConfig
    from frf_ident.io.model_file import load_model
    say = sink(progress)
    cfg = IdentificationConfig(MultisineConfig(f_low=float(band_hz[0]), f_high=float(band_hz[1]),
                                               n_realisations=realisations,
                                               n_periods=periods), None)
    out.mkdir(parents=True, exist_ok=True)
    say(f'verify: identify {tuned_model} with the tuned controller ({realisations} '
        f'realisations x {periods} periods, multisine {band_hz[0]:g}-{band_hz[1]:g} Hz)')
    run_identify(tuned_model, None, cfg, out / 'bag', progress=lambda s: None)
    estimate_bag(out / 'bag', out / 'estimate', progress=lambda s: None)
    camp = read_campaign([out / 'estimate'])
    old = outcome.campaign.freq_hz
    if camp.freq_hz.shape != old.shape or not np.allclose(camp.freq_hz, old, rtol=1e-9):
        say(f'verify: the new FRF has {camp.freq_hz.size} lines {camp.freq_hz[0]:.3g}-'
            f'{camp.freq_hz[-1]:.3g} Hz, the tuned one {old.size} lines {old[0]:.3g}-'
            f'{old[-1]:.3g} Hz: margins between other lines differ (give the band the tuned '
            f'FRF was measured with)')
    _, robot, ctrl = load_model(tuned_model)
    names = robot.joint_names
    order = [names.index(a) for a, _, _ in camp.channels]
    filt = np.stack([sections_response(camp.freq_hz, ctrl.sos[k], robot.sample_rate)
                     for k in order])
    measured = loop_check(camp.frfs[0], ctrl.kp[order], ctrl.ki[order], dt=robot.dt,
                          draws=draws, filters=filt)
    predicted = outcome.after.checks[outcome.campaign.nominal]
    agreement = {p.axis: {k: _z(getattr(p, k), getattr(m, k)) for k in MARGINS}
                 for p, m in zip(predicted.axes, measured.axes)}
    if predicted.peak_sensitivity is not None and measured.peak_sensitivity is not None:
        agreement['mimo'] = {'peak_sensitivity': _z(predicted.peak_sensitivity,
                                                    measured.peak_sensitivity)}
    v = Verification(predicted, measured, agreement, out / 'estimate')
    for line in v.lines():
        say(line)
    say(f'verify: {"agrees" if v.agrees else "does NOT agree"} with the prediction within '
        f'{AGREEMENT_SD:g} combined standard deviations')
    (out / 'verify.json').write_text(json.dumps(jsonable({
        'tuned_model': str(tuned_model), 'estimate': str(out / 'estimate'),
        'predicted': check_dict(predicted), 'measured': check_dict(measured),
        'agreement': {a: {k: (None if not np.isfinite(z) else z) for k, z in d.items()}
                      for a, d in agreement.items()},
        'agreement_sd': AGREEMENT_SD, 'agrees': v.agrees}), indent=1))
    return v
