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
Where the model's structure is missing: the frequency-domain fit's residual, line by line.

The multisine estimate of the record (the estimate with a variance) is divided by the same
estimate of a model's simulation, axis by axis (:class:`~frf_ident.core.fit.link_mode.RatioData`):
the estimator's and the sampling's share cancels, and for the right model the ratio is 1 up
to the noise. Its standard deviation is the measured FRF's: the larger of its total variance
(over the realisations: noise and nonlinear distortion) and its noise variance (over the
periods), each averaged over NOISE_SMOOTH_LINES lines each side. A variance from two
realisations has two degrees of freedom per line; the noise spectrum is smooth, |P| is not.

- :func:`read_structure` (stage 0): every axis' inertias, stiffness and damping fitted to the
  ratio of the nominal model (:func:`~frf_ident.core.fit.link_mode.fit_linear_ratio`) and
  the residual tested line by line, in bands of neighbouring lines and for whiteness
  (:func:`~frf_ident.core.fit.residual_whiteness.residual_test`). A band of at least
  MODE_MIN_LINES lines above the noise marks where the structure is missing: no parameter
  change explains it. A parameter mismatch is named only on an axis whose residual is white;
  a second mode is fitted in the band (:mod:`.second_mode`).
- :func:`model_bands` (closing stages): the same test against the extended model: what it
  leaves of stage 0's bands that no linear parameter change removes (a mismatch that leaves
  a band is withdrawn; a band nothing fills is reported unexplained, with its centre, width
  and peak).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from frf_ident.core.fit.link_mode import fit_linear_ratio, LinearRatioFit, RatioData
from frf_ident.core.fit.residual_whiteness import residual_test, ResidualBand, ResidualTest
from frf_ident.core.model.params import RobotParams
import numpy as np

from ..mode_thresholds import MODE_LEFT_SHARE, MODE_MIN_LINES, NOISE_SMOOTH_LINES

__all__ = ['StructureReading', 'model_bands', 'ratio_data', 'read_structure', 'structural']


def structural(test: ResidualTest) -> list[ResidualBand]:
    """Return the bands of a residual test that span at least MODE_MIN_LINES lines."""
    return [b for b in test.bands if b.n_lines >= MODE_MIN_LINES]


@dataclass
class StructureReading:
    """Stage 0's reading of where the nominal model's structure is missing."""

    #: the record's multisine FRF over the nominal simulation's, with its noise
    data: RatioData
    #: every axis' linear parameters fitted to it
    linear: LinearRatioFit
    #: the residual test of each axis' channel after the linear fit
    tests: list[ResidualTest]

    def white(self, axis: int) -> bool:
        """Tell whether the linear fit leaves only noise in the axis' residual: nothing missing."""
        return self.tests[axis].white

    def bands(self, axis: int) -> list[ResidualBand]:
        """Return the axis' bands of at least MODE_MIN_LINES lines, strongest first."""
        return structural(self.tests[axis])

    def text(self, names: list[str]) -> str:
        """Return one line for the trace: every axis' verdict."""
        return '; '.join(f'{a}: {t.summary()}' for a, t in zip(names, self.tests))


def _smoothed(var: np.ndarray) -> np.ndarray:
    """Return the running mean over NOISE_SMOOTH_LINES lines each side (shorter at the ends)."""
    k = np.ones(2 * NOISE_SMOOTH_LINES + 1)
    return np.convolve(var, k, 'same') / np.convolve(np.ones_like(var), k, 'same')


def ratio_data(meas: dict[str, Any], est: dict[str, Any], n: int) -> RatioData | None:
    """
    Return the multisine FRF of the record over a model's, with its noise (None without).

    Parameters
    ----------
    meas : dict
        The record's estimates ('multisine' with a variance is used).
    est : dict
        The same estimates of the model's simulation.
    n : int
        The axes (the square n x n part of the estimates).

    Returns
    -------
    RatioData or None
        The diagonal ratio and its standard deviation; None where the record has no multisine
        estimate with a positive variance, or the model's estimate is missing.

    """
    pm, ps = meas.get('multisine'), est.get('multisine')
    if pm is None or ps is None or min(np.shape(pm.response)[:2]) < n:
        return None
    idx = np.arange(n)
    found = [v[idx, idx] for v in (pm.total_variance, pm.noise_variance) if v is not None]
    if not found or not all(np.all(np.isfinite(v) & (v > 0)) for v in found):
        return None
    sim = ps.response[idx, idx]
    var = np.max([[_smoothed(v) for v in x] for x in found], axis=0)
    sigma = np.sqrt(var) / np.abs(sim)
    return RatioData(np.asarray(pm.freq_hz, dtype=float), pm.response[idx, idx] / sim, sigma)


def read_structure(meas: dict[str, Any], sim_est: dict[str, Any], robot: RobotParams
                   ) -> StructureReading | None:
    """
    Fit the linear parameters to the record against the nominal model and test the residual.

    Parameters
    ----------
    meas, sim_est : dict
        The record's estimates and the same of the nominal model's simulation.
    robot : RobotParams
        The nominal model.

    Returns
    -------
    StructureReading or None
        The ratio, the linear fit and each axis' residual test; None without a multisine
        estimate with a variance (no test is possible: nothing is withheld for it).

    """
    data = ratio_data(meas, sim_est, robot.n_axes)
    if data is None:
        return None
    linear = fit_linear_ratio(robot, data)
    return StructureReading(data, linear, [residual_test(data.freq_hz, e)
                                           for e in linear.residual])


def model_bands(meas: dict[str, Any], est: dict[str, Any], model: RobotParams,
                asked: StructureReading | None) -> list[list[ResidualBand]]:
    """
    Return per axis the bands of missing structure stage 0 found and a model still leaves.

    The ratio of the record's multisine FRF to the model's simulated one, with every axis'
    linear parameters refitted to it (:func:`read_structure` against ``model``): a nonlinear
    effect named a percent off (a stiffening gear's k2) shifts the estimate as a stiffness
    does, and is not missing structure; a resonance the model lacks stays. Only bands that
    overlap one of stage 0's on the same axis and keep MODE_LEFT_SHARE of its statistic
    count: an axis the nominal model's linear parameters already leave white lacks no
    structure, whatever an extension's nonlinear effect does to the multisine (the demo bag's
    joint_2: white at stage 0, a band of 6.8 x the noise over 7 lines around its resonance
    with the stiffening gear named 1 % off), and a named mode a few per mille off leaves a
    trace of its band, not the band (the 22 Hz mode of damping ratio 0.005: 9,400 x the
    noise over 53 lines at stage 0, 4.5 x over 10 with the mode named).

    Parameters
    ----------
    meas, est : dict
        The record's estimates and the same of the model's simulation (the fit part: its
        multisine variance holds the nonlinear distortions, a single held-out realisation's
        only the noise).
    model : RobotParams
        The model (its linear part and second modes are refitted around).
    asked : StructureReading or None
        Stage 0's reading; None (no stage 0, no multisine variance): no band is returned.

    Returns
    -------
    list of list of ResidualBand
        Per axis its bands, strongest first.

    """
    reading = read_structure(meas, est, model) if asked is not None else None
    if reading is None:
        return [[] for _ in range(model.n_axes)]
    return [[b for b in reading.bands(i)
             if any(b.lo_hz <= a.hi_hz and a.lo_hz <= b.hi_hz
                    and b.statistic >= MODE_LEFT_SHARE * a.statistic for a in asked.bands(i))]
            for i in range(model.n_axes)]
