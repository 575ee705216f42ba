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
Choose the analysis band of a time-series record from its sample rate, motion and noise.

The friction, inertia and gravity effects are read from the inverse-dynamics residual below a
low-pass cut-off ``fc``; above it the residual is scanned for structure no rigid-body effect
explains (:mod:`.timeseries.resonance`). The rule (:func:`analysis_band`), per moving axis:

1. the velocity's white noise floor: the median Welch PSD between 0.6 and 0.95 of the Nyquist
   frequency (as :func:`.prediction.noise_level` takes the torque's);
2. the motion: the lines where the velocity PSD stands ``BAND_SNR`` above that floor;
3. the frequency below which ``BAND_MOTION_SHARE`` of that power lies (the velocity, not the
   acceleration: a broadband shake carries acceleration power up to Nyquist, not motion).

``fc`` is the largest of these over the axes, at least ``FC_HZ`` (the band the diagnosis is
calibrated at) and at most ``BAND_MAX_SHARE`` of the sample rate (room for the scan above).
On EMPS (bang-bang trajectories at 1 kHz) the motion reaches 14 Hz, on the KUKA A record
(250 Hz, sinusoids) 3 Hz: both keep FC_HZ; a faster motion or a slower sample rate moves the
band.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from frf_ident.core.recording import Recording
import numpy as np
from scipy import signal

from .thresholds import BAND_MAX_SHARE, BAND_MOTION_SHARE, BAND_SNR, FC_HZ

__all__ = ['AnalysisBand', 'analysis_band', 'fixed_band']


@dataclass(frozen=True)
class AnalysisBand:
    """The band a time-series diagnosis fits in, and why."""

    #: [Hz] low-pass cut-off of residual and regressors
    fc_hz: float
    #: [Hz] per axis the frequency below which BAND_MOTION_SHARE of the motion's power lies
    #: (0 where the axis shows no motion above its noise)
    motion_hz: tuple[float, ...]
    #: [Hz] the largest band the sample rate leaves room for (BAND_MAX_SHARE of it)
    limit_hz: float
    #: which bound set ``fc_hz``: 'motion', 'calibrated minimum', 'sample rate' or 'given'
    reason: str

    def to_dict(self) -> dict:
        """Return the report.json ``analysis_band`` entry."""
        return {'fc_hz': round(self.fc_hz, 2),
                'motion_hz': [round(x, 2) for x in self.motion_hz],
                'limit_hz': round(self.limit_hz, 2), 'set_by': self.reason}

    def describe(self) -> str:
        """Return one line for people."""
        return (f'analysis band 0-{self.fc_hz:.3g} Hz (set by the {self.reason}; motion up to '
                + ', '.join(f'{x:.3g}' for x in self.motion_hz) + ' Hz per axis, '
                f'sample-rate limit {self.limit_hz:.3g} Hz)')


def motion_band(v: np.ndarray, fs: float) -> np.ndarray:
    """
    Return per axis the frequency holding BAND_MOTION_SHARE of the motion's power.

    Parameters
    ----------
    v : ndarray, shape (N, n)
        Measured velocities.
    fs : float
        Sample rate [Hz].

    Returns
    -------
    ndarray, shape (n,)
        [Hz]; 0 for an axis without a line above BAND_SNR noise floors.

    """
    v = np.nan_to_num(np.asarray(v, float))
    nper = int(min(2 ** int(math.log2(max(v.shape[0] // 8, 64))), 4096))
    f, p = signal.welch(v, fs=fs, nperseg=min(nper, v.shape[0]), axis=0)
    top = (f > 0.6 * fs / 2) & (f < 0.95 * fs / 2)
    floor = np.median(p[top], axis=0) if top.any() else np.zeros(v.shape[1])
    acc = np.where(p > BAND_SNR * floor, p, 0.0)
    out = np.zeros(v.shape[1])
    for i in range(v.shape[1]):
        total = acc[:, i].sum()
        if total > 0:
            c = np.cumsum(acc[:, i]) / total
            out[i] = f[min(int(np.searchsorted(c, BAND_MOTION_SHARE)), f.size - 1)]
    return out


def analysis_band(rec: Recording) -> AnalysisBand:
    """
    Choose the analysis band of a record (module docstring: the rule).

    Parameters
    ----------
    rec : Recording
        The record (its velocities and sample rate).

    Returns
    -------
    AnalysisBand
        The cut-off and the numbers it was chosen from.

    """
    motion = motion_band(rec.velocity, rec.fs)
    limit = BAND_MAX_SHARE * rec.fs
    want = float(motion.max(initial=0.0))
    fc, why = (want, 'motion') if want > FC_HZ else (FC_HZ, 'calibrated minimum')
    if fc > limit:
        fc, why = limit, 'sample rate'
    return AnalysisBand(float(fc), tuple(float(x) for x in motion), float(limit), why)


def fixed_band(rec: Recording, fc: float) -> AnalysisBand:
    """Return a band given by the caller (``fc`` [Hz]), with the record's motion for the report."""
    return AnalysisBand(float(fc), tuple(float(x) for x in motion_band(rec.velocity, rec.fs)),
                        BAND_MAX_SHARE * rec.fs, 'given')
