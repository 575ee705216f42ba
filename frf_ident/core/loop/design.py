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
PI gains for a target phase margin and bandwidth, read off a frequency response.

At the target crossover w_c the loop must have |C P| = 1 and arg(C P) = -180 deg + phi_m.
The PI kp (1 - j w_i / w) (w_i = ki / kp) contributes the phase -atan(w_i / w_c), so
w_i = w_c tan(phi_c) with phi_c = 180 deg - phi_m + arg P(j w_c), and kp = cos(phi_c) / |P|.
phi_c < 0 means P alone leaves more margin than asked: a P controller (ki = 0) with that kp;
phi_c >= 90 deg means no PI reaches the target there. P(j w_c) is interpolated (magnitude
in log, phase unwrapped) from the given lines: the measured FRF or a fitted model.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ['PIProposal', 'propose_pi']


@dataclass(frozen=True)
class PIProposal:
    """
    Proposed PI gains and what they were designed for.

    Attributes
    ----------
    kp, ki : float
        Gains [N m s/rad], [N m/rad] (continuous PI kp + ki / s).
    bandwidth_hz : float
        Target gain crossover [Hz].
    phase_margin_deg : float
        Target phase margin [deg].
    feasible : bool
        False when no PI reaches the phase margin at that crossover (then kp, ki are those
        of the largest PI phase lead, ki = 0).

    """

    kp: float
    ki: float
    bandwidth_hz: float
    phase_margin_deg: float
    feasible: bool


def propose_pi(freq_hz: np.ndarray, response: np.ndarray, bandwidth_hz: float,
               phase_margin_deg: float) -> PIProposal:
    """
    Propose PI gains placing the crossover at ``bandwidth_hz`` with ``phase_margin_deg``.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Frequencies of ``response`` [Hz], increasing, around ``bandwidth_hz``.
    response : ndarray of complex, shape (n_freq,)
        The plant P (torque -> velocity) of the axis.
    bandwidth_hz : float
        Target crossover [Hz], within the measured band.
    phase_margin_deg : float
        Target phase margin [deg].

    Returns
    -------
    PIProposal
        The gains (see the module doc).

    Raises
    ------
    ValueError
        ``bandwidth_hz`` lies outside the measured band.

    """
    f = np.asarray(freq_hz, dtype=float)
    if not f[0] <= bandwidth_hz <= f[-1]:
        raise ValueError(f'bandwidth {bandwidth_hz:g} Hz lies outside the measured band '
                         f'{f[0]:g}-{f[-1]:g} Hz')
    p = np.asarray(response, dtype=complex)
    mag = np.exp(np.interp(np.log(bandwidth_hz), np.log(f), np.log(np.abs(p))))
    phase = np.interp(np.log(bandwidth_hz), np.log(f), np.unwrap(np.angle(p)))
    # phase of P in (-360, 0] deg relative to the loop's -180 deg reference
    phase = (phase + np.pi) % (2 * np.pi) - np.pi
    phi_c = np.pi - np.radians(phase_margin_deg) + phase
    phi_c = (phi_c + np.pi) % (2 * np.pi) - np.pi
    feasible = phi_c < np.pi / 2
    phi_c = min(max(phi_c, 0.0), np.pi / 2) if feasible else 0.0
    kp = np.cos(phi_c) / mag
    wc = 2 * np.pi * bandwidth_hz
    return PIProposal(float(kp), float(kp * wc * np.tan(phi_c)), float(bandwidth_hz),
                      float(phase_margin_deg), bool(feasible))
