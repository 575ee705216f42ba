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
Loop responses on a measured FRF and the typed results of the controller check.

The controller is the velocity PI of the model file (:class:`~frf_ident.core.simulation.
controller.PIVelocity`), one per axis: C(z) = kp + ki dt z / (z - 1) as the simulation runs it,
or C(s) = kp + ki / s in continuous time. The uncertainty of every margin comes from
Monte-Carlo draws of the FRF from its own variance (circular complex Gaussian per line):
first-order propagation fails where a crossover moves from one line to the next.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ['AxisMargins', 'DRAWS', 'LoopCheck', 'Margin', 'draw_responses', 'edge_gain_db',
           'loop_response', 'pi_response', 'sensitivity_peak']

#: Monte-Carlo draws of the FRF for the margins' standard deviations: the relative error of a
#: standard deviation from n draws is about 1 / sqrt(2 n), 10 % for 50 (each draw costs one
#: python-control stability_margins per axis, ~0.1 s on a loaded 2-core machine)
DRAWS = 50


def pi_response(freq_hz: np.ndarray, kp: float, ki: float, dt: float | None = None
                ) -> np.ndarray:
    """
    Return the frequency response of the velocity PI.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Frequencies in Hz.
    kp, ki : float
        Gains [N m s/rad] and [N m/rad].
    dt : float, optional
        Sample time [s]: the discrete PI kp + ki dt z / (z - 1) of the simulation; None: the
        continuous kp + ki / s.

    Returns
    -------
    ndarray of complex, shape (n_freq,)
        C at every frequency.

    """
    w = 2 * np.pi * np.asarray(freq_hz, dtype=float)
    if dt is None:
        return kp + ki / (1j * w)
    z = np.exp(1j * w * dt)
    return kp + ki * dt * z / (z - 1)


def loop_response(response: np.ndarray, controller: np.ndarray) -> np.ndarray:
    """
    Return the loop gain L = P C (output side) of every frequency.

    Parameters
    ----------
    response : ndarray of complex, shape (..., n, n, n_freq)
        The plant FRF P (torque -> velocity).
    controller : ndarray of complex, shape (n, n_freq)
        The diagonal controller C_i of every axis.

    Returns
    -------
    ndarray of complex, shape (..., n, n, n_freq)
        P diag(C).

    """
    return response * controller[None, :, :]


def edge_gain_db(loop: np.ndarray) -> np.ndarray:
    """
    Return |L| at the highest measured line in dB (above 0: a crossover above the band).

    Parameters
    ----------
    loop : ndarray of complex, shape (..., n_freq)
        Loop responses on increasing frequencies.

    Returns
    -------
    ndarray, shape (...)
        20 log10 |L(f_max)|.

    Examples
    --------
    >>> float(edge_gain_db(np.array([10.0, 1.0, 0.1j])))
    -20.0

    """
    return 20 * np.log10(np.abs(np.asarray(loop)[..., -1]))


def sensitivity_peak(loop: np.ndarray) -> np.ndarray:
    """
    Return the peak over frequency of the largest singular value of S = (I + L)^-1.

    Parameters
    ----------
    loop : ndarray of complex, shape (..., n, n, n_freq)
        Loop gain(s) L.

    Returns
    -------
    ndarray, shape (...)
        max_w sigma_max(S(jw)) (1 / the MIMO modulus margin).

    """
    lm = np.moveaxis(loop, -1, -3)                   # (..., n_freq, n, n)
    n = lm.shape[-1]
    smax = 1.0 / np.linalg.svd(np.eye(n) + lm, compute_uv=False)[..., -1]
    return smax.max(axis=-1)


def draw_responses(response: np.ndarray, variance: np.ndarray, n_draws: int,
                   rng: np.random.Generator) -> np.ndarray:
    """
    Draw FRFs P + E with E circular complex Gaussian of the given variance.

    Parameters
    ----------
    response : ndarray of complex
        The estimate.
    variance : ndarray, same shape
        E|E|^2 of every entry.
    n_draws : int
        Number of draws.
    rng : numpy.random.Generator
        Random source.

    Returns
    -------
    ndarray of complex, shape (n_draws,) + response.shape
        The draws.

    """
    shape = (n_draws,) + response.shape
    e = rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
    return response + e * np.sqrt(np.asarray(variance) / 2)


