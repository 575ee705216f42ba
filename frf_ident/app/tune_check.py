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
A velocity controller (PI and filters per axis) checked on every pose of a campaign.

Per pose: the margins ``loop`` reports (python-control's ``stability_margins`` on the FRD
data, :func:`frf_ident.app.loop.margins`), the MIMO sensitivity peak, and Nyquist's count on
the band (:func:`frf_ident.core.loop.frd_margins.frd_margins`: is the loop stable, does the
band hold its crossover). Standard deviations (nominal pose) come from draws of its FRF from
its variance as in ``loop``, their margins read off the lines by ``frd_margins`` (vectorised:
python-control takes ~50 ms a loop, 150 a check; the two agree to the line spacing,
test/core/loop/test_frd_margins.py). With uncertainty weights, the robust test on the
nominal pose: max |W T_0| and the worst modulus margin over the uncertainty set,
min (|1 + L_0| - |W L_0|).
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.app.loop import margins
from frf_ident.app.tune_inputs import Campaign
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.loop.check import (AxisMargins, draw_responses, edge_gain_db, loop_response,
                                       LoopCheck, Margin, pi_response, sensitivity_peak)
from frf_ident.core.loop.frd_margins import frd_margins, FrdMargins
from frf_ident.core.loop.targets import TuneTargets
import numpy as np

__all__ = ['ControllerCheck', 'RobustTest', 'check_controller', 'check_pose', 'target_verdicts']


@dataclass(frozen=True)
class RobustTest:
    """
    Robust stability of one axis' nominal loop against its uncertainty weight.

    Attributes
    ----------
    peak : float
        max over the lines of |W T_0| (robustly stable when < 1).
    frequency_hz : float
        Where it peaks [Hz].
    modulus_margin : float
        min (|1 + L_0| - |W L_0|): the smallest modulus margin of any plant in the set.

    """

    peak: float
    frequency_hz: float
    modulus_margin: float


@dataclass
class ControllerCheck:
    """
    One controller on every pose.

    Attributes
    ----------
    kp, ki : ndarray, shape (n_axes,)
        PI gains.
    filters : ndarray of complex, shape (n_axes, n_freq), or None
        Response of each axis' filters.
    checks : list of LoopCheck
        Per pose, what ``loop`` reports (standard deviations on the nominal pose only).
    nyquist : list of FrdMargins
        Per pose, the margins read off the lines with the stability count (per axis).
    robust : list of RobustTest or None
        Per axis, with weights.
    nominal : int
        Index of the nominal pose.

    """

    kp: np.ndarray
    ki: np.ndarray
    filters: np.ndarray | None
    checks: list[LoopCheck]
    nyquist: list[FrdMargins]
    robust: list[RobustTest] | None
    nominal: int

    def values(self, j: int, name: str) -> np.ndarray:
        """Return margin ``name`` of axis j at every pose (NaN where not available)."""
        return np.array([getattr(c.axes[j], name).value for c in self.checks], dtype=float)

    def worst(self, j: int, name: str) -> tuple[float, int]:
        """Return the smallest margin ``name`` of axis j over the poses and its pose index."""
        v = self.values(j, name)
        if name == 'gain_margin_db':
            v = np.where(np.isnan(v), np.inf, v)
        k = int(np.nanargmin(np.where(np.isnan(v), np.inf, v))) if np.isfinite(v).any() \
            else self.nominal
        return float(v[k]), k

    def stable(self, j: int) -> np.ndarray:
        """Return per pose whether axis j's loop is stable with its crossover in the band."""
        return np.array([bool(n.stable[j] and n.in_band[j]) for n in self.nyquist])

    def peak_sensitivity(self) -> np.ndarray:
        """Return the MIMO sensitivity peak at every pose (NaN for one axis)."""
        return np.array([np.nan if c.peak_sensitivity is None else c.peak_sensitivity.value
                         for c in self.checks])


def _sd(x: np.ndarray) -> float:
    ok = x[np.isfinite(x)]
    return float(ok.std(ddof=1)) if ok.size > 2 else float('nan')


