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
The entries of a diagnosis report as typed records, shared by both routes.

Each record is what report.json (docs/CONTRACT.md §7) holds under one key, and what the
console summary and the HTML report read: the held-out scores of a model (:class:`Scores`),
the route's metrics (:class:`RouteMetrics`), an axis left unexplained (:class:`Unexplained`,
with its :class:`Signature`), a candidate not taken (:class:`Rejected`) and the integrator
check (:class:`IntegratorCheck`), and a parameter the record does not determine
(:class:`NotDetermined`, on its effect). ``to_dict`` writes the report's entry, keys in the order
report.json has always had them; absent optional fields are left out.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any

from .line_cause import LineCause

__all__ = ['AxisScore', 'IntegratorCheck', 'NotDetermined', 'Rejected', 'ResonanceBand',
           'RouteMetrics', 'Scores',
           'Signature', 'Unexplained']


def _present(obj: Any, names: tuple[str, ...]) -> dict[str, Any]:
    """Return ``{name: value}`` of the fields of ``obj`` in ``names`` that are not None."""
    return {k: getattr(obj, k) for k in names if getattr(obj, k) is not None}


@dataclass(frozen=True)
class AxisScore:
    """One axis' held-out numbers of one model."""

    #: RMS over the analysed lines of 20 log10 |P_measured / P_model| [dB] (NaN: no line)
    frf_error_db: float
    #: RMS of the output error over the RMS of the measured output (docs/CONTRACT.md §7)
    time_nrmse: float
    #: time series: the share of held-out samples where the axis moves (None: experiments)
    moving_share: float | None = None
    #: experiments: the 95th percentile over the analysed lines of |20 log10 |P_measured /
    #: P_model|| [dB]: the few lines around a resonance the RMS over all lines hides
    frf_error_p95_db: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``per_axis`` entry."""
        out = {'frf_error_db': self.frf_error_db,
               'time_nrmse': self.time_nrmse}
        out.update(_present(self, ('moving_share', 'frf_error_p95_db')))
        return out


@dataclass(frozen=True)
class Scores:
    """A model's held-out numbers: pooled over the axes and per axis."""

    frf_error_db: float
    time_nrmse: float
    per_axis: dict[str, AxisScore]

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``metrics.baseline`` / ``metrics.extended`` entry."""
        return {'frf_error_db': self.frf_error_db,
                'time_nrmse': self.time_nrmse,
                'per_axis': {ax: s.to_dict() for ax, s in self.per_axis.items()}}


@dataclass(frozen=True)
class ResonanceBand:
    """The held-out FRF error of one axis in the band of a named or unexplained mode."""

    axis: str
    #: [f1, f2] Hz
    band_hz: list[float]
    #: 'second_mode' (a named mode's band) or 'unexplained' (a band the extended model leaves)
    source: str
    #: RMS over the held-out lines in the band of 20 log10 |P_measured / P_model| [dB] of the
    #: nominal and the extended model, and the 95th percentile of its magnitude over them
    nominal_db: float
    extended_db: float
    nominal_p95_db: float
    extended_p95_db: float
    #: the held-out lines in the band (multisine and chirp)
    n_lines: int

    @property
    def worse(self) -> bool:
        """Return True when the extended model is further from the record here than the nominal."""
        return self.extended_db > self.nominal_db

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``metrics.resonance_bands`` entry."""
        return {'axis': self.axis, 'band_hz': list(self.band_hz), 'source': self.source,
                'nominal_db': self.nominal_db, 'extended_db': self.extended_db,
                'nominal_p95_db': self.nominal_p95_db, 'extended_p95_db': self.extended_p95_db,
                'n_lines': self.n_lines, 'worse': self.worse}

    def text(self) -> str:
        """Return one line for people: the band's error before and after."""
        return (f'{self.axis} {self.band_hz[0]:.4g}-{self.band_hz[1]:.4g} Hz ({self.source}): '
                f'{self.nominal_db:.3g} dB (95th percentile {self.nominal_p95_db:.3g}) -> '
                f'{self.extended_db:.3g} dB ({self.extended_p95_db:.3g})'
                + (': worse with the extension' if self.worse else ''))


@dataclass(frozen=True)
class RouteMetrics:
    """The nominal and the extended model on the data held out from the fit."""

    #: the nominal model (report.json calls it ``baseline``)
    baseline: Scores
    extended: Scores
    #: which data were held out for these numbers (one sentence)
    validation: str
    #: experiments: the error in the band of every named or unexplained mode, per axis
    resonance_bands: list[ResonanceBand] = field(default_factory=list)

    @property
    def improved(self) -> bool:
        """
        Return whether the extension is an improvement on the held-out data.

        Its FRF error over all lines is not above the nominal's (or not defined) and no
        resonance band is worse: a better median that worsens a resonance is not one.
        """
        e, b = self.extended.frf_error_db, self.baseline.frf_error_db
        return not (e > b) and not any(r.worse for r in self.resonance_bands)

    def to_dict(self) -> dict[str, Any]:
        """Return the route's part of report.json ``metrics``."""
        out = {'baseline': self.baseline.to_dict(), 'extended': self.extended.to_dict(),
               'validation': self.validation}
        if self.resonance_bands:
            out['resonance_bands'] = [r.to_dict() for r in self.resonance_bands]
            out['improved'] = self.improved
        return out