@dataclass(frozen=True)
class Margin:
    """A margin and its standard deviation over the FRF's draws (NaN without variance)."""

    value: float
    std: float

    def text(self, unit: str, digits: int = 3) -> str:
        """Return ``value +- std unit`` for people."""
        if not np.isfinite(self.value):
            return f'{self.value} {unit}'
        sd = f' +- {self.std:.2g}' if np.isfinite(self.std) else ''
        return f'{self.value:.{digits}g}{sd} {unit}'


@dataclass(frozen=True)
class AxisMargins:
    """
    Margins of one axis's loop L_i = C_i P_ii (the other loops open).

    Attributes
    ----------
    axis : str
        The axis.
    kp, ki : float
        The PI gains checked.
    gain_margin_db : Margin
        Gain margin [dB] (inf when the phase never crosses -180 deg in the band).
    phase_margin_deg : Margin
        Phase margin [deg].
    crossover_hz : Margin
        Gain crossover frequency [Hz].
    modulus_margin : Margin
        min |1 + L|, the distance of the Nyquist curve from -1.
    band_hz : tuple of float
        The measured band (lowest, highest line) [Hz] the margins were read in.
    edge_gain_db : float
        |L| at the highest measured line [dB]: above 0 the loop crosses over above the
        band, where nothing was measured.

    """

    axis: str
    kp: float
    ki: float
    gain_margin_db: Margin
    phase_margin_deg: Margin
    crossover_hz: Margin
    modulus_margin: Margin
    band_hz: tuple[float, float] = (float('nan'), float('nan'))
    edge_gain_db: float = float('nan')

    @property
    def crossover_above_band(self) -> bool:
        """Return whether |L| is still above 1 at the highest measured line."""
        return bool(self.edge_gain_db > 0)

    def notes(self) -> dict[str, str]:
        """
        Return why a margin has no value, by margin name (empty when all are measured).

        ``gain_margin_db``: no -180 deg crossing in the band (python-control's infinite gain
        margin: whatever lies above the band was not measured); ``phase_margin_deg`` and
        ``crossover_hz``: no gain crossover in the band; ``band_edge``: |L| above 1 at the
        highest line, so a crossover lies above the band and the margins read in the band do
        not describe the loop.
        """
        top = f'{self.band_hz[1]:.3g} Hz'
        out = {}
        if not np.isfinite(self.gain_margin_db.value):
            out['gain_margin_db'] = (f'no gain margin within the measured band (no -180 deg '
                                     f'crossing up to {top})')
        if not np.isfinite(self.phase_margin_deg.value):
            out['phase_margin_deg'] = out['crossover_hz'] = (
                f'no gain crossover within the measured band (up to {top})')
        if self.crossover_above_band:
            out['band_edge'] = (f'|L| is {self.edge_gain_db:+.1f} dB at the band edge {top}: '
                                f'the loop crosses over above the measured band, where its '
                                f'margins are not measured')
        return out

    def summary(self) -> str:
        """Return one line with the four margins (and what the band does not show)."""
        notes = self.notes()
        gm = notes.get('gain_margin_db', f'gain margin {self.gain_margin_db.text("dB")}')
        pm = notes.get('phase_margin_deg', f'phase margin {self.phase_margin_deg.text("deg")} '
                                           f'at {self.crossover_hz.text("Hz")}')
        edge = f'; {notes["band_edge"]}' if 'band_edge' in notes else ''
        return (f'{self.axis} (kp {self.kp:.4g}, ki {self.ki:.4g}): {gm}, {pm}, '
                f'modulus margin {self.modulus_margin.text("", 2).strip()}{edge}')


@dataclass(frozen=True)
class LoopCheck:
    """
    The controller check on a measured FRF.

    Attributes
    ----------
    axes : list of AxisMargins
        Per-axis SISO margins.
    peak_sensitivity : Margin or None
        MIMO: peak of sigma_max(S) of the full loop; None for one axis.
    draws : int
        Monte-Carlo draws behind the standard deviations (0 without variance).
    discrete_dt : float or None
        Sample time of the discrete PI, None for the continuous one.

    """

    axes: list[AxisMargins]
    peak_sensitivity: Margin | None
    draws: int
    discrete_dt: float | None

    def summary(self) -> list[str]:
        """Return one line per axis plus the MIMO sensitivity peak."""
        lines = [a.summary() for a in self.axes]
        if self.peak_sensitivity is not None:
            lines.append(f'MIMO: peak max singular value of S '
                         f'{self.peak_sensitivity.text("", 3).strip()}')
        return lines
