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
Resonance and antiresonance of each axis from a motor-side FRF (torque -> motor velocity).

The diagonal channel P_ii of a flexible joint falls as 1/(J s) (rigid body), dips at the
antiresonance (the link oscillating against a held motor) and peaks at the resonance. Both are
read from the accelerance |2 pi f P_ii(f)| (torque -> acceleration), which is flat where the
robot moves as a rigid body, so its largest interior value is the resonance and its smallest
value below that the antiresonance. Each extremum is refined between the analysis lines by
the vertex of a parabola through the line and its two neighbours: in 1/|A|^2 at the
resonance and in |A|^2 at the antiresonance, which near a lightly damped pole or zero pair
are quadratic in f ((f - f0)^2 + (zeta f0)^2), so the vertex is the mode's frequency even
when the lines are as far apart as the mode is wide.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ['AxisModes', 'axis_modes']


@dataclass(frozen=True)
class AxisModes:
    """
    Resonance and antiresonance of every diagonal channel.

    Attributes
    ----------
    resonance_hz : ndarray, shape (n,)
        Peak of the accelerance of P_ii [Hz] (NaN where no interior peak).
    antiresonance_hz : ndarray, shape (n,)
        Dip of the accelerance below the resonance [Hz] (NaN where none).

    """

    resonance_hz: np.ndarray
    antiresonance_hz: np.ndarray


def _refine(f: np.ndarray, y: np.ndarray, k: int) -> float:
    """Vertex of the parabola through lines k-1, k, k+1 of y (a minimum at k), in f."""
    x, v = f[k - 1:k + 2] - f[k], y[k - 1:k + 2]
    a, b, _ = np.polyfit(x, v / v[1], 2)
    if not a > 0.0:
        return float(f[k])
    return float(f[k] + np.clip(-b / (2 * a), x[0], x[2]))


def axis_modes(freq_hz: np.ndarray, response: np.ndarray) -> AxisModes:
    """
    Return resonance and antiresonance of each axis from a square FRF array.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Analysis lines [Hz], increasing.
    response : ndarray, shape (n, n, n_freq)
        Torque -> motor velocity FRF (python-control FRD layout: outputs, inputs, lines),
        channel (i, i) the axis i's own; NaN lines are skipped.

    Returns
    -------
    AxisModes
        Per axis, in channel order.

    """
    f_all = np.asarray(freq_hz, dtype=float)
    p = np.asarray(response)
    n = min(p.shape[0], p.shape[1])
    res, anti = np.full(n, np.nan), np.full(n, np.nan)
    for i in range(n):
        ok = np.isfinite(p[i, i]) & (f_all > 0)
        f = f_all[ok]
        power = np.abs(2 * np.pi * f * p[i, i][ok]) ** 2
        if f.size < 3 or not np.all(power > 0):
            continue
        k = int(np.argmax(power[1:-1])) + 1
        res[i] = _refine(f, 1.0 / power, k)
        if k >= 2:
            j = int(np.argmin(power[1:k])) + 1
            anti[i] = _refine(f, power, j)
    return AxisModes(resonance_hz=res, antiresonance_hz=anti)
