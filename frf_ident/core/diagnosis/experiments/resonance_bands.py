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
The held-out judgement that sees resonances, and the bands of missing structure left over.

The FRF error over all lines (RMS, or a median) hides the few lines around a resonance: an
extension that fixes the low-frequency inertia and misses a mode scores well there.

- :func:`bands_left`: the extended model's residual (fit part, linear parameters refitted)
  tested for stage 0's bands of missing structure (:func:`.structure.model_bands`); each
  band nothing explains is an ``unexplained`` entry of kind 'structure missing in the FRF'
  with its edges, centre and peak line.
- :func:`resonance_bands`: on the held-out estimates (the last multisine realisation and the
  previous chirp iteration), per axis, the FRF error of the nominal and the extended model in
  the band of every named second mode (:func:`.second_mode.mode_band`) and every unexplained
  band: RMS over the band's lines and the 95th percentile over them.
- :func:`with_p95`: each axis' 95th percentile of the line errors beside its RMS.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

from frf_ident.core.fit.residual_whiteness import RESIDUAL_ALPHA
from frf_ident.core.model.params import RobotParams
import numpy as np

from .second_mode import mode_band
from .structure import model_bands, StructureReading
from ..common import diag_ratio, Effect
from ..records import ResonanceBand, Scores, Signature, Unexplained
from ..thresholds import UNEXPLAINED_RATIO

__all__ = ['MISSING_STRUCTURE', 'bands_left', 'resonance_bands', 'with_p95']

#: the ``kind`` of an unexplained band of the FRF fit's residual
MISSING_STRUCTURE = 'structure missing in the FRF'


def _line_errors(meas: dict[str, Any], est: dict[str, Any], axis: int,
                 band: list[float] | None = None) -> np.ndarray:
    """Return 20 log10 |P_meas / P_model| of axis' lines of every estimate (in ``band``)."""
    out = []
    for k, pm in meas.items():
        if k not in est:
            continue
        x = 20 * np.log10(np.abs(diag_ratio(pm, est[k])[axis]))
        if band is not None:
            f = np.asarray(pm.freq_hz)
            x = x[(f >= band[0]) & (f <= band[1])]
        out.append(x[np.isfinite(x)])
    return np.concatenate(out) if out else np.zeros(0)


def _rms_p95(x: np.ndarray) -> tuple[float, float]:
    """Return the RMS and the 95th percentile of |x| (NaN for no line)."""
    if not x.size:
        return float('nan'), float('nan')
    return (round(float(np.sqrt(np.mean(x ** 2))), 4),
            round(float(np.percentile(np.abs(x), 95)), 4))


def with_p95(scores: Scores, meas: dict[str, Any], est: dict[str, Any]) -> Scores:
    """Return ``scores`` with each axis' 95th-percentile line error filled in."""
    per = {ax: replace(s, frf_error_p95_db=_rms_p95(_line_errors(meas, est, i))[1])
           for i, (ax, s) in enumerate(scores.per_axis.items())}
    return replace(scores, per_axis=per)


def bands_left(meas: dict[str, Any], est: dict[str, Any], model: RobotParams,
               asked: StructureReading | None) -> list[Unexplained]:
    """
    Return an ``unexplained`` entry per band of missing structure the extended model leaves.

    A band of stage 0 that the model's multisine residual, its linear parameters refitted,
    still shows (:func:`.structure.model_bands`: at least MODE_MIN_LINES lines above the
    noise, false-alarm probability RESIDUAL_ALPHA per axis) at UNEXPLAINED_RATIO times the
    noise on average: clearly above noise, as an unexplained axis.

    Parameters
    ----------
    meas, est : dict
        The fit part's estimates of the record and of the extended model's simulation.
    model : RobotParams
        The extended model.
    asked : StructureReading or None
        Stage 0's reading (None: nothing is reported).

    Returns
    -------
    list of Unexplained
        Kind :data:`MISSING_STRUCTURE`, strongest band of each axis first.

    """
    names = model.joint_names
    bands = model_bands(meas, est, model, asked)
    return [Unexplained(ax, Signature(band_hz=[round(b.lo_hz, 2), round(b.hi_hz, 2)],
                                      centre_hz=round(b.centre_hz, 2),
                                      peak_hz=round(b.peak_hz, 2),
                                      peak_over_floor=round(b.excess, 3),
                                      false_alarm=RESIDUAL_ALPHA),
                        kind=MISSING_STRUCTURE)
            for ax, found in zip(names, bands) for b in found if b.excess >= UNEXPLAINED_RATIO]


def resonance_bands(ext: RobotParams, effects: list[Effect], unexplained: list[Unexplained],
                    estimates: dict[str, dict[str, Any]]) -> list[ResonanceBand]:
    """
    Return the held-out FRF error in the band of every named or unexplained mode.

    Parameters
    ----------
    ext : RobotParams
        The extended model.
    effects : list of Effect
        The named effects (their ``second_mode`` ones give a band each).
    unexplained : list of Unexplained
        The unexplained entries (those of kind :data:`MISSING_STRUCTURE` give a band each).
    estimates : dict
        The held-out estimates: 'measured', 'nominal', 'extended' -> {design: FRF}.

    Returns
    -------
    list of ResonanceBand
        One per band, named modes first.

    """
    meas = estimates['measured']
    lines = np.unique(np.concatenate([np.asarray(pm.freq_hz) for pm in meas.values()]))
    names = ext.joint_names
    found = [(e.axis_index, mode_band(ext, e, lines), 'second_mode') for e in effects
             if e.name == 'second_mode']
    found += [(names.index(u.axis), u.signature.band_hz, 'unexplained') for u in unexplained
              if u.kind == MISSING_STRUCTURE]
    out = []
    for i, band, source in found:
        nom = _line_errors(meas, estimates['nominal'], i, band)
        ext_ = _line_errors(meas, estimates['extended'], i, band)
        (nb, np95), (eb, ep95) = _rms_p95(nom), _rms_p95(ext_)
        out.append(ResonanceBand(names[i], list(band), source, nb, eb, np95, ep95, int(nom.size)))
    return out
