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
Margins of many SISO loops given on the same lines at once: the loop-shaping search's check.

python-control's ``stability_margins`` (what :func:`frf_ident.app.loop.margins` runs and what
``tune`` reports) costs about a millisecond per loop; the search of
:mod:`frf_ident.core.loop.shaping` looks at tens of thousands of loops (gains x filters x
poses), so it reads the margins off the measured lines directly, vectorised over any leading
axes:

- modulus margin: min over the lines of |1 + L|;
- gain crossings: where |L| passes 1 between two lines (interpolated linearly in log |L|
  over log f), each with the phase margin arg L + 180 deg wrapped to [-180, 180) deg (a
  resonance that lifts |L| above 1 again adds crossings); as python-control does, the
  crossing whose margin is smallest in magnitude gives the phase margin (signed) and the
  crossover; the bandwidth is the lowest crossing from |L| > 1 to |L| < 1;
- phase crossings: where the unwrapped phase passes an odd multiple of -180 deg, each with
  the gain margin -20 log10 |L|; the one smallest in magnitude is reported (signed; inf when
  the phase never gets there in the band).
- stability: margins alone do not tell whether a loop whose |L| exceeds 1 at a resonance is
  stable (python-control's picks ignore the crossings far from 1). Nyquist's criterion on the
  band: the unwrapped phase change of 1 + L from the lowest to the highest line, less the
  change of its principal value, is 2 pi times the number of encirclements of -1 (tested
  against known loops in test/core/loop/test_frd_margins.py). With a stable plant and a PI
  (the loop starts with |L| large between -180 and -90 deg) the closed loop is stable when
  that number is 0, provided the band holds the crossover: |L| > 1 at the lowest line and
  < 1 at the highest (``in_band``; outside the band nothing is known).

The lines are not interpolated further (python-control's FRD spline is): a test holds both to
each other on the tuned loops (test/core/loop/test_frd_margins.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ['FrdMargins', 'frd_margins', 'mimo_encirclements']


@dataclass(frozen=True)
class FrdMargins:
    """
    Margins of loops on measured lines, every array shaped like the loops' leading axes.

    Attributes
    ----------
    gain_margin_db : ndarray
        Gain margin [dB]; inf without a phase crossing in the band.
    phase_margin_deg : ndarray
        Phase margin of the gain crossing where it is smallest in magnitude [deg]; NaN
        without a crossing.
    crossover_hz : ndarray
        The gain crossing of the phase margin [Hz]; NaN without one.
    modulus_margin : ndarray
        min |1 + L| over the lines.
    peak_frequency_hz : ndarray
        The line where |1 + L| is smallest [Hz] (where the sensitivity peaks).
    bandwidth_hz : ndarray
        Lowest gain crossing from |L| > 1 to |L| < 1 [Hz]; NaN without one.
    phase_crossover_hz : ndarray
        The phase crossing of the gain margin [Hz]; NaN without one.
    encirclements : ndarray of int
        Net encirclements of -1 over the band (clockwise negative).
    stable : ndarray of bool
        No encirclement of -1 over the band.
    in_band : ndarray of bool
        |L| > 1 at the lowest line and < 1 at the highest: the band holds the crossover, so
        the margins and ``stable`` judge the loop.
    top_db : ndarray
        -20 log10 |L| at the highest line [dB]: beyond the band the phase is unknown, so no
        gain margin larger than this can be claimed for frequencies above it.

    """

    gain_margin_db: np.ndarray
    phase_margin_deg: np.ndarray
    crossover_hz: np.ndarray
    modulus_margin: np.ndarray
    peak_frequency_hz: np.ndarray
    bandwidth_hz: np.ndarray
    phase_crossover_hz: np.ndarray
    encirclements: np.ndarray
    stable: np.ndarray
    in_band: np.ndarray
    top_db: np.ndarray


def _unwrap(phase: np.ndarray) -> np.ndarray:
    """Unwrap along the last axis (numpy's unwrap, without its generality)."""
    d = np.diff(phase, axis=-1)
    d -= 2 * np.pi * np.round(d / (2 * np.pi))
    out = np.empty_like(phase)
    out[..., 0] = phase[..., 0]
    np.cumsum(d, axis=-1, out=out[..., 1:])
    out[..., 1:] += phase[..., :1]
    return out


def frd_margins(loop: np.ndarray, freq_hz: np.ndarray) -> FrdMargins:
    """
    Return the margins of SISO loops L given on the lines ``freq_hz``.

    Parameters
    ----------
    loop : ndarray of complex, shape (..., n_freq)
        L at every line; leading axes are separate loops.
    freq_hz : ndarray, shape (n_freq,)
        Increasing frequencies [Hz].

    Returns
    -------
    FrdMargins
        The margins (see the module doc), shaped ``loop.shape[:-1]``.

    Examples
    --------
    An integrator 10 / s crosses 1 at 10 / (2 pi) Hz with 90 deg of phase margin:

    >>> f = np.geomspace(0.1, 10.0, 400)
    >>> m = frd_margins(10.0 / (2j * np.pi * f), f)
    >>> round(float(m.crossover_hz), 3), round(float(m.phase_margin_deg), 1)
    (1.592, 90.0)
    >>> float(m.gain_margin_db)
    inf

    """
    f = np.asarray(freq_hz, dtype=float)
    lo = np.asarray(loop, dtype=complex)
    lf = np.log(f)
    mag = np.log(np.maximum(np.abs(lo), 1e-300))
    ph = _unwrap(np.angle(lo))
    dist = np.abs(1.0 + lo)
    k = np.argmin(dist, axis=-1)
    # gain crossings between line j and j + 1
    a, b = mag[..., :-1], mag[..., 1:]
    cross = (a > 0) != (b > 0)
    t = np.where(cross, a / np.where(cross, a - b, 1.0), 0.0)
    at_ph = ph[..., :-1] + t * (ph[..., 1:] - ph[..., :-1])
    at_f = np.exp(lf[:-1] + t * (lf[1:] - lf[:-1]))
    pm = np.where(cross, np.degrees(np.mod(at_ph, 2 * np.pi)) - 180.0, np.nan)
    pick = np.argmin(np.where(cross, np.abs(pm), np.inf), axis=-1)[..., None]
    pm = np.take_along_axis(pm, pick, axis=-1)[..., 0]
    wc = np.take_along_axis(np.where(cross, at_f, np.nan), pick, axis=-1)[..., 0]
    down = cross & (a > 0)
    bw = np.where(down, at_f, np.inf).min(axis=-1)
    bw = np.where(np.isfinite(bw), bw, np.nan)
    # phase crossings: the unwrapped phase passes -180 deg + m 360 deg
    turns = np.floor((ph + np.pi) / (2 * np.pi))
    pc = turns[..., 1:] != turns[..., :-1]
    edge = 2 * np.pi * np.maximum(turns[..., 1:], turns[..., :-1]) - np.pi
    s = np.where(pc, (edge - ph[..., :-1]) / np.where(pc, ph[..., 1:] - ph[..., :-1], 1.0), 0.0)
    gm_all = np.where(pc, -20.0 / np.log(10.0) * (a + s * (b - a)), np.inf)
    pick = np.argmin(np.abs(gm_all), axis=-1)[..., None]
    gm = np.take_along_axis(gm_all, pick, axis=-1)[..., 0]
    at_pf = np.where(pc, np.exp(lf[:-1] + s * (lf[1:] - lf[:-1])), np.nan)
    w180 = np.take_along_axis(at_pf, pick, axis=-1)[..., 0]
    wind = _unwrap(np.angle(1.0 + lo))
    laps = (wind[..., -1] - wind[..., 0] - np.angle(1.0 + lo[..., -1])
            + np.angle(1.0 + lo[..., 0])) / (2 * np.pi)
    enc = np.rint(laps).astype(int)
    return FrdMargins(gm, pm, wc, dist.min(axis=-1), f[k], bw, w180, enc, enc == 0,
                      (mag[..., 0] > 0) & (mag[..., -1] < 0), -20.0 / np.log(10.0) * mag[..., -1])


def _laps(x: np.ndarray) -> np.ndarray:
    """Net turns of x about the origin over the last axis, its ends by their principal value."""
    wind = _unwrap(np.angle(x))
    return np.rint((wind[..., -1] - wind[..., 0] - np.angle(x[..., -1])
                    + np.angle(x[..., 0])) / (2 * np.pi)).astype(int)


def mimo_encirclements(loop: np.ndarray) -> np.ndarray:
    """
    Return the net encirclements of the origin by det(I + L) over the band (MIMO Nyquist).

    Counted as those of every axis's 1 + L_ii (as :func:`frd_margins` counts them) plus those
    of the interaction det(I + L) / prod_i (1 + L_ii): that ratio tends to the positive real
    det(P) / prod P_ii (the rigid body's inertia) below the band and to 1 above it, so its
    principal values at the band's ends are where its unmeasured parts start and end, which
    det(I + L) itself, turning with every integrator, is not. With a stable plant and PIs
    the closed loop is stable when it is 0 (and every loop's band holds its crossover).

    Parameters
    ----------
    loop : ndarray of complex, shape (..., n, n, n_freq)
        L = P C at the lines.

    Returns
    -------
    ndarray of int, shape (...)
        The count.

    Examples
    --------
    >>> f = np.geomspace(0.1, 10.0, 200)
    >>> int(mimo_encirclements(np.eye(2)[:, :, None] * (1.0 / (2j * np.pi * f))[None, None]))
    0

    """
    lm = np.moveaxis(np.asarray(loop, dtype=complex), -1, -3)           # (..., F, n, n)
    n = lm.shape[-1]
    diag = 1.0 + np.diagonal(lm, axis1=-2, axis2=-1)                      # (..., F, n)
    ratio = np.linalg.det(np.eye(n) + lm) / np.prod(diag, axis=-1)
    return _laps(ratio) + _laps(np.moveaxis(diag, -1, -2)).sum(axis=-1)
