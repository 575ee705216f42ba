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
Notch and low-pass biquads at a resonance band, continuous and discretised for the controller.

Notch: N(s) = (s^2 + 2 zeta_z w0 s + w0^2) / (s^2 + 2 zeta_p w0 s + w0^2), unit gain far from
w0, depth zeta_z / zeta_p at w0. From a :class:`~frf_ident.core.loop.modes.ResonanceBand`
[f_lo, f_hi] (the modes over the poses +- 2 standard errors, damping zeta):

- centre w0 = 2 pi sqrt(f_lo f_hi) (the band's geometric centre);
- zeros: zeta_z = max(zeta, (f_hi - f_lo) / (f_hi + f_lo)). For one well-known mode the
  zeros cancel its poles (the classic notch: the loop then sees the mode with the notch's pole
  damping instead of its own); for a band the zeros spread over its relative half width, so
  the notch is at least -3 dB below its pole-side level across the band;
- poles: zeta_p, the width, is a design choice (NOTCH_WIDTHS; the loop shaping picks it):
  the resonance then peaks like a mode of damping zeta_p, and the phase the notch costs at a
  crossover w_c well below w0 is about 2 (zeta_p - zeta_z) w_c / w0 rad.

Low-pass: w0^2 / (s^2 + 2 zeta w0 s + w0^2) below the band, for resonances well above the
crossover where a notch's phase is not needed.

Discretisation (the controller's rate fs): Tustin with prewarping at w0, i.e.
``scipy.signal.bilinear`` at the rate fs' = w0 / (2 tan(w0 / (2 fs))), so the discrete filter
has its centre (or corner) exactly at w0 while the rest of the axis is compressed towards
Nyquist (test/core/loop/test_notch.py holds the discrete minimum to w0). The result is one
second-order section [b0, b1, b2, 1, a1, a2] (scipy's ``sos`` layout), run on the measured
velocity in front of the PI (:mod:`frf_ident.core.simulation.controller`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

__all__ = ['Biquad', 'LOWPASS_ZETA', 'MAX_CENTRE_SHARE', 'MIN_DEPTH_DB', 'NOTCH_WIDTHS',
           'design_lowpass', 'design_notch', 'sections_response']

#: pole damping ratios (widths) of the notches the loop shaping tries: the damping the
#: resonance appears to have behind the notch; wider costs more phase below the notch
#: (0.7: a critically damped look, 0.1: ten times a typical gear mode's 0.01)
NOTCH_WIDTHS = (0.1, 0.2, 0.35, 0.5, 0.7)
#: a notch shallower than this [dB] (zeta_p / zeta_z below 1.5) is not worth its phase
MIN_DEPTH_DB = 3.5
#: damping ratio of the low-pass candidates (Butterworth)
LOWPASS_ZETA = 0.7
#: highest filter frequency as a share of the controller's rate (below Nyquist with room for
#: the prewarped Tustin map, which is singular at fs / 2)
MAX_CENTRE_SHARE = 0.45


@dataclass(frozen=True)
class Biquad:
    """
    A second-order filter of the velocity loop, continuous and discrete.

    Attributes
    ----------
    kind : str
        ``'notch'`` or ``'lowpass'``.
    frequency_hz : float
        Centre (notch) or corner (low-pass) [Hz].
    zeta_zero : float
        Damping of the notch's zeros (0 for a low-pass: no zeros).
    zeta_pole : float
        Damping of the poles.
    num_s, den_s : ndarray, shape (3,)
        Continuous transfer function, descending powers of s [rad/s].
    sos : ndarray, shape (6,)
        Discrete section [b0, b1, b2, 1, a1, a2] at ``sample_rate``.
    sample_rate : float
        Controller rate [Hz] the section is for.
    band_hz : tuple of float
        The band it was designed to cover [Hz] (notch), else (frequency_hz, frequency_hz).

    """

    kind: str
    frequency_hz: float
    zeta_zero: float
    zeta_pole: float
    num_s: np.ndarray
    den_s: np.ndarray
    sos: np.ndarray
    sample_rate: float
    band_hz: tuple[float, float]

    @property
    def depth_db(self) -> float:
        """Return the notch depth [dB] (positive), 0 for a low-pass."""
        if self.kind != 'notch':
            return 0.0
        return float(-20.0 * np.log10(self.zeta_zero / self.zeta_pole))

    def response(self, freq_hz: np.ndarray) -> np.ndarray:
        """Return the discrete section's response at ``freq_hz`` (complex)."""
        w = 2 * np.pi * np.asarray(freq_hz, dtype=float) / self.sample_rate
        return signal.sosfreqz(self.sos.reshape(1, 6), worN=w)[1]

    def continuous_response(self, freq_hz: np.ndarray) -> np.ndarray:
        """Return the continuous filter's response at ``freq_hz`` (complex)."""
        s = 2j * np.pi * np.asarray(freq_hz, dtype=float)
        return np.polyval(self.num_s, s) / np.polyval(self.den_s, s)

    def summary(self) -> str:
        """Return one line for people."""
        if self.kind == 'notch':
            return (f'notch at {self.frequency_hz:.4g} Hz, depth {self.depth_db:.0f} dB, '
                    f'-3 dB width {2 * self.zeta_pole * self.frequency_hz:.3g} Hz (band '
                    f'{self.band_hz[0]:.4g}-{self.band_hz[1]:.4g} Hz)')
        return f'low-pass at {self.frequency_hz:.4g} Hz, damping {self.zeta_pole:.2g}'


def sections_response(freq_hz: np.ndarray, sos: np.ndarray, sample_rate: float) -> np.ndarray:
    """
    Return the response of a chain of discrete second-order sections.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Frequencies [Hz].
    sos : ndarray, shape (n_sections, 6)
        [b0, b1, b2, 1, a1, a2] per section (none: the response is 1).
    sample_rate : float
        The rate they run at [Hz].

    Returns
    -------
    ndarray of complex, shape (n_freq,)
        prod_s (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2) at z = exp(j 2 pi f / fs).

    """
    f = np.asarray(freq_hz, dtype=float)
    sec = np.asarray(sos, dtype=float).reshape(-1, 6)
    if not len(sec):
        return np.ones(f.shape, dtype=complex)
    return signal.sosfreqz(sec, worN=2 * np.pi * f / sample_rate)[1]


def _discrete(num: np.ndarray, den: np.ndarray, w0: float, fs: float) -> np.ndarray:
    """Tustin with prewarping at w0 [rad/s]: one normalised section."""
    fs_warp = w0 / (2.0 * np.tan(w0 / (2.0 * fs)))
    b, a = signal.bilinear(num, den, fs=fs_warp)
    return np.concatenate([b / a[0], a / a[0]])


def _check_frequency(f0: float, fs: float) -> None:
    if not (np.isfinite(f0) and 0 < f0 < MAX_CENTRE_SHARE * fs):
        raise ValueError(f'filter frequency {f0:.4g} Hz: expected 0 < f < {MAX_CENTRE_SHARE:g} '
                         f'x the controller rate {fs:g} Hz')


def design_notch(low_hz: float, high_hz: float, damping: float, zeta_pole: float,
                 sample_rate: float) -> Biquad:
    """
    Return the notch for the band [low_hz, high_hz] with pole damping ``zeta_pole``.

    Parameters
    ----------
    low_hz, high_hz : float
        The band to cover [Hz] (the resonance over the poses +- its standard errors).
    damping : float
        The resonance's (smallest) damping ratio.
    zeta_pole : float
        The notch's pole damping (its width).
    sample_rate : float
        Controller rate [Hz].

    Returns
    -------
    Biquad
        The notch (module doc).

    Raises
    ------
    ValueError
        The centre is not below MAX_CENTRE_SHARE of the rate, or the notch would be shallower
        than MIN_DEPTH_DB.

    Examples
    --------
    A mode at 10 Hz with 1 % damping known to 0.1 Hz (2 SE each side):

    >>> n = design_notch(9.8, 10.2, 0.01, 0.5, 1000.0)
    >>> round(n.frequency_hz, 3), round(n.zeta_zero, 3), round(n.depth_db, 1)
    (9.998, 0.02, 28.0)
    >>> bool(abs(abs(n.response([n.frequency_hz])[0]) - 0.04) < 1e-6)
    True

    """
    f0 = float(np.sqrt(low_hz * high_hz))
    _check_frequency(f0, sample_rate)
    zz = max(float(damping), (high_hz - low_hz) / (high_hz + low_hz))
    zp = float(zeta_pole)
    if not zp >= zz * 10 ** (MIN_DEPTH_DB / 20):
        raise ValueError(f'notch at {f0:.4g} Hz: pole damping {zp:g} is not {MIN_DEPTH_DB:g} '
                         f'dB above the zero damping {zz:.3g}')
    w0 = 2 * np.pi * f0
    num = np.array([1.0, 2 * zz * w0, w0 ** 2])
    den = np.array([1.0, 2 * zp * w0, w0 ** 2])
    return Biquad('notch', f0, float(zz), zp, num, den, _discrete(num, den, w0, sample_rate),
                  float(sample_rate), (float(low_hz), float(high_hz)))


def design_lowpass(corner_hz: float, sample_rate: float, zeta: float = LOWPASS_ZETA) -> Biquad:
    """
    Return the low-pass biquad w0^2 / (s^2 + 2 zeta w0 s + w0^2), prewarped at its corner.

    Parameters
    ----------
    corner_hz : float
        Corner frequency [Hz].
    sample_rate : float
        Controller rate [Hz].
    zeta : float, optional
        Damping ratio.

    Returns
    -------
    Biquad
        The low-pass.

    Raises
    ------
    ValueError
        The corner is not below MAX_CENTRE_SHARE of the rate.

    """
    _check_frequency(corner_hz, sample_rate)
    w0 = 2 * np.pi * corner_hz
    num = np.array([0.0, 0.0, w0 ** 2])
    den = np.array([1.0, 2 * zeta * w0, w0 ** 2])
    return Biquad('lowpass', float(corner_hz), 0.0, float(zeta), num, den,
                  _discrete(num, den, w0, sample_rate), float(sample_rate),
                  (float(corner_hz), float(corner_hz)))
