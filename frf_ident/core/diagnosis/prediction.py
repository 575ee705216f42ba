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
Predict the torque of a model file from measured motion: metrics, noise floor, signature.

``time_nrmse`` and ``frf_error_db`` of the time-series route (docs/CONTRACT.md §7) for any
record of the robot, the NRMSE^2 torque noise alone leaves, and where a residual lives.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
import numpy as np
from scipy import signal

from .common import bridge_gaps
from .records import AxisScore, Scores, Signature
from .regressors import model_residual, moving
from .residual import lowpass
from .thresholds import EDGE, FC_HZ

__all__ = ['default_mask', 'noise_floor', 'noise_level', 'predict_metrics', 'Prediction',
           'signature', 'torque_metrics']


@dataclass
class Prediction:
    """A model's torque prediction on a record: its scores, residual and compared rows."""

    scores: Scores
    #: measured minus predicted torque, low-passed, between samples, shape (N-1, n)
    residual: np.ndarray
    #: per axis the rows the scores were taken over (in the mask, not bridged, moving)
    rows: np.ndarray


def noise_floor(rec: Recording, f: np.ndarray, fc: float, use: np.ndarray | None = None
                ) -> np.ndarray:
    """
    Return per axis the NRMSE^2 that torque noise alone leaves.

    Per axis NRMSE^2 that torque noise alone leaves after the fc low-pass: the white level
    of the residual (:func:`noise_level`) times the bandwidth fc, over the variance of the
    low-passed torque on the rows the NRMSE is taken over.

    Parameters
    ----------
    rec : Recording
        The recording.
    f : ndarray, shape (N-1, n)
        The model's torque residual (:func:`model_residual`).
    fc : float
        Low-pass cut-off of the metric [Hz].
    use : ndarray of bool, shape (N-1, n), optional
        Per axis the rows the NRMSE is taken over (``rows`` of :func:`predict_metrics`); all
        rows if omitted.

    Returns
    -------
    ndarray, shape (n,)
        The floor per axis.

    """
    fs = rec.fs
    level = noise_level(f, fs)
    uf = lowpass(rec.effort[:-1], fs, fc)
    var_u = np.array([np.var(uf[use[:, i], i]) if use is not None and use[:, i].sum() > 1
                      else np.var(uf[:, i]) for i in range(uf.shape[1])])
    return level * min(fc, fs / 2) / np.maximum(var_u, 1e-300)


