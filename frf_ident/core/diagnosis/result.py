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
Hold the one result type of both diagnosis routes.

:class:`DiagnosisResult` is what :func:`.experiments.pipeline.diagnose_experiments` and
:func:`.timeseries.pipeline.diagnose_timeseries` return, what ``frf-ident diagnose`` writes into
report.json (docs/CONTRACT.md §7) and what the HTML report draws. The route's own data for the
figures sit in ``detail`` (:class:`ExperimentsDetail` or :class:`TimeseriesDetail`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
import numpy as np

from .band import AnalysisBand
from .common import Effect
from .records import IntegratorCheck, Rejected, RouteMetrics, Unexplained


@dataclass
class ExperimentsDetail:
    """What the experiments route keeps for the figures and the benchmarks."""

    #: the recording's evaluator (:class:`.experiments.evaluator.Evaluator`; simulations,
    #: noise floors)
    evaluator: Any
    #: FRF estimates of the held-out part: 'measured', 'nominal', 'extended' -> {design: FRD}
    estimates: dict[str, dict[str, Any]]
    #: closed-loop simulations of the nominal and extended model: 'nominal', 'extended'
    sims: dict[str, Recording]
    #: held-out misfit per axis (noise floors) of the nominal ('baseline': with the sensor
    #: the record shows, :mod:`.sensor`) and extended model, and of the model file as given
    #: where the record's sensor changed it ('without_sensor')
    misfit: dict[str, list[float]]
    #: the held-out check's gain test per effect it judged, 'name@axis' ->
    #: :class:`.experiments.noise_gain.HeldOutGain`
    held_out_gains: dict[str, Any] = field(default_factory=dict)


@dataclass
class ResidualTrace:
    """The time-series route's residuals between samples, for the figures."""

    #: [s] time of the rows, shape (N-1,)
    t: np.ndarray
    #: inverse-dynamics residual of the nominal model, shape (N-1, n)
    f: np.ndarray
    #: positions, velocities between samples, shape (N-1, n)
    q: np.ndarray
    v: np.ndarray
    #: the torque the nominal and the extended model predict (low-passed residual removed)
    pred_baseline: np.ndarray
    pred_extended: np.ndarray
    #: the held-out rows, shape (N-1,)
    val_mask: np.ndarray


@dataclass
class TimeseriesDetail:
    """What the time-series route keeps for the figures."""

    residual: ResidualTrace
    #: per axis the NRMSE^2 torque noise alone leaves on the held-out rows
    noise_floor_nrmse2: list[float]


@dataclass
class DiagnosisResult:
    """
    The diagnosis of one record against a nominal model (docs/CONTRACT.md §7).

    Attributes
    ----------
    mode : str
        'experiments' (FRF and closed-loop simulation evidence) or 'timeseries'.
    effects : list of Effect
        The named effects, strongest first.
    rejected : list of dict
        Candidates not taken, with their numbers (report.json ``rejected``).
    unexplained : list of dict
        Axes whose held-out misfit stays clearly above noise, with their signature; and
        (time-series route) resonances in the residual above the analysis band, ``kind``
        'resonance above the analysis band' with the ``band_hz`` of each
        (:mod:`.timeseries.resonance`).
    metrics : dict
        ``baseline`` (nominal model), ``extended``, ``validation`` text; the app adds
        ``validation_records`` and ``least_squares``.
    extended : RobotParams
        The nominal model with the effects written in.
    discretisation : dict or None
        The simulation-step check (experiments route); None without simulation.
    n_sims : int
        Closed-loop simulations of the recorded excitation (0 for the time-series route).
    detail : ExperimentsDetail or TimeseriesDetail
        The route's data for the figures.
    fit_rows, held_out_rows : ndarray of bool, shape (N-1,)
        The rows (between samples) the route fitted on and held out; the least-squares
        baseline (:mod:`.crosscheck.baseline`) is fitted and judged on the same.

    """

    mode: str
    effects: list[Effect]
    rejected: list[Rejected]
    unexplained: list[Unexplained]
    metrics: RouteMetrics
    extended: RobotParams
    detail: ExperimentsDetail | TimeseriesDetail
    fit_rows: np.ndarray
    held_out_rows: np.ndarray
    discretisation: IntegratorCheck | None = None
    n_sims: int = 0
    #: the candidates that were not taken (experiments route; their rejected entries)
    candidates: list[Effect] = field(default_factory=list)
    #: the band the effects were fitted in (time-series route, :func:`.band.analysis_band`);
    #: None where the route does not choose one (experiments: FC_HZ)
    band: AnalysisBand | None = None
