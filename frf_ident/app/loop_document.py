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
The loop.json mapping of a controller check (docs/CONTRACT.md §8): margins with their notes.

Every margin is ``{"value", "std", "note"}``: value and standard deviation, null where not
finite or not available, and the note that says why (no -180 deg crossing within the measured
band, no gain crossover within it); per axis |L| at the band edge and whether the loop crosses
over above the band.
"""
from __future__ import annotations

from typing import Any

from frf_ident.core.loop.check import LoopCheck, Margin
import numpy as np

__all__ = ['check_dict']


def _finite(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None


def check_dict(check: LoopCheck) -> dict[str, Any]:
    """Return a LoopCheck as the JSON mapping of loop.json (non-finite values as null)."""
    def m(v: Margin, note: str | None = None) -> dict[str, float | str | None]:
        return {'value': _finite(v.value), 'std': _finite(v.std), 'note': note}
    axes = []
    for a in check.axes:
        notes = a.notes()
        axes.append({'axis': a.axis, 'kp': a.kp, 'ki': a.ki,
                     'gain_margin_db': m(a.gain_margin_db, notes.get('gain_margin_db')),
                     'phase_margin_deg': m(a.phase_margin_deg, notes.get('phase_margin_deg')),
                     'crossover_hz': m(a.crossover_hz, notes.get('crossover_hz')),
                     'modulus_margin': m(a.modulus_margin),
                     'band_edge_gain_db': _finite(a.edge_gain_db),
                     'crossover_above_band': a.crossover_above_band})
    return {'draws': check.draws, 'discrete_dt': check.discrete_dt, 'axes': axes,
            'peak_sensitivity': None if check.peak_sensitivity is None
            else m(check.peak_sensitivity)}
