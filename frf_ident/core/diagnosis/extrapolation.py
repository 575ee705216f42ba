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
Measure how far another record leaves the configuration range a diagnosis was fitted on.

A model fitted on one record is checked on others (``--validate``); where another record
drives an axis beyond the positions the fit saw, a position-dependent term (gravity, ripple)
is extrapolated there, and a worse error need not mean a wrong effect. Reported per axis in
degrees beyond the fitted range.
"""
from __future__ import annotations

import math

from frf_ident.core.recording import Recording
import numpy as np

from .thresholds import RANGE_TOLERANCE_DEG

__all__ = ['beyond_fitted_range']


def beyond_fitted_range(fit: Recording, fit_rows: np.ndarray, other: Recording,
                        names: list[str]) -> dict[str, dict[str, float]]:
    """
    Return per axis how far ``other`` leaves the position range of the fit rows [deg].

    Parameters
    ----------
    fit : Recording
        The record the diagnosis fitted on.
    fit_rows : ndarray of bool, shape (N-1,)
        Its fit rows (between samples).
    other : Recording
        Another record of the same robot.
    names : list of str
        The axes' names in the report.

    Returns
    -------
    dict
        ``{axis: {"fitted_deg": [lo, hi], "reached_deg": [lo, hi], "beyond_deg": d}}`` for
        every axis that ``other`` leaves by more than RANGE_TOLERANCE_DEG (``d`` the larger
        excursion below or above); empty when it stays inside.

    """
    q = 0.5 * (fit.position[1:] + fit.position[:-1])[fit_rows]
    out = {}
    if not q.size:
        return out
    lo, hi = np.nanmin(q, axis=0), np.nanmax(q, axis=0)
    olo, ohi = np.nanmin(other.position, axis=0), np.nanmax(other.position, axis=0)
    for i, name in enumerate(names):
        d = math.degrees(max(lo[i] - olo[i], ohi[i] - hi[i], 0.0))
        if d > RANGE_TOLERANCE_DEG:
            out[name] = {'fitted_deg': [round(math.degrees(lo[i]), 2),
                                        round(math.degrees(hi[i]), 2)],
                         'reached_deg': [round(math.degrees(olo[i]), 2),
                                         round(math.degrees(ohi[i]), 2)],
                         'beyond_deg': round(d, 2)}
    return out
