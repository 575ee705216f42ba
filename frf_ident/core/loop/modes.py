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
The resonances a filter is placed at: fitted modes with their standard errors, over poses.

A mode is :class:`~frf_ident.core.fit.rational.Mode` (natural frequency and damping ratio with
first-order standard errors). The rational fit gives its modes itself; the physical two-mass
fit (:mod:`frf_ident.core.fit.physical`) gives them here, from the complex pole pair of its
denominator D(s) and the fit's Cramer-Rao covariance (``dp / dtheta = -dD/dtheta (p) / D'(p)``).
Over the poses of a campaign one resonance is a :class:`ResonanceBand`: the nominal pose's
mode and the mode nearest to it at every other pose, and the band they and their standard
errors span, which the filter must cover.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.fit.rational import Mode
import numpy as np

__all__ = ['COVERAGE', 'LIGHT_DAMPING', 'MATCH_RATIO', 'ResonanceBand', 'resonance_bands',
           'two_mass_mode']

#: damping ratio below which a mode is a resonance worth a filter: above it the peak over the
#: background is below 1 / (2 * 0.2) = 2.5 (8 dB), which the PI's gain handles without one
LIGHT_DAMPING = 0.2
#: standard errors each side of a mode's frequency a filter covers: 2 keeps about 95 % of the
#: frequencies the fit cannot rule out (a notch that misses the mode by its uncertainty is
#: useless)
COVERAGE = 2.0
#: a pose's mode belongs to the nominal pose's resonance when its frequency lies within this
#: factor of it (and it is the nearest such mode)
MATCH_RATIO = 1.6


def two_mass_mode(theta: np.ndarray, covariance: np.ndarray) -> Mode | None:
    """
    Return the resonance of a two-mass fit with first-order standard errors.

    Parameters
    ----------
    theta : array_like, shape (5,)
        Jm, Jo, k, d, bv (order of :data:`frf_ident.core.fit.physical.PARAMETERS`).
    covariance : array_like, shape (5, 5)
        Their covariance (the fit's Cramer-Rao bound).

    Returns
    -------
    Mode or None
        The complex pole pair of D(s) as natural frequency [Hz] and damping ratio, None when
        all poles are real (no resonance).

    Examples
    --------
    Jm = 1, Jo = 1, k = 400, no damping: the resonance is sqrt(k (1/Jm + 1/Jo)) / (2 pi):

    >>> m = two_mass_mode([1.0, 1.0, 400.0, 0.0, 0.0], np.zeros((5, 5)))
    >>> round(m.frequency_hz, 4), m.damping
    (4.5016, 0.0)

    """
    jm, jo, k, d, bv = (float(v) for v in theta)
    den = np.array([jm * jo, jm * d + jo * d + bv * jo, jm * k + jo * k + bv * d, bv * k])
    roots = np.roots(den)
    upper = [p for p in roots if p.imag > 1e-9 * abs(p)]
    if not upper:
        return None
    p = upper[0]
    dd = np.polyval(np.polyder(den), p)
    grads = np.array([jo * p ** 3 + d * p ** 2 + k * p,
                      jm * p ** 3 + (d + bv) * p ** 2 + k * p,
                      (jm + jo) * p + bv,
                      (jm + jo) * p ** 2 + bv * p,
                      jo * p ** 2 + d * p + k])
    dp = -grads / dd
    r = abs(p)
    dr = (np.conj(p) * dp).real / r
    dz = -dp.real / r + p.real * dr / r ** 2
    cov = np.asarray(covariance, dtype=float)
    two_pi = 2 * np.pi
    return Mode(float(r / two_pi), float(np.sqrt(max(dr @ cov @ dr, 0.0)) / two_pi),
                float(-p.real / r), float(np.sqrt(max(dz @ cov @ dz, 0.0))))


@dataclass(frozen=True)
class ResonanceBand:
    """
    One lightly damped resonance over the poses, and the band a filter must cover.

    Attributes
    ----------
    modes : tuple of Mode or None
        The mode at every pose (None where that pose shows none near the nominal one).
    nominal : int
        Index of the nominal pose.
    low_hz, high_hz : float
        The band: the lowest frequency - COVERAGE standard errors to the highest + COVERAGE
        standard errors over the poses.
    damping : float
        The smallest damping ratio over the poses.

    """

    modes: tuple[Mode | None, ...]
    nominal: int
    low_hz: float
    high_hz: float
    damping: float

    @property
    def centre_hz(self) -> float:
        """Return the geometric centre of the band [Hz]."""
        return float(np.sqrt(self.low_hz * self.high_hz))

    @property
    def spread(self) -> float:
        """Return the highest over the lowest mode frequency of the poses, minus 1."""
        f = [m.frequency_hz for m in self.modes if m is not None]
        return float(max(f) / min(f) - 1.0)

    def summary(self) -> str:
        """Return one line: the nominal mode and the band."""
        m = self.modes[self.nominal]
        poses = sum(x is not None for x in self.modes)
        over = f' over {poses} poses (spread {100 * self.spread:.1f} %)' if poses > 1 else ''
        return (f'resonance {m.summary()}; filter band {self.low_hz:.4g}-{self.high_hz:.4g} Hz'
                f'{over}')


def resonance_bands(modes: list[list[Mode]], nominal: int, band_hz: tuple[float, float],
                    coverage: float = COVERAGE, light: float = LIGHT_DAMPING
                    ) -> list[ResonanceBand]:
    """
    Group the lightly damped modes of every pose into resonance bands.

    Parameters
    ----------
    modes : list of list of Mode
        The fitted modes of every pose.
    nominal : int
        Index of the nominal pose: each of its lightly damped modes (0 < damping < ``light``)
        inside ``band_hz`` starts a band; an unstable fitted pole (damping < 0) does not.
    band_hz : tuple of float
        The measured band (low, high) [Hz]: a mode outside it is not seen well enough to
        filter.
    coverage : float, optional
        Standard errors each side.
    light : float, optional
        Damping ratio below which a mode is a resonance.

    Returns
    -------
    list of ResonanceBand
        By frequency.

    """
    def lightly(ms):      # a pole in the right half plane (damping < 0) is no resonance
        return [m for m in ms if 0 < m.damping < light
                and band_hz[0] <= m.frequency_hz <= band_hz[1]]
    out = []
    for m0 in lightly(modes[nominal]):
        picked: list[Mode | None] = []
        for k, ms in enumerate(modes):
            near = [m for m in lightly(ms)
                    if abs(np.log(m.frequency_hz / m0.frequency_hz)) < np.log(MATCH_RATIO)]
            picked.append(m0 if k == nominal else
                          min(near, key=lambda m: abs(np.log(m.frequency_hz / m0.frequency_hz)),
                              default=None))
        have = [m for m in picked if m is not None]
        sd = [m.frequency_std_hz if np.isfinite(m.frequency_std_hz) else 0.0 for m in have]
        lo = min(m.frequency_hz - coverage * s for m, s in zip(have, sd))
        hi = max(m.frequency_hz + coverage * s for m, s in zip(have, sd))
        out.append(ResonanceBand(tuple(picked), nominal, float(max(lo, 1e-9)), float(hi),
                                 float(min(m.damping for m in have))))
    return out
