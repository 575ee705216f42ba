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
The chirp iteration's next reference capped so that its planned position stays in the bound.

The iteration asks for the desired torque u_des on every line (eq. 18); at the low end of the
band that torque moves a light robot far: |q| ~ |u| / (J w^2) (Table 1's 150 N m on the iiwa
14's joint 4, J ~ 1.3 kg m^2, need 27 deg at 2 Hz). The excitation refuses a plan whose
position, the reference's integral, leaves the bound (plan_checks.check_position_bound), so
the iteration must not ask for one (issue 50: the second step of ``demo --plant mujoco``
planned 8.4 deg against the 4 deg bound). :func:`cap_position` lowers the reference where
the bound needs it and nowhere else, in two stages:

1. per line and experiment, the column R[l, :, m] (all channels together, so the torque's
   direction on that line is kept) so that its position amplitude |R| / (2 pi f) stays below
   half of ``margin`` x bound (the integral of a chirp started at phase psi carries an
   offset |cos psi| / w_0 besides its oscillation: half for each), f the lowest frequency
   the line's amplitude is played at: the line below it (r(t) interpolates between lines),
   the chirp's start for the first line (below the first line r(t) keeps its amplitude);
2. by the peak of each experiment's synthesised reference's integral (the exact planned
   position, from the move target 0 as the check computes it) where stage 1 was not enough
   (the offset and the interpolation between lines are estimated, not bounded): first the
   lines stage 1 lowered, then, should that not suffice, the experiment as a whole.

The lines above the capped ones keep the amplitude the iteration asked for (unless the last
step of stage 2 was needed: the log line's count of lines says so).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, Callable

import numpy as np

__all__ = ['cap_position', 'planned_peak', 'PositionCap']


@dataclass(frozen=True)
class PositionCap:
    """What :func:`cap_position` lowered, for the iteration's summary and the log."""

    #: [rad] the position bound and the share of it the capped reference may plan to use
    bound: float
    margin: float
    #: lines lowered (in any experiment), of ``n_lines``; the highest of them [Hz]
    lines: int
    n_lines: int
    up_to_hz: float
    #: the largest cut on a line [dB] (stages 1 and 2 together)
    max_cut_db: float
    #: [rad] per axis the planned peak position after the cap, and before it
    planned_peak: tuple[float, ...]
    uncapped_peak: tuple[float, ...]

    @property
    def capped(self) -> bool:
        """Return whether anything was lowered."""
        return self.lines > 0

    def to_dict(self) -> dict[str, Any]:
        """Return the summary entry (JSON numbers, degrees)."""
        return {'bound_deg': math.degrees(self.bound), 'margin': self.margin,
                'lines': self.lines, 'n_lines': self.n_lines, 'up_to_hz': self.up_to_hz,
                'max_cut_db': self.max_cut_db,
                'planned_peak_deg': [math.degrees(x) for x in self.planned_peak],
                'uncapped_peak_deg': [math.degrees(x) for x in self.uncapped_peak]}

    def describe(self) -> str:
        """Return the log line: the limit, what it cost, the peaks before and after."""
        peak = ' / '.join(f'{math.degrees(x):.2f}' for x in self.planned_peak)
        asked = ' / '.join(f'{math.degrees(x):.2f}' for x in self.uncapped_peak)
        return (f'amplitude capped by the position limit at {math.degrees(self.bound):.2f} deg '
                f'(planned up to {100 * self.margin:.0f} % of it): {self.lines} of '
                f'{self.n_lines} lines up to {self.up_to_hz:.2f} Hz lowered by up to '
                f'{self.max_cut_db:.1f} dB; planned peak position {peak} deg per axis '
                f'(uncapped {asked} deg)')


def planned_peak(signals: np.ndarray, dt: float) -> np.ndarray:
    """
    Return per experiment and axis the peak planned position of chirp references.

    Parameters
    ----------
    signals : ndarray, shape (n_ex, N, n_u)
        The velocity references [rad/s], each run from the move target 0.
    dt : float
        Sample time [s].

    Returns
    -------
    ndarray, shape (n_ex, n_u)
        max_t |dt sum_(k<=t) r_k| [rad], as plan_checks.check_position_bound integrates.

    Examples
    --------
    >>> r = np.ones((1, 1000, 2)) * [0.1, -0.2]
    >>> planned_peak(r, 1e-3).round(6).tolist()
    [[0.1, 0.2]]

    """
    return np.max(np.abs(np.cumsum(signals, axis=1) * dt), axis=1)


def cap_position(R: np.ndarray, freqs: np.ndarray, synthesise: Callable[[np.ndarray], np.ndarray],
                 dt: float, bound: float, margin: float, f_start: float
                 ) -> tuple[np.ndarray, PositionCap]:
    """
    Return the reference spectra lowered so the planned position stays in ``margin`` x bound.

    Parameters
    ----------
    R : ndarray, shape (n_lines, n_u, n_ex)
        The next reference in chirp coordinates [rad/s].
    freqs : ndarray, shape (n_lines,)
        The analysis lines [Hz].
    synthesise : callable
        R -> r(t), shape (n_ex, N, n_u) (``ChirpIteration.reference_signals``).
    dt : float
        Sample time [s].
    bound : float
        The position bound around the operating point [rad].
    margin : float
        The share of it the capped reference may plan to use.
    f_start : float
        The chirp's instantaneous frequency at its start [Hz] (at most the first line).

    Returns
    -------
    R : ndarray
        The capped spectra (``R`` itself where nothing was lowered).
    cap : PositionCap

    """
    limit = margin * bound
    before = planned_peak(synthesise(R), dt)
    freqs = np.asarray(freqs, float)
    played = np.minimum(freqs, np.concatenate([[f_start], freqs[:-1]]))
    pos = np.abs(R) / (2 * np.pi * played)[:, None, None]
    fac = np.minimum(1.0, 0.5 * limit / np.maximum(pos.max(axis=1), 1e-300))   # (F, n_ex)
    if np.all(before <= limit):
        fac = np.ones_like(fac)
    for lines in (fac < 1.0, np.ones_like(fac, bool)):                           # stage 2
        peak = planned_peak(synthesise(R * fac[:, None, :]), dt).max(axis=1)     # (n_ex,)
        fac = np.where(lines, fac * np.minimum(1.0, limit / np.maximum(peak, 1e-300)), fac)
    low = (fac < 1.0 - 1e-12).any(axis=1)
    n_low = int(np.count_nonzero(low))
    out = R * fac[:, None, :] if n_low else R
    cap = PositionCap(bound, margin, n_low, len(freqs),
                      float(np.max(freqs[low])) if n_low else 0.0,
                      float(-20 * np.log10(fac.min())) if n_low else 0.0,
                      tuple(planned_peak(synthesise(out), dt).max(axis=0).tolist()),
                      tuple(before.max(axis=0).tolist()))
    return out, cap
