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
Exponential chirp excitation (Saupe & Knoblach 2015, Section 5).

- :func:`exponential_chirp_coefficients` — a0, a1 of eq. 16 from f(t0) = fl, f(t1) = fu
- :func:`chirp_instantaneous_frequency` — eq. 16, f(t) = exp(a0 t + a1)
- :func:`chirp_phase` — the phase 2 pi int_t0^t f(tau) dtau of eq. 15 in closed form
- :func:`chirp_time_at_frequency` — eq. 16 inverted: when f_x is excited
- :func:`exponential_chirp` — eq. 15, r_c(t, phi) = A(t) sin(2 pi int f + phi)
- :func:`amplitude_schedule` — frequency-dependent amplitude (Table 1), smooth in time
- :func:`chirp_phase_flips` — eq. 26 MIMO scheme (input k flipped by pi in experiment k > 1)
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

from frf_ident.errors import DesignError
import numpy as np

__all__ = ['ChirpDesign', 'amplitude_schedule', 'chirp_instantaneous_frequency', 'chirp_phase',
           'chirp_phase_flips', 'chirp_time_at_frequency', 'exponential_chirp',
           'exponential_chirp_coefficients']


def exponential_chirp_coefficients(f_low: float, f_high: float, t0: float,
                                   t1: float) -> tuple[float, float]:
    """
    Return the coefficients (a0, a1) of f(t) = exp(a0 t + a1) (eq. 16).

    They follow from f(t0) = fl and f(t1) = fu: a0 = ln(fu / fl) / (t1 - t0),
    a1 = ln fl - a0 t0.

    Parameters
    ----------
    f_low, f_high : float
        Band [fl, fu] in Hz, 0 < f_low < f_high.
    t0, t1 : float
        Start and end of the sweep in s, t0 < t1.

    Returns
    -------
    tuple of float
        (a0 in 1/s, a1).

    Raises
    ------
    DesignError
        The band is not positive and increasing, or t1 <= t0.

    """
    if not (np.isfinite(f_low) and f_low > 0):
        raise DesignError(f'{f_low=} must be a positive frequency in Hz')
    if not (np.isfinite(f_high) and f_high > f_low):
        raise DesignError(f'{f_high=} must be greater than {f_low=}')
    if not (np.isfinite(t1) and t1 > t0):
        raise DesignError(f'chirp duration t1 - t0 = {t1 - t0!r} s must be positive')
    a0 = np.log(f_high / f_low) / (t1 - t0)
    a1 = np.log(f_low) - a0 * t0
    return float(a0), float(a1)


def chirp_instantaneous_frequency(t: np.ndarray, a0: float, a1: float) -> np.ndarray:
    """
    Return the instantaneous frequency f(t) = exp(a0 t + a1) in Hz (eq. 16).

    Parameters
    ----------
    t : array_like
        Times in s.
    a0, a1 : float
        Coefficients from :func:`exponential_chirp_coefficients`.

    Returns
    -------
    ndarray
        f(t) in Hz, same shape as ``t``.

    """
    return np.exp(a0 * np.asarray(t, dtype=float) + a1)


def chirp_phase(t: np.ndarray, a0: float, a1: float, t0: float) -> np.ndarray:
    """
    Return the phase 2 pi int_t0^t f(tau) dtau = 2 pi (f(t) - f(t0)) / a0 of eq. 15.

    Parameters
    ----------
    t : array_like
        Times in s.
    a0, a1 : float
        Coefficients of eq. 16.
    t0 : float
        Start of the sweep in s (phase 0 there).

    Returns
    -------
    ndarray
        The phase in rad, same shape as ``t``.

    """
    t = np.asarray(t, dtype=float)
    return 2.0 * np.pi * (np.exp(a0 * t + a1) - np.exp(a0 * t0 + a1)) / a0


def chirp_time_at_frequency(f: np.ndarray, a0: float, a1: float) -> np.ndarray:
    """
    Return the time at which frequency f is excited, t = (ln f - a1) / a0 (eq. 16 inverted).

    Parameters
    ----------
    f : array_like
        Frequencies in Hz (positive).
    a0, a1 : float
        Coefficients of eq. 16.

    Returns
    -------
    ndarray
        Times in s, same shape as ``f``.

    """
    return (np.log(np.asarray(f, dtype=float)) - a1) / a0


