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
The noise the record's repeated multisine periods show.

The raw material of the noise floors every misfit of :class:`.evaluator.Evaluator` is
measured in: velocity and torque noise variance per axis, how much weaker the held-out chirp
iteration is than the one fitted (what an encoder's repeating quantisation error adds:
:mod:`.quantisation_floor`).
"""
from __future__ import annotations

from typing import Any

from frf_ident.core.estimation.chirp_estimate import chirp_input_power
from frf_ident.core.recording import Recording
import numpy as np

__all__ = ['held_out_chirp_scale', 'period_noise']


def period_noise(rec: Recording, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the noise variance of velocity and effort per axis from the multisine periods.

    Noise variance of velocity and effort per axis measured from the multisine periods:
    half the mean square difference of consecutive steady-state periods (periodic signal
    cancels, noise doubles). NaN where the recording has no repeated periods.
    """
    dv, du = [], []
    for s in rec.segments:
        info = s.info
        if info.get('design') != 'multisine' or int(info.get('periods', 0)) < 2:
            continue
        P = int(info.get('period_samples', 0))
        sl = rec.slice(s.t_start, s.t_end)
        k0 = sl.start + P * int(info.get('transient_periods', 0))
        k1 = min(sl.stop, sl.start + P * (int(info.get('transient_periods', 0))
                                          + int(info['periods'])))
        if P < 2 or k1 - k0 < 2 * P or not mask[k0:k1].all():
            continue
        dv.append(rec.velocity[k0 + P:k1] - rec.velocity[k0:k1 - P])
        du.append(rec.effort[k0 + P:k1] - rec.effort[k0:k1 - P])
    n = rec.velocity.shape[1]
    if not dv:
        return np.full(n, np.nan), np.full(n, np.nan)
    return (0.5 * np.mean(np.concatenate(dv) ** 2, axis=0),
            0.5 * np.mean(np.concatenate(du) ** 2, axis=0))


def held_out_chirp_scale(fit: Recording, val: Recording, fitted: Any) -> np.ndarray:
    """
    Return per axis how many times noisier the held-out chirp estimate is than the fitted one.

    The chirp has no noise variance of its own: its floor is the multisine's relative noise,
    taken to hold for the chirp iteration fitted (the one at the desired torque). The
    iteration held out is the one before, which may be far weaker (the first runs at
    ``r_initial``: on the UR5e scene of test/app/test_diagnose_mjcf.py 1/60 of the fitted
    torque, where even the true model sat 84 floors off). In closed loop the plain estimate
    Y U^-1 errs by the measurement noise over the input's excerpt spectrum, so a line's
    noise relative to the response is x_f = f / (|P_f|^2 power_f): the input's effective
    power there (:func:`...estimation.chirp_estimate.chirp_input_power`), the response's
    magnitude, and f because every excerpt spans a fixed number of periods (1/f long:
    white noise's share grows with f). The held-out iteration's line has r_f =
    power_fit / power_held times the fitted one's noise; the evaluator's chirp term is the
    mean over the lines, so the factor is ``sum(x_f r_f) / sum(x_f)``. The noise
    concentrates on a few lines (near the antiresonance), so the weights matter:
    test/core/diagnosis/test_held_out_floor.py checks the factor against the misfit noise
    alone puts on a simulated record, and prints the uniform mean of r_f beside it.

    Parameters
    ----------
    fit, val : Recording
        The fit and held-out views of a record (:func:`..common.split_recording`).
    fitted : FrequencyResponse
        The chirp estimate of the fit view (its diagonal magnitude weights the lines).

    Returns
    -------
    ndarray, shape (n_axes,)
        The factor per axis; 1 where either view has no complete chirp iteration.

    """
    n = len(fit.joint_names)
    powers = []
    for part in (fit, val):
        if not any(s.info.get('design') == 'chirp' for s in part.segments):
            return np.ones(n)
        freq, p = chirp_input_power(part)
        powers.append(p)
    out = np.ones(n)
    f_est = np.log(np.asarray(fitted.freq_hz, dtype=float))
    for a in range(min(n, fitted.response.shape[0], fitted.response.shape[1])):
        with np.errstate(divide='ignore', invalid='ignore'):
            mag2 = np.exp(np.interp(np.log(freq), f_est,
                                    np.log(np.abs(fitted.response[a, a]) ** 2)))
            x = freq / (mag2 * powers[0][:, a])
            r = powers[0][:, a] / powers[1][:, a]
        ok = np.isfinite(x) & (x > 0) & np.isfinite(r) & (r > 0)
        if ok.any():
            out[a] = float(np.sum(x[ok] * r[ok]) / np.sum(x[ok]))
    return out