def noise_level(f: np.ndarray, fs: float) -> np.ndarray:
    """
    Return per axis the white torque-noise level of a residual [torque^2 / Hz].

    The median one-sided power spectral density (Welch) between 0.6 and 0.95 of the Nyquist
    frequency, where the motion leaves little; a white noise of standard deviation sigma has
    the level 2 sigma^2 / fs.

    Parameters
    ----------
    f : ndarray, shape (N, n)
        A torque residual (:func:`model_residual`).
    fs : float
        Sample rate [Hz].

    Returns
    -------
    ndarray, shape (n,)
        The level per axis (zeros when the record is too short to have that band).

    """
    nper = int(min(2 ** int(math.log2(max(f.shape[0] // 8, 64))), 4096))
    fr, p = signal.welch(f, fs=fs, nperseg=nper, axis=0)
    sel = (fr > 0.6 * fs / 2) & (fr < 0.95 * fs / 2)
    return np.median(p[sel], axis=0) if sel.any() else np.zeros(f.shape[1])


def signature(res: np.ndarray, q, v, a, t, mask, fs, fc) -> Signature:
    """
    Return where a held-out residual lives (band and correlated signal).

    Where a held-out residual lives: the band [f1, f2] Hz holding the middle half of its
    power (quartiles below fc) and the signal it correlates with most (|r| >= 0.3).
    """
    band = None
    r = res[mask]
    if r.size >= 64:
        nper = int(min(2 ** int(math.log2(r.size // 4)), 4096))
        fr, p = signal.welch(r, fs=fs, nperseg=nper)
        sel = (fr > 0) & (fr <= fc)
        if sel.any() and p[sel].sum() > 0:
            c = np.cumsum(p[sel]) / p[sel].sum()
            fsel = fr[sel]
            df = float(fr[1] - fr[0])      # a spectral line stands for its bin's width
            band = [round(max(float(fsel[np.searchsorted(c, 0.25)]) - df, 0.0), 2),
                    round(float(fsel[min(np.searchsorted(c, 0.75), fsel.size - 1)]) + df, 2)]
    best, rb = None, 0.3
    rr = r - r.mean()
    for name, x in (('position', q), ('velocity', v), ('acceleration', a), ('time', t)):
        xm = x[mask] - x[mask].mean()
        den = math.sqrt(float(xm @ xm) * float(rr @ rr))
        c = abs(float(xm @ rr)) / den if den > 0 else 0.0
        if c >= rb:
            best, rb = name, c
    return Signature(band_hz=band, correlates_with=best)


def predict_metrics(rec: Recording, robot: RobotParams, *, fc: float = FC_HZ,
                    mask: np.ndarray | None = None) -> Prediction:
    """
    Return held-out metrics of a model file on a recording.

    Held-out metrics of a model file on a recording: the torque the model predicts from
    the measured motion against the measured torque (both low-passed at fc), on ``mask``
    (between samples, N-1; default all but the ends), never on rows bridged over a gap
    (:func:`.common.bridge_gaps`).

    Parameters
    ----------
    rec : Recording
        The record (any record of the robot, not necessarily the one fitted).
    robot : RobotParams
        The model file's robot (nominal or extended).
    fc : float
        Low-pass cut-off of torques and residual [Hz].
    mask : ndarray of bool, shape (N-1,), optional
        The samples (between samples) the metrics are computed on.

    Returns
    -------
    Prediction
        The scores (``frf_error_db``, ``time_nrmse``, per axis), the residual (measured minus
        predicted torque, low-passed) and per axis the rows the scores were taken over.

    """
    rec, lost = bridge_gaps(rec)
    f, _, vh, _ = model_residual(rec, robot)
    return torque_metrics(rec, lost, lowpass(f, rec.fs, fc), robot.joint_names, fc=fc,
                          mask=mask)


def default_mask(n_rows: int) -> np.ndarray:
    """Return the rows (between samples) compared by default: all but EDGE at both ends."""
    N = n_rows + 1
    mask = np.zeros(N - 1, bool)
    mask[int(EDGE * N):N - 1 - int(EDGE * N)] = True
    return mask


def torque_metrics(rec: Recording, lost: np.ndarray, ff: np.ndarray, names: list[str], *,
                   fc: float = FC_HZ, mask: np.ndarray | None = None) -> Prediction:
    """
    Return the §7 metrics of a torque prediction given as its low-passed residual.

    The one definition of ``time_nrmse`` and ``frf_error_db`` of the time-series route, for
    any predictor (a model file through :func:`predict_metrics`, the least-squares baseline
    of :mod:`.crosscheck.baseline`): on ``mask`` minus the bridged rows, per axis only where it
    moves (at rest static friction holds any torque).

    Parameters
    ----------
    rec : Recording
        The gap-bridged record.
    lost : ndarray of bool, shape (N,)
        Its bridged rows (:func:`.common.bridge_gaps`).
    ff : ndarray, shape (N-1, n)
        Measured minus predicted torque, low-passed at ``fc``, between samples.
    names : list of str
        The axes' names.
    fc : float
        Low-pass cut-off [Hz].
    mask : ndarray of bool, shape (N-1,), optional
        The rows compared (default :func:`default_mask`).

    Returns
    -------
    Prediction
        As :func:`predict_metrics`.

    """
    fs = rec.fs
    vh = 0.5 * (rec.velocity[1:] + rec.velocity[:-1])
    if mask is None:
        mask = default_mask(rec.t.size - 1)
    use = (mask & ~(lost[1:] | lost[:-1]))[:, None] & moving(vh, rec.velocity, fs, fc)
    uf = lowpass(rec.effort[:-1], fs, fc)
    u_model = uf - ff
    per = {}
    err2, var2 = 0.0, 0.0
    for i, name in enumerate(names):
        m = use[:, i]
        e = ff[m, i]
        du = uf[m, i] - uf[m, i].mean() if m.any() else np.zeros(0)
        err2, var2 = err2 + float(e @ e), var2 + float(du @ du)
        per[name] = AxisScore(
            round(_frf_error(rec.velocity[:-1][m][:, [i]], uf[m][:, [i]], u_model[m][:, [i]],
                             fs), 4),
            round(math.sqrt(float(e @ e) / max(float(du @ du), 1e-300)), 5),
            moving_share=round(float(m.sum()) / max(int(mask.sum()), 1), 3))
    rows = use.any(axis=1)
    scores = Scores(round(_frf_error(rec.velocity[:-1][rows], uf[rows], u_model[rows], fs), 4),
                    round(math.sqrt(err2 / max(var2, 1e-300)), 5), per)
    return Prediction(scores, ff, use)


def _frf_error(v: np.ndarray, u_meas: np.ndarray, u_model: np.ndarray, fs: float) -> float:
    """Return the RMS dB difference of the Welch H1 estimates u_meas -> v and u_model -> v."""
    out = []
    nper = int(min(2 ** int(math.log2(max(v.shape[0] // 4, 64))), 4096))
    for i in range(v.shape[1]):
        fr, pm = signal.csd(u_meas[:, i], v[:, i], fs=fs, nperseg=nper)
        _, uu = signal.welch(u_meas[:, i], fs=fs, nperseg=nper)
        _, pmod = signal.csd(u_model[:, i], v[:, i], fs=fs, nperseg=nper)
        _, mm = signal.welch(u_model[:, i], fs=fs, nperseg=nper)
        _, coh = signal.coherence(u_meas[:, i], v[:, i], fs=fs, nperseg=nper)
        sel = (coh > 0.5) & (fr > 0) & (fr < 20)
        if sel.any():
            out.append(20 * np.log10(np.abs((pm[sel] / uu[sel]) / (pmod[sel] / mm[sel]))))
    v_ = np.concatenate(out) if out else np.array([np.nan])
    return float(np.sqrt(np.mean(v_ ** 2)))