def exponential_chirp(t: np.ndarray, a0: float, a1: float, t0: float, t1: float,
                      amplitude: float | np.ndarray | Callable[[np.ndarray], np.ndarray],
                      phi: float = 0.0) -> np.ndarray:
    """
    Evaluate the chirp r_c(t, phi) = A(t) sin(2 pi int_t0^t f + phi) of eq. 15.

    Parameters
    ----------
    t : array_like
        Times in s.
    a0, a1 : float
        Coefficients of eq. 16.
    t0, t1 : float
        The sweep interval [t0, t1] in s.
    amplitude : float, array_like or callable
        A(t): a constant, an array aligned with ``t``, or a function of time.
    phi : float, optional
        Extra phase in rad (the MIMO phase of eq. 9 or eq. 26).

    Returns
    -------
    ndarray
        r_c at the times ``t`` on [t0, t1], zero outside; same shape as ``t``.

    """
    t = np.asarray(t, dtype=float)
    amp = amplitude(t) if callable(amplitude) else np.broadcast_to(amplitude, t.shape)
    inside = (t >= t0) & (t <= t1)
    return np.where(inside, amp * np.sin(chirp_phase(t, a0, a1, t0) + phi), 0.0)


def amplitude_schedule(breaks_hz: Sequence[float], levels: Sequence[float], *,
                       transition: float = 0.05) -> Callable[[np.ndarray], np.ndarray]:
    """
    Build a frequency-dependent amplitude A(f) in the style of Table 1.

    ``levels[i]`` applies between ``breaks_hz[i-1]`` and ``breaks_hz[i]`` (e.g. breaks [40],
    levels [100, 50]: 100 below 40 Hz, 50 above). Steps are smoothed by a raised cosine over
    +-``transition`` (relative) in frequency, so A(t) varies slowly compared to the excited
    frequency as Section 5 assumes (footnote 6).

    Parameters
    ----------
    breaks_hz : sequence of float
        Positive, increasing break frequencies in Hz (may be empty).
    levels : sequence of float
        Finite, non-negative amplitudes, one more than ``breaks_hz``.
    transition : float, optional
        Relative half-width of each smoothed step (0.05: +-5 % around the break).

    Returns
    -------
    callable
        Vectorised A(f): array of frequencies in Hz -> array of amplitudes.

    Raises
    ------
    DesignError
        The lengths do not match, a level is negative or not finite, or the breaks are not
        positive and increasing.

    """
    breaks = np.asarray(breaks_hz, dtype=float)
    lv = np.asarray(levels, dtype=float)
    if lv.size != breaks.size + 1:
        raise DesignError(f'{len(levels)=} must be len(breaks_hz) + 1 = {breaks.size + 1}')
    if np.any(lv < 0) or not np.all(np.isfinite(lv)):
        raise DesignError(f'amplitude levels {lv.tolist()} must be finite and non-negative')
    if np.any(np.diff(breaks) <= 0) or np.any(breaks <= 0):
        raise DesignError(f'breaks_hz {breaks.tolist()} must be positive and increasing')

    def schedule(f: np.ndarray) -> np.ndarray:
        f = np.asarray(f, dtype=float)
        a = np.full(f.shape, lv[0])
        for b, lo, hi in zip(breaks, lv[:-1], lv[1:]):
            x = np.clip((np.log(np.maximum(f, 1e-300) / b) / np.log1p(transition) + 1) / 2,
                        0.0, 1.0)
            a = a + (hi - lo) * (0.5 - 0.5 * np.cos(np.pi * x))
        return a

    return schedule


def chirp_phase_flips(n_u: int) -> np.ndarray:
    """
    Return the MIMO chirp phases of eq. 26: phi~_lk = pi if l = k and l > 1, else 0.

    In experiment k only input k is inverted (experiment 1: none), the scheme Section 7.2
    found better for chirps than the orthogonal shifts of eq. 9.

    Parameters
    ----------
    n_u : int
        Number of inputs (and of experiments, n_ex = n_u).

    Returns
    -------
    ndarray, shape (n_u, n_u)
        Phase in rad of input l (row) in experiment k (column).

    Raises
    ------
    DesignError
        ``n_u`` < 1.

    """
    if n_u < 1:
        raise DesignError(f'{n_u=} must be at least 1')
    phi = np.zeros((n_u, n_u))
    for k in range(1, n_u):
        phi[k, k] = np.pi
    return phi