@dataclass(frozen=True)
class Signature:
    """Where the misfit an unexplained entry names lives."""

    #: [f1, f2] Hz of the strongest band of the residual
    band_hz: list[float] | None = None
    #: experiments: every band where the FRF residual concentrates, strongest first
    bands_hz: list[list[float]] | None = None
    #: what the time residual correlates with: position, velocity, acceleration or time
    correlates_with: str | None = None
    #: experiments, a band of the FRF fit's residual above the noise (kind 'structure missing
    #: in the FRF'): the lines weighted by their excess [Hz]
    centre_hz: float | None = None
    #: a peak of the residual spectrum above the analysis band (time series), or the line of
    #: largest residual in a band of the FRF fit's residual (experiments)
    peak_hz: float | None = None
    half_power_width_hz: float | None = None
    peak_over_floor: float | None = None
    threshold: float | None = None
    false_alarm: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``signature`` entry."""
        return _present(self, tuple(f.name for f in fields(self)))


@dataclass(frozen=True)
class Unexplained:
    """An axis the extended model leaves clearly above its floor, or a peak above the band."""

    axis: str
    signature: Signature
    #: share of the nominal misfit above the floor that is left (None: a spectral peak)
    misfit_share: float | None = None
    #: 'resonance above the analysis band' or 'line above the analysis band' (time series);
    #: None for an axis left above its floor
    kind: str | None = None
    #: a peak above the band: locked to position or to time, with the evidence
    cause: LineCause | None = None

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``unexplained`` entry."""
        out: dict[str, Any] = {'axis': self.axis}
        out.update(_present(self, ('kind', 'misfit_share')))
        out['signature'] = self.signature.to_dict()
        if self.cause is not None:
            out['cause'] = self.cause.to_dict()
        return out


#: the numbers a rejected candidate may carry, in the order report.json writes them
_REJECTED_NUMBERS = ('misfit_share_removed', 'p_value', 'residual_share', 'held_out_gain',
                     'forward_share', 'fitted_value')


@dataclass(frozen=True)
class Rejected:
    """A candidate effect that was fitted or considered but not taken, and why."""

    name: str
    axis: str
    #: the parameter values it was fitted with (model-file keys; None: not fitted)
    parameters: dict[str, Any] | None = None
    #: why a rule, not only a number, rejected it (one sentence; None: its numbers say it)
    reason: str | None = None
    #: experiments: the share of its axis' misfit it removed (taken above a threshold)
    misfit_share_removed: float | None = None
    #: time series: F-test p value, share of the residual it explains, held-out gain
    p_value: float | None = None
    residual_share: float | None = None
    held_out_gain: float | None = None
    #: time series: the share of the axis' moving samples with positive velocity
    forward_share: float | None = None
    #: time series: the value a joint fit gave it outside the physical range
    fitted_value: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``rejected`` entry."""
        out: dict[str, Any] = {'name': self.name, 'axis': self.axis}
        out.update(_present(self, _REJECTED_NUMBERS + ('parameters', 'reason')))
        return out

    def numbers(self) -> str:
        """Return its numbers as one short text for people ('' without any)."""
        return ', '.join(f'{k.replace("_", " ")} {getattr(self, k):.3g}'
                         for k in _REJECTED_NUMBERS if getattr(self, k) is not None)


@dataclass(frozen=True)
class IntegratorCheck:
    """Whether the plant's integrator step is fine enough for the record (experiments)."""

    axes: list[str]
    #: the model's ``simulation.substeps``
    substeps: int
    #: held-out misfit per axis (noise floors) at ``substeps`` and at twice as many
    held_out_misfit: list[float]
    held_out_misfit_double_substeps: list[float]
    #: the axes whose misfit moved by more than the noise allows: simulated too coarsely
    too_coarse: list[str] = field(default_factory=list)
    #: the substeps the extended model is written (and scored) with: ``substeps``, doubled
    #: while doubling lowers the held-out misfit of every axis it moves (at most MAX_SUBSTEPS)
    written_substeps: int = 0
    #: whether doubling ``written_substeps`` once more moves no axis beyond the noise
    settled: bool = True

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``discretisation`` entry."""
        return {'axes': list(self.axes), 'substeps': self.substeps,
                'held_out_misfit': list(self.held_out_misfit),
                'held_out_misfit_double_substeps': list(self.held_out_misfit_double_substeps),
                'too_coarse': list(self.too_coarse),
                'written_substeps': self.written_substeps or self.substeps,
                'settled': self.settled}

    def verdict(self) -> str:
        """Return what the check found and did, as one sentence."""
        if not self.too_coarse:
            return 'within the noise on every axis.'
        return (f'{", ".join(self.too_coarse)} simulated too coarsely for this record at '
                f'{self.substeps} substeps: extended_model.yaml is written, and its held-out '
                f'metrics taken, with simulation.substeps = {self.written_substeps}'
                + (' (doubling it again moves no axis beyond the noise).' if self.settled else
                   ' (doubling it again no longer lowers the misfit of every axis it moves: '
                   "the rest of the misfit is not the integrator's alone)."))


@dataclass(frozen=True)
class NotDetermined:
    """A parameter of a named effect that the record does not determine (``not_determined``)."""

    #: the model-file key ('viscous_friction'; 'torque_ripple amplitude' for a term's field)
    parameter: str
    #: [lo, hi] the values its refits took and its value +- 2 standard errors (model units;
    #: report.json ``range``)
    value_range: list[float]
    #: why: its standard error is too large a share of its value, or its refits disagree
    reason: str
    #: the experiment that would determine it ('a slower multisine or ...')
    experiment: str

    def to_dict(self) -> dict[str, Any]:
        """Return the report's ``not_determined`` entry."""
        return {'parameter': self.parameter,
                'range': [float(f'{x:.6g}') for x in self.value_range],
                'reason': self.reason, 'experiment': self.experiment}
