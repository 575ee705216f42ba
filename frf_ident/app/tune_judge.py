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
What ``tune``'s search of one axis may use and must pass, across the axes of a robot.

:func:`shared_bands`: the resonance bands an axis may filter (its own and the other axes',
the poles of a coupled robot being shared). :func:`reported_judge`: the last word on a
choice the search made on the lines: the margins as reported and the MIMO loop.
"""
from __future__ import annotations

from frf_ident.app.loop import margins
from frf_ident.app.tune_inputs import Campaign
from frf_ident.core.loop.check import loop_response, sensitivity_peak
from frf_ident.core.loop.frd_margins import frd_margins, mimo_encirclements
from frf_ident.core.loop.modes import ResonanceBand
from frf_ident.core.loop.targets import TuneTargets
import numpy as np
from scipy import interpolate

__all__ = ['UPSAMPLE', 'reported_judge', 'shared_bands']

#: the search's judge reads the margins off the spline between the lines at this many times
#: their number (python-control's FRD interpolation, what the report reads)
UPSAMPLE = 8


def shared_bands(own: list[list[ResonanceBand]], j: int) -> list[ResonanceBand]:
    """
    Return the bands axis j may filter: its own, then the other axes' it does not overlap.

    The poles of a coupled robot are shared: a mode another axis's fit found can lift this
    axis's loop, or the MIMO loop through the coupling; the search decides whether a filter
    there pays.
    """
    out = list(own[j])
    for k, bands in enumerate(own):
        for b in bands if k != j else []:
            if all(b.high_hz < o.low_hz or b.low_hz > o.high_hz for o in out):
                out.append(b)
    return out


def reported_judge(camp: Campaign, j: int, fixed: list[np.ndarray], dt: float,
                   targets: TuneTargets):
    """
    Return the search's judge for axis j: the margins as reported meet the targets everywhere.

    The search reads the margins off the lines; ``loop`` and tune's report interpolate
    between them (python-control's spline through real and imaginary part): the judge reads
    them off such a spline, UPSAMPLE times denser, at every pose, and a candidate that passes
    there once more as reported (python-control, ~50 ms a pose: only for those). For a square
    FRF also the MIMO sensitivity peak with the axes tuned before it closed too (the later
    ones open): at most 1 / modulus margin target at every pose, and no encirclement of
    det(I + L) (:func:`~frf_ident.core.loop.frd_margins.mimo_encirclements`), so the
    coupling cannot undo what each axis meets.
    """
    f = camp.freq_hz
    p, _ = camp.axis_responses(j)
    square = all(fr.noutputs == fr.ninputs for fr in camp.frfs) and len(camp.channels) > 1
    inputs = [i for _, _, i in camp.channels]
    dense = np.geomspace(f[0], f[-1], UPSAMPLE * f.size)

    def accept(setting) -> bool:
        c = setting.response(f, dt)
        if square:
            cs = np.zeros((len(inputs), f.size), dtype=complex)
            for k, ck in enumerate(fixed + [c]):
                cs[inputs[k]] = ck
            loops = [loop_response(fr.response, cs) for fr in camp.frfs]
            if not (max(sensitivity_peak(lo) for lo in loops) <= 1.0 / targets.modulus_margin
                    and all(mimo_encirclements(lo) == 0 for lo in loops)):
                return False
        lo = interpolate.CubicSpline(2 * np.pi * f, p * c[None], axis=-1)(2 * np.pi * dense)
        m = frd_margins(lo, dense)
        if not (np.all(m.phase_margin_deg >= targets.phase_margin_deg)
                and np.all(m.modulus_margin >= targets.modulus_margin)
                and np.all(np.minimum(m.gain_margin_db, m.top_db) >= targets.gain_margin_db)):
            return False
        gm, pm, _, mm = margins(p * c[None], 2 * np.pi * f).T          # what is reported
        return bool(np.all(pm >= targets.phase_margin_deg)
                    and np.all(mm >= targets.modulus_margin)
                    and np.all(gm >= targets.gain_margin_db))
    return accept
