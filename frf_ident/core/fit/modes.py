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
The modes of a fitted denominator: natural frequency and damping ratio with their errors.

First order: a change da_m of the scaled denominator coefficient m moves a pole p by
-p^m da_m / D'(p); the Cramer-Rao covariance of the denominator, and the shifts of the
model-error shapes (:mod:`frf_ident.core.fit.model_error`), map through that Jacobian to the
frequency |p| and the damping ratio -Re p / |p|.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.fit.model_error import bound
from frf_ident.core.fit.stable import MIN_DAMPING
import numpy as np

__all__ = ['Mode', 'modes_of']


@dataclass(frozen=True)
class Mode:
    """
    One pole pair (or real pole) of a fitted model with its first-order standard errors.

    Attributes
    ----------
    frequency_hz, frequency_std_hz : float
        Natural frequency |p| / 2 pi [Hz] and its standard error.
    damping, damping_std : float
        Damping ratio -Re p / |p| and its standard error (1 for a real pole).
    in_band : bool
        False for a complex pair whose frequency lies outside the fitted lines: not
        supported by the data.
    at_limit : bool
        True for a pair whose damping ratio ended at the stability limit of the refit
        (below twice :data:`~frf_ident.core.fit.stable.MIN_DAMPING`): the data would put it
        in the right half-plane.
    frequency_bound_hz, damping_bound : float
        Bound of the bias a missing structure can leave (0 where the cost test passes).

    """

    frequency_hz: float
    frequency_std_hz: float
    damping: float
    damping_std: float
    in_band: bool = True
    frequency_bound_hz: float = 0.0
    damping_bound: float = 0.0
    at_limit: bool = False

    @property
    def supported(self) -> bool:
        """Return whether the data support the mode: in the band, not at the stability limit."""
        return self.in_band and not self.at_limit

    def summary(self) -> str:
        """Return one line: frequency and damping with their reported errors, and the flags."""
        flag = ('' if self.in_band else ': OUTSIDE the fitted band, not supported by the data')
        flag += ('' if not self.at_limit else ': at the stability limit (the data would put '
                 'it in the right half-plane)')
        return (f'{self.frequency_hz:.4g} +- '
                f'{np.hypot(self.frequency_std_hz, self.frequency_bound_hz):.2g} Hz, damping '
                f'ratio {self.damping:.4f} +- {np.hypot(self.damping_std, self.damping_bound):.2g}'
                + flag)


def modes_of(den_scaled: np.ndarray, omega0: float, cov_den: np.ndarray,
             shift_den: np.ndarray | None, band_hz: tuple[float, float]) -> list[Mode]:
    """
    Return the poles of a scaled monic denominator as modes, one per upper-half-plane pole.

    Parameters
    ----------
    den_scaled : ndarray, shape (order + 1,)
        Denominator in ascending powers of s / omega0, the last 1.
    omega0 : float
        The frequency scale [rad/s].
    cov_den : ndarray, shape (order, order)
        Covariance of den_scaled[:-1].
    shift_den : ndarray, shape (order, n_shapes), or None
        Model-error shifts of den_scaled[:-1] (None: no model error).
    band_hz : tuple of float
        The fitted band (low, high) [Hz]: a complex pair outside it is flagged.

    Returns
    -------
    list of Mode
        Sorted by frequency.

    """
    a = np.asarray(den_scaled, dtype=float)
    n = a.size - 1
    dpoly = np.polyder(a[::-1])
    out = []
    for p in np.roots(a[::-1]):
        if p.imag < -1e-12 * abs(p):
            continue
        dp = -(p ** np.arange(n)) / np.polyval(dpoly, p)     # dp / da_m, complex
        r = abs(p)
        dr = (np.conj(p) * dp).real / r
        dz = -dp.real / r + p.real * dr / r ** 2
        f_hz = float(r * omega0 / (2 * np.pi))
        b_r, b_z = (0.0, 0.0) if shift_den is None else bound(shift_den, np.array([dr, dz]))
        complex_pair = p.imag > 1e-12 * abs(p)
        out.append(Mode(f_hz, float(np.sqrt(max(dr @ cov_den @ dr, 0.0)) * omega0 / (2 * np.pi)),
                        float(-p.real / r), float(np.sqrt(max(dz @ cov_den @ dz, 0.0))),
                        in_band=not complex_pair or band_hz[0] <= f_hz <= band_hz[1],
                        frequency_bound_hz=float(b_r * omega0 / (2 * np.pi)),
                        damping_bound=float(b_z),
                        at_limit=bool(complex_pair and -p.real / r < 2 * MIN_DAMPING)))
    return sorted(out, key=lambda m: m.frequency_hz)