@dataclass
class ChirpDesign:
    """
    An exponential chirp design (eqs. 15-16) on [t0, t1] with a frequency-dependent amplitude.

    Parameters
    ----------
    f_low, f_high : float
        Band [fl, fu] in Hz.
    duration : float
        Sweep duration t1 - t0 in s.
    amplitude : float or array_like, shape (n_u, n_breaks + 1)
        Amplitude levels per channel (rows) between the common ``breaks_hz`` (see
        :func:`amplitude_schedule`); a plain float gives one constant amplitude on every
        channel, a single row applies to every channel.
    breaks_hz : list of float, optional
        Break frequencies of the amplitude schedule in Hz (default none).
    t0 : float, optional
        Start of the sweep in s.

    Attributes
    ----------
    a0, a1 : float
        Coefficients of f(t) = exp(a0 t + a1) (eq. 16).

    Raises
    ------
    DesignError
        The duration or an amplitude is not positive and finite, the band is invalid, or the
        number of levels does not match ``breaks_hz``.

    """

    f_low: float
    f_high: float
    duration: float
    amplitude: np.ndarray
    breaks_hz: list[float] = field(default_factory=list)
    t0: float = 0.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.duration) and self.duration > 0):
            raise DesignError(f'chirp duration={self.duration!r} s must be positive')
        self.a0, self.a1 = exponential_chirp_coefficients(self.f_low, self.f_high, self.t0,
                                                          self.t1)
        amp = np.atleast_2d(np.asarray(self.amplitude, dtype=float))
        if np.any(~np.isfinite(amp)) or np.any(amp <= 0):
            raise DesignError(f'chirp amplitude {amp.tolist()} must be positive and finite')
        if amp.shape[1] != len(self.breaks_hz) + 1:
            raise DesignError(f'amplitude has {amp.shape[1]} levels per channel, '
                              f'breaks_hz={self.breaks_hz} needs {len(self.breaks_hz) + 1}')
        self.amplitude = amp

    @property
    def t1(self) -> float:
        """Return the end of the sweep, t0 + duration [s]."""
        return self.t0 + self.duration

    def check_sample_rate(self, fs: float) -> None:
        """
        Check that the band lies below the Nyquist frequency of the sample rate.

        Parameters
        ----------
        fs : float
            Sample rate in Hz.

        Raises
        ------
        DesignError
            ``f_high`` is at or above fs / 2.

        """
        if self.f_high >= 0.5 * fs:
            raise DesignError(f'chirp f_high={self.f_high:g} Hz is at or above the Nyquist '
                              f'frequency {0.5 * fs:g} Hz of fs={fs:g} Hz')

    def amplitude_of_channel(self, ch: int) -> Callable[[np.ndarray], np.ndarray]:
        """
        Return A(t) of one channel: its schedule at the instantaneous frequency f(t).

        Parameters
        ----------
        ch : int
            Channel index (0-based); beyond the rows of ``amplitude`` the last row applies.

        Returns
        -------
        callable
            Vectorised A(t): array of times in s -> array of amplitudes.

        """
        levels = self.amplitude[min(ch, self.amplitude.shape[0] - 1)]
        sched = amplitude_schedule(self.breaks_hz, levels)
        return lambda t: sched(chirp_instantaneous_frequency(t, self.a0, self.a1))

    def evaluate(self, t: np.ndarray, phases: np.ndarray) -> np.ndarray:
        """
        Return the MIMO chirp of every experiment and channel at the times ``t`` (eq. 15).

        Parameters
        ----------
        t : array_like, shape (N,)
            Times in s.
        phases : ndarray, shape (n_u, n_ex)
            Phase of each channel in each experiment in rad (:func:`chirp_phase_flips` or
            eq. 9 shifts).

        Returns
        -------
        ndarray, shape (n_ex, N, n_u)
            The reference of channel l in experiment m; zero outside [t0, t1].

        """
        n_u, n_ex = phases.shape
        t = np.asarray(t, dtype=float)
        base = np.sin(chirp_phase(t, self.a0, self.a1, self.t0))
        cosb = np.cos(chirp_phase(t, self.a0, self.a1, self.t0))
        inside = (t >= self.t0) & (t <= self.t1)
        out = np.empty((n_ex, t.size, n_u))
        for ch in range(n_u):
            amp = self.amplitude_of_channel(ch)(t) * inside
            for m in range(n_ex):
                ph = phases[ch, m]
                out[m, :, ch] = amp * (base * np.cos(ph) + cosb * np.sin(ph))
        return out

    def time_at(self, f: np.ndarray) -> np.ndarray:
        """
        Return the time at which each frequency is excited (eq. 16 inverted).

        Parameters
        ----------
        f : array_like
            Frequencies in Hz.

        Returns
        -------
        ndarray
            Times in s, same shape as ``f``.

        """
        return chirp_time_at_frequency(f, self.a0, self.a1)

    def to_dict(self) -> dict:
        """
        Return the design as a JSON-ready dict.

        Returns
        -------
        dict
            ``f_low``, ``f_high``, ``duration``, ``amplitude`` (nested list), ``breaks_hz``
            and ``t0``.

        """
        return {'f_low': self.f_low, 'f_high': self.f_high, 'duration': self.duration,
                'amplitude': self.amplitude.tolist(), 'breaks_hz': list(self.breaks_hz),
                't0': self.t0}

    @classmethod
    def from_dict(cls, d: dict) -> 'ChirpDesign':
        """
        Build a design from the dict of :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            Needs ``f_low``, ``f_high``, ``duration`` and ``amplitude``; ``breaks_hz`` and
            ``t0`` are optional.

        Returns
        -------
        ChirpDesign
            The design.

        Raises
        ------
        DesignError
            The values are out of range (see the class).

        """
        return cls(float(d['f_low']), float(d['f_high']), float(d['duration']),
                   np.asarray(d['amplitude'], dtype=float), list(d.get('breaks_hz', [])),
                   float(d.get('t0', 0.0)))
