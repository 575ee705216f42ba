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

from dataclasses import asdict, dataclass, field, replace
import math
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.progress import Progress
from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError
from scipy import stats

from ..common import Effect
from ..result import DiagnosisResult
from ..thresholds import SPREAD_ALPHA
from ..timeseries.pipeline import diagnose_timeseries

__all__ = ['SCALAR_PARAMETERS', 'scalar_estimates', 'SpreadCheck', 'SpreadPair', 'spread_check',
           'standard_errors_across', 'widened']

#: the parameters compared between records: a constant load (``gravity_torque``) and the
#: gravity terms are the configuration's, which differs between records by design
SCALAR_PARAMETERS = ('coulomb_friction', 'viscous_friction', 'motor_inertia')


@dataclass(frozen=True)
class SpreadPair:
    """One parameter of the report against the same parameter of another record."""

    axis: str
    parameter: str
    #: the other record's index (1: the first other record)
    record: int
    #: the report's value and the other record's
    values: list[float]
    combined_se: float
    #: the difference over the combined standard error
    z: float


@dataclass
class SpreadCheck:
    """The standard errors against the spread between records (``standard_errors_across``)."""

    pairs: list[SpreadPair] = field(default_factory=list)
    #: RMS of the z values (None without a pair) and the chi-square p value of their sum
    rms_z: float | None = None
    p_value: float | None = None
    #: what every standard error of the report was multiplied by (1: they hold)
    factor: float = 1.0
    #: what was compared: 'the --validate records' or 'the two halves of the record'
    compared: str = ''

    def to_dict(self) -> dict[str, Any]:
        """Return the report's entry."""
        return {'pairs': [asdict(p) for p in self.pairs], 'rms_z': self.rms_z,
                'p_value': self.p_value, 'factor': self.factor, 'compared': self.compared}


def scalar_estimates(effects: list[Effect]) -> dict[tuple[str, str], tuple[float, float]]:
    """Return {(axis, parameter): (value, standard error)} of the scalar parameters."""
    out = {}
    for e in effects:
        for k in SCALAR_PARAMETERS:
            se = (e.standard_error or {}).get(k)
            if k in e.parameters and se is not None and math.isfinite(se) and se > 0:
                out[e.axis, k] = (float(e.parameters[k]), float(se))
    return out


def spread_check(runs: list[dict[tuple[str, str], tuple[float, float]]], compared: str = ''
                 ) -> SpreadCheck:
    """
    Compare the parameters of several records by their combined standard errors.

    Parameters
    ----------
    runs : list of dict
        Per record :func:`estimates`; the first is the record the diagnosis reports.
    compared : str
        What the records are (for the report).

    Returns
    -------
    SpreadCheck
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
                pairs.append(SpreadPair(key[0], key[1], j, [a, b], s, (a - b) / s))
    if not pairs:
        return SpreadCheck(compared=compared)
    chi2 = sum(p.z ** 2 for p in pairs)
    rms = math.sqrt(chi2 / len(pairs))
    p = float(stats.chi2.sf(chi2, len(pairs)))
    return SpreadCheck(pairs, rms, p, rms if p < SPREAD_ALPHA and rms > 1.0 else 1.0, compared)


def standard_errors_across(res: DiagnosisResult, rec: Recording,
                           others: list[tuple[str, Recording]], robot: RobotParams,
                           progress: Progress) -> tuple[DiagnosisResult, SpreadCheck | None]:
    """
    Check the standard errors against the spread between records; widen them if it is larger.

    Time-series route: each ``--validate`` record diagnosed on its own against the fit
    record's parameters, or without such records the two halves of the record against each
    other. Returns the result (its standard errors widened where they do not hold) and the
    check (None on the experiments route, or where a record could not be diagnosed).
    """
    if res.mode != 'timeseries':
        return res, None
    if others:
        what, recs = 'the --validate records', [o for _, o in others]
        runs = [scalar_estimates(res.effects)]
    else:
        n = rec.t.size // 2
        what, runs = 'the two halves of the record', []
        recs = [Recording(rec.t[sl] - rec.t[sl][0], rec.joint_names, rec.position[sl],
                          rec.velocity[sl], rec.effort[sl], meta=dict(rec.meta))
                for sl in (slice(0, n), slice(n, None))]
    try:
        runs += [scalar_estimates(diagnose_timeseries(o, replace(robot, sample_rate=o.fs)).effects)
                 for o in recs]
    except EstimationError as err:
        progress(f'standard errors not checked across records ({what}: {err})')
        return res, None
    check = spread_check(runs, what)
    if check.rms_z is None:
        return res, check
    progress(f'standard errors against the spread between {what}: RMS of the differences '
             f'{check.rms_z:.2g} combined standard errors over {len(check.pairs)} '
             f'parameter(s) (chi-square p = {check.p_value:.2g}): '
             + (f'standard errors widened x{check.factor:.2g}' if check.factor > 1
                else 'they hold'))
    return replace(res, effects=widened(res.effects, check.factor)), check


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
