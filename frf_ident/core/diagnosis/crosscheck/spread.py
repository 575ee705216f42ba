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
Check the reported standard errors against the spread of the same parameter between records.

The block-robust standard errors (:func:`..selection.block_standard_errors`) describe one
record: the noise and misfit within its blocks. Another record of the same robot (a
``--validate`` record, or the other half of the same one) moves through other configurations,
so whatever the model lacks there moves the parameters too. :func:`spread_check` compares
the difference of each friction and inertia parameter between two records with their
combined standard error, z = (a - b) / sqrt(se_a^2 + se_b^2); if the z values are larger
than the standard errors allow (chi-square test, SPREAD_ALPHA), the standard errors are
scaled by their RMS (:func:`widened`), so that they hold across records.
"""
from __future__ import annotations

from dataclasses import replace
import math
from typing import Any

from scipy import stats

from ..common import Effect
from ..thresholds import SPREAD_ALPHA

__all__ = ['SCALAR_PARAMETERS', 'estimates', 'spread_check', 'widened']

#: the parameters compared between records: a constant load (``gravity_torque``) and the
#: gravity terms are the configuration's, which differs between records by design
SCALAR_PARAMETERS = ('coulomb_friction', 'viscous_friction', 'motor_inertia')


def estimates(effects: list[Effect]) -> dict[tuple[str, str], tuple[float, float]]:
    """Return {(axis, parameter): (value, standard error)} of the scalar parameters."""
    out = {}
    for e in effects:
        for k in SCALAR_PARAMETERS:
            se = (e.standard_error or {}).get(k)
            if k in e.parameters and se is not None and math.isfinite(se) and se > 0:
                out[e.axis, k] = (float(e.parameters[k]), float(se))
    return out


def spread_check(runs: list[dict[tuple[str, str], tuple[float, float]]]) -> dict[str, Any]:
    """
    Compare the parameters of several records by their combined standard errors.

    Parameters
    ----------
    runs : list of dict
        Per record :func:`estimates`; the first is the record the diagnosis reports.

    Returns
    -------
    dict
        ``pairs``: per parameter named in the first and another record its two values, the
        combined standard error and z; ``rms_z`` (None without a pair); ``p_value`` of
        sum z^2 under chi-square(n pairs) (standard errors that hold give z ~ N(0, 1));
        ``factor``: ``rms_z`` where p < SPREAD_ALPHA, else 1.

    """
    pairs = []
    for j, other in enumerate(runs[1:], start=1):
        for key, (a, sa) in runs[0].items():
            if key in other:
                b, sb = other[key]
                s = math.hypot(sa, sb)
                pairs.append({'axis': key[0], 'parameter': key[1], 'record': j,
                              'values': [a, b], 'combined_se': s, 'z': (a - b) / s})
    if not pairs:
        return {'pairs': [], 'rms_z': None, 'p_value': None, 'factor': 1.0}
    chi2 = sum(p['z'] ** 2 for p in pairs)
    rms = math.sqrt(chi2 / len(pairs))
    p = float(stats.chi2.sf(chi2, len(pairs)))
    return {'pairs': pairs, 'rms_z': rms, 'p_value': p,
            'factor': rms if p < SPREAD_ALPHA and rms > 1.0 else 1.0}


def widened(effects: list[Effect], factor: float) -> list[Effect]:
    """Return the effects with every standard error multiplied by ``factor``."""
    if factor == 1.0:
        return effects
    return [replace(e, standard_error=_scaled(e.standard_error, factor)) for e in effects]


def _scaled(x: Any, f: float) -> Any:
    """Return a standard-error entry (number, list or dict of them; None) times ``f``."""
    if isinstance(x, dict):
        return {k: _scaled(v, f) for k, v in x.items()}
    if isinstance(x, list):
        return [_scaled(v, f) for v in x]
    return None if x is None else float(x) * f