def check_pose(frf: FrequencyResponse, channels, kp: np.ndarray, ki: np.ndarray,
               controller: np.ndarray, dt: float, draws: int = 0, seed: int = 0
               ) -> tuple[LoopCheck, FrdMargins]:
    """
    Check one pose: the reported margins, their standard deviations, Nyquist's count.

    Parameters
    ----------
    frf : FrequencyResponse
        The pose's FRF.
    channels : list of tuple
        (axis, output, input) of every axis.
    kp, ki : ndarray
        PI gains (for the labels).
    controller : ndarray of complex, shape (n_axes, n_freq)
        C_i = PI_i F_i at the lines.
    dt : float
        Controller sample time [s] (recorded in the check).
    draws : int, optional
        Draws of the FRF for the standard deviations (0: none).
    seed : int, optional
        Seed of the draws.

    Returns
    -------
    LoopCheck
        Per-axis margins (python-control) with standard deviations, the MIMO peak.
    FrdMargins
        The margins read off the lines with the stability count, per axis.

    """
    loops = np.stack([frf.response[o, i] * controller[j] for j, (_, o, i) in enumerate(channels)])
    nominal = margins(loops, frf.omega)
    var = frf.variance()
    sds = np.full((len(channels), 4), np.nan)
    drawn = None
    if var is not None and draws > 0:
        drawn = draw_responses(frf.response, var, draws, np.random.default_rng(seed))
        m = frd_margins(np.stack([drawn[:, o, i] * controller[j]
                                  for j, (_, o, i) in enumerate(channels)], axis=1), frf.freq_hz)
        for q, name in enumerate(('gain_margin_db', 'phase_margin_deg', 'crossover_hz',
                                  'modulus_margin')):
            sds[:, q] = [_sd(getattr(m, name)[:, j]) for j in range(len(channels))]
    edge = edge_gain_db(loops)
    band = (float(frf.freq_hz.min()), float(frf.freq_hz.max()))
    axes = [AxisMargins(a, float(kp[j]), float(ki[j]),
                        *[Margin(float(nominal[j, q]), float(sds[j, q])) for q in range(4)],
                        band_hz=band, edge_gain_db=float(edge[j]))
            for j, (a, _, _) in enumerate(channels)]
    peak = None
    if len(channels) > 1 and frf.noutputs == frf.ninputs:
        c = controller[np.argsort([i for _, _, i in channels])]
        value = float(sensitivity_peak(loop_response(frf.response, c)))
        sd = float('nan') if drawn is None else _sd(sensitivity_peak(loop_response(drawn, c)))
        peak = Margin(value, sd)
    return (LoopCheck(axes, peak, 0 if drawn is None else draws, dt),
            frd_margins(loops, frf.freq_hz))


def check_controller(camp: Campaign, kp: np.ndarray, ki: np.ndarray, dt: float,
                     filters: np.ndarray | None = None, weights: list[np.ndarray] | None = None,
                     draws: int = 0) -> ControllerCheck:
    """
    Check a PI (with filters) at every pose of a campaign.

    Parameters
    ----------
    camp : Campaign
        The FRFs.
    kp, ki : array_like, shape (n_axes,)
        PI gains (discrete PI at ``dt``).
    dt : float
        Controller sample time [s].
    filters : ndarray of complex, shape (n_axes, n_freq), optional
        Each axis' filter response.
    weights : list of ndarray, optional
        |W| of every axis at the lines (the robust test).
    draws : int, optional
        Draws of the nominal pose's FRF for the standard deviations.

    Returns
    -------
    ControllerCheck
        The checks.

    """
    kp, ki = np.asarray(kp, float), np.asarray(ki, float)
    f = camp.freq_hz
    c = np.stack([pi_response(f, p, i, dt) for p, i in zip(kp, ki)])
    if filters is not None:
        c = c * filters
    checks, nyq = [], []
    for k, frf in enumerate(camp.frfs):
        chk, m = check_pose(frf, camp.channels, kp, ki, c, dt,
                            draws if k == camp.nominal else 0)
        checks.append(chk)
        nyq.append(m)
    robust = None
    if weights is not None:
        robust = []
        f0 = camp.frfs[camp.nominal]
        for j, (_, o, i) in enumerate(camp.channels):
            lo = f0.response[o, i] * c[j]
            wt = np.abs(weights[j] * lo / (1 + lo))
            q = int(np.argmax(wt))
            robust.append(RobustTest(float(wt[q]), float(f[q]),
                                     float(np.min(np.abs(1 + lo) - np.abs(weights[j] * lo)))))
    return ControllerCheck(kp, ki, filters, checks, nyq, robust, camp.nominal)


def target_verdicts(check: ControllerCheck, j: int, targets: TuneTargets
                    ) -> dict[str, dict[str, float | bool | int | None]]:
    """
    Return per target of axis j the worst value over the poses, where, and whether it is met.

    Parameters
    ----------
    check : ControllerCheck
        The controller on the poses.
    j : int
        The axis.
    targets : TuneTargets
        What to meet.

    Returns
    -------
    dict
        ``{target: {"value", "pose", "met"}}`` for the phase, gain and modulus margins (the
        reported python-control values), ``stability`` (value: poses unstable or crossing
        outside the band) and, with weights, ``robust`` (value: max |W T_0|).

    """
    out: dict[str, dict[str, float | bool | int | None]] = {}
    for name in ('phase_margin_deg', 'gain_margin_db', 'modulus_margin'):
        v, k = check.worst(j, name)
        out[name] = {'value': v if np.isfinite(v) else None, 'pose': k,
                     'met': bool(np.isfinite(v) and v >= getattr(targets, name)
                                 or (name == 'gain_margin_db' and v == np.inf))}
    ok = check.stable(j)
    out['stability'] = {'value': int((~ok).sum()), 'pose': int(np.argmin(ok)) if not ok.all()
                        else None, 'met': bool(ok.all())}
    if check.robust is not None:
        r = check.robust[j]
        out['robust'] = {'value': r.peak, 'pose': check.nominal,
                         'met': bool(r.peak < 1.0) or not targets.robust}
    return out
