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
w_i = w_c tan(phi_c) with phi_c = 180 deg - phi_m + arg P(j w_c) (the lag the PI must add),
and kp = cos(phi_c) / |P|. phi_c >= 90 deg: the plant alone leaves more margin than asked
there and no PI lags enough to lower it: a P controller (ki = 0, kp = 1 / |P|), more margin
than asked. phi_c < 0: the plant lags more than 180 deg - phi_m there and a PI only adds lag:
no PI reaches the target (infeasible); the P controller of the least lag is proposed and its
smaller margin reported. P(j w_c) is interpolated from the given lines (the measured FRF or a
fitted model) as python-control's smooth FRD interpolates the loop the check reads
(:func:`interpolate`): designed and checked loop agree at the target.

The design sets the loop at one frequency only: a resonance can lift |L| above 1 elsewhere
(another crossover, with less margin), a large kp can keep it above 1 to the band's edge.
:func:`check_targets` compares what the measured loop then has (the margins of
:mod:`frf_ident.core.loop.check`) with the targets and says which is missed and by how much.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import splev, splprep

__all__ = ['CROSSOVER_TOLERANCE', 'PIProposal', 'PM_TOLERANCE_DEG', 'TargetCheck',
           'check_targets', 'interpolate', 'propose_pi']

#: a proposal meets its phase-margin target when the measured loop's margin lies at most this
#: far below it: design and check interpolate alike, so at a single crossover they agree to
#: 0.1-0.3 deg (python-control's root finding, its margin draws) on the demo FRF
#: (test/app/test_loop_targets.py)
PM_TOLERANCE_DEG = 1.0
#: ... and its gain crossover within this share of the target bandwidth (they agree to
#: 0.5 % there)
CROSSOVER_TOLERANCE = 0.05


def interpolate(freq_hz: np.ndarray, response: np.ndarray, at_hz: float) -> complex:
    """
    Return a response between its lines as python-control's smooth FRD interpolates it.

    A cubic interpolating spline of the real and imaginary parts over angular frequency
    (``scipy.interpolate.splprep``, weights 1 / (|P| + 0.001), as ``control.frd(...,
    smooth=True)``): on the demo robot's FRF (53 lines, 0.65 Hz apart) it stays within 0.9 deg
    and 0.1 dB of the exact FRF between the lines, where log-linear magnitude and phase
    missed by up to 21 deg and 4 dB next to the antiresonances.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Increasing frequencies [Hz] (at least 2).
    response : ndarray of complex, shape (n_freq,)
        The response on them.
    at_hz : float
        Where to read it [Hz], within the lines.

    Returns
    -------
    complex
        The interpolated response.

    Examples
    --------
    >>> f = np.array([1.0, 2.0, 3.0, 4.0])
    >>> interpolate(f, (1 - 2j) * f ** 2, 2.5)      # a cubic reproduces a parabola
    (6.25-12.5j)

    """
    f = np.asarray(freq_hz, dtype=float)
    p = np.asarray(response, dtype=complex)
    k = 3 if f.size > 3 else f.size - 1
    tck, _ = splprep([p.real, p.imag], u=2 * np.pi * f, w=1.0 / (np.abs(p) + 0.001), s=0.0,
                     k=k)
    re, im = splev(2 * np.pi * at_hz, tck)
    return complex(float(re), float(im))


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
        False when no PI reaches the phase margin at that crossover: the plant lags more
        than 180 deg - the margin there (then kp, ki are those of the least lag, ki = 0).
    plant_phase_deg : float
        arg P at the target crossover [deg], in (-180, 180].

    """

    kp: float
    ki: float
    bandwidth_hz: float
    phase_margin_deg: float
    feasible: bool
    plant_phase_deg: float = float('nan')


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
    pc = interpolate(f, response, bandwidth_hz)
    mag, phase = abs(pc), float(np.angle(pc))               # arg P in (-180, 180] deg
    lag = np.pi - np.radians(phase_margin_deg) + phase       # what the PI must add
    lag = (lag + np.pi) % (2 * np.pi) - np.pi
    feasible = bool(lag >= 0)
    lag = min(max(lag, 0.0), np.pi / 2)
    wc = 2 * np.pi * bandwidth_hz
    if lag >= np.pi / 2:                                     # P alone: more margin than asked
        return PIProposal(float(1.0 / mag), 0.0, float(bandwidth_hz), float(phase_margin_deg),
                          True, float(np.degrees(phase)))
    kp = np.cos(lag) / mag
    return PIProposal(float(kp), float(kp * wc * np.tan(lag)), float(bandwidth_hz),
                      float(phase_margin_deg), feasible, float(np.degrees(phase)))


@dataclass(frozen=True)
class TargetCheck:
    """
    Whether the measured loop with proposed gains has the bandwidth and margin asked for.

    Attributes
    ----------
    met : bool
        Every target met (within :data:`PM_TOLERANCE_DEG` and :data:`CROSSOVER_TOLERANCE`).
    missed : tuple of str
        One phrase per target missed, with by how much.

    """

    met: bool
    missed: tuple[str, ...]

    def text(self) -> str:
        """Return 'targets met' or 'target missed: ...' for people."""
        return 'targets met' if self.met else 'target missed: ' + '; '.join(self.missed)


def check_targets(proposal: PIProposal, phase_margin_deg: float, crossover_hz: float,
                  edge_gain_db: float = float('nan'),
                  band_hz: tuple[float, float] = (float('nan'), float('nan'))) -> TargetCheck:
    """
    Compare the margins the measured loop has with the proposal's targets.

    Parameters
    ----------
    proposal : PIProposal
        The gains and their targets.
    phase_margin_deg, crossover_hz : float
        Phase margin [deg] and gain crossover [Hz] of the measured loop with these gains
        (NaN: no crossover in the band).
    edge_gain_db : float, optional
        |L| at the highest measured line [dB]; above 0 the loop crosses over above the band.
    band_hz : tuple of float, optional
        The measured band [Hz], for the text.

    Returns
    -------
    TargetCheck
        Met, or what is missed and by how much.

    Examples
    --------
    >>> p = PIProposal(100.0, 1e4, 20.0, 60.0, True)
    >>> check_targets(p, 59.6, 20.1).text()
    'targets met'
    >>> [m.split(',')[0] for m in check_targets(p, 19.6, 3.9).missed]
    ['phase margin 19.6 deg', 'crossover 3.9 Hz']

    """
    bw, pm = proposal.bandwidth_hz, proposal.phase_margin_deg
    missed = []
    if not proposal.feasible:
        missed.append(f'no PI reaches {pm:g} deg at {bw:g} Hz: the plant lags '
                      f'{-proposal.plant_phase_deg:.0f} deg there and a PI only adds lag '
                      f'(proposed: a P controller)')
    if edge_gain_db > 0:
        missed.append(f'|L| is {edge_gain_db:+.1f} dB at the band edge {band_hz[1]:.3g} Hz: the '
                      f'loop crosses over above the measured band')
    if not np.isfinite(phase_margin_deg):
        missed.append('no gain crossover within the measured band')
    else:
        if phase_margin_deg < pm - PM_TOLERANCE_DEG:
            missed.append(f'phase margin {phase_margin_deg:.3g} deg, '
                          f'{pm - phase_margin_deg:.3g} deg below the {pm:g} deg target')
        if abs(crossover_hz / bw - 1) > CROSSOVER_TOLERANCE:
            missed.append(f'crossover {crossover_hz:.3g} Hz, {100 * (crossover_hz / bw - 1):+.0f} '
                          f'% off the {bw:g} Hz target')
    return TargetCheck(not missed, tuple(missed))
