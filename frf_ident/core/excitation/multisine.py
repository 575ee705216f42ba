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
Odd random-phase multisine excitation (Saupe & Knoblach 2015, Section 4).

One function per step of the paper's design (Section 4.2) so each can be checked on its own:

- :func:`reference_frequency_set` — the 80 log-spaced reference frequencies F~ in [fl, fu]
- :func:`analysis_sample_time` — Ts ~ 1/(5 fu), a whole multiple of the recording's sample time
- :func:`dft_length` — eq. 12 with the power-of-two zero padding of footnote 3
- :func:`fundamental_frequency` — eq. 11, f0 = 1/(Ts nf)
- :func:`odd_harmonics_nearest` — odd multiples of f0 nearest to F~, duplicates removed
- :func:`multisine` — eq. 8, r(t, phi) = sum_s A_s sin(2 pi f_s t + phi_rand,s + phi)
- :func:`mimo_phase_shifts` — eq. 9, phi_lm = 2 pi (l-1)(m-1) / n_u (condition number 1)
- :func:`crest_factor` — peak over RMS
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math

from frf_ident.errors import DesignError
import numpy as np

__all__ = ['MultisineDesign', 'MultisineRealisation', 'analysis_sample_time', 'crest_factor',
           'design_odd_multisine', 'dft_length', 'fundamental_frequency', 'mimo_phase_shifts',
           'multisine', 'multisine_realisation', 'odd_harmonics_nearest', 'random_phases',
           'reference_frequency_set']


def _check_band(f_low: float, f_high: float) -> None:
    if not (np.isfinite(f_low) and f_low > 0):
        raise DesignError(f'{f_low=} must be a positive frequency in Hz')
    if not (np.isfinite(f_high) and f_high > f_low):
        raise DesignError(f'{f_high=} must be greater than {f_low=}')


def _check_positive(**values: float) -> None:
    for name, val in values.items():
        if not (np.isfinite(val) and val > 0):
            raise DesignError(f'{name}={val!r} must be a positive finite number')


def reference_frequency_set(f_low: float, f_high: float, n: int = 80) -> np.ndarray:
    """
    Return the reference set F~: ``n`` log-spaced frequencies in [fl, fu] (Sec. 4.2).

    Parameters
    ----------
    f_low, f_high : float
        Band [fl~, fu~] in Hz, 0 < f_low < f_high.
    n : int, optional
        Number of frequencies (80 in the paper).

    Returns
    -------
    ndarray, shape (n,)
        The frequencies in Hz, from f_low to f_high inclusive.

    Raises
    ------
    DesignError
        The band is not positive and increasing, or ``n`` < 2.

    """
    _check_band(f_low, f_high)
    if n < 2:
        raise DesignError(f'{n=} reference frequencies: need at least 2')
    return np.geomspace(f_low, f_high, int(n))


def analysis_sample_time(f_high: float, dt: float | None = None) -> float:
    """
    Return the analysis sample time Ts ~ 1/(5 fu~) (eq. 10, Sec. 4.2).

    With the recording's sample time ``dt`` given, Ts is the largest whole multiple of dt not
    above 1/(5 fu~) (so the data are resampled by an integer factor): 1 kHz and fu~ = 60 Hz
    give the paper's Ts = 3 ms.

    Parameters
    ----------
    f_high : float
        Upper band edge fu~ in Hz.
    dt : float, optional
        Sample time of the recording in s; None returns 1/(5 fu~) itself.

    Returns
    -------
    float
        Ts in s (at least ``dt`` when dt is given).

    Raises
    ------
    DesignError
        ``f_high`` or ``dt`` is not positive, or ``f_high`` is at or above the Nyquist
        frequency 1/(2 dt).

    """
    _check_positive(f_high=f_high)
    ts = 1.0 / (5.0 * f_high)
    if dt is None:
        return ts
    _check_positive(dt=dt)
    if 2.0 * f_high >= 1.0 / dt:
        raise DesignError(
            f'{f_high=} Hz is at or above the Nyquist frequency {0.5 / dt:g} Hz of the '
            f'sample rate {1.0 / dt:g} Hz')
    return dt * max(1, math.floor(ts / dt + 1e-9))


def dft_length(resolution_hz: float, ts: float) -> int:
    """
    Return the DFT length nf = ceil(1/(f0~ Ts)) (eq. 12), padded to a power of two.

    The zero padding to a power of two is the paper's footnote 3.

    Parameters
    ----------
    resolution_hz : float
        Desired frequency resolution f0~ in Hz.
    ts : float
        Analysis sample time Ts in s.

    Returns
    -------
    int
        nf, the smallest power of two (at least 2) not below ceil(1/(f0~ Ts)).

    Raises
    ------
    DesignError
        ``resolution_hz`` or ``ts`` is not a positive finite number.

    """
    _check_positive(resolution_hz=resolution_hz, ts=ts)
    n = math.ceil(1.0 / (resolution_hz * ts) - 1e-9)
    return 1 << max(1, (n - 1).bit_length())


def fundamental_frequency(ts: float, nf: int) -> float:
    """
    Return the DFT resolution and multisine fundamental f0 = 1/(Ts nf) (eq. 11).

    Parameters
    ----------
    ts : float
        Analysis sample time Ts in s.
    nf : int
        DFT length.

    Returns
    -------
    float
        f0 in Hz; also 1 / period of the multisine.

    Raises
    ------
    DesignError
        ``ts`` or ``nf`` is not positive.

    """
    _check_positive(ts=ts, nf=nf)
    return 1.0 / (ts * nf)


def odd_harmonics_nearest(f_ref: np.ndarray, f0: float) -> np.ndarray:
    """
    Return the odd multiples of f0 nearest to the reference frequencies (Sec. 4.2).

    Parameters
    ----------
    f_ref : array_like
        Reference frequencies F~ in Hz.
    f0 : float
        Fundamental frequency in Hz.

    Returns
    -------
    ndarray of int64
        The sorted odd harmonic numbers h, duplicates removed (frequencies h * f0); at
        least 1.

    """
    f_ref = np.asarray(f_ref, dtype=float)
    # nearest odd integer to x: 2*round((x-1)/2)+1
    h = 2 * np.round((f_ref / f0 - 1.0) / 2.0).astype(np.int64) + 1
    h = np.maximum(h, 1)
    return np.unique(h)


def multisine(t: np.ndarray, freq_hz: np.ndarray, amplitudes: np.ndarray,
              phases: np.ndarray, phi: float = 0.0) -> np.ndarray:
    """
    Evaluate the multisine r(t, phi) = sum_s A_s sin(2 pi f_s t + phi_rand,s + phi) (eq. 8).

    Evaluated in blocks so long signals stay within bounded memory.

    Parameters
    ----------
    t : array_like
        Times in s (any shape).
    freq_hz : array_like, shape (n_s,)
        Line frequencies f_s in Hz.
    amplitudes : float or array_like, shape (n_s,)
        Line amplitudes A_s (a scalar applies to every line).
    phases : array_like, shape (n_s,)
        Random phases phi_rand,s in rad.
    phi : float, optional
        Common extra phase in rad (the MIMO shift of eq. 9).

    Returns
    -------
    ndarray
        r at the times ``t``, same shape as ``t``.

    """
    t = np.asarray(t, dtype=float)
    freq_hz = np.asarray(freq_hz, dtype=float)
    amplitudes = np.broadcast_to(np.asarray(amplitudes, dtype=float), freq_hz.shape)
    phases = np.asarray(phases, dtype=float) + phi
    out = np.empty(t.shape, dtype=float)
    flat_t, flat_out = t.reshape(-1), out.reshape(-1)
    block = max(1, 2_000_000 // max(1, freq_hz.size))
    w = 2.0 * np.pi * freq_hz
    for i in range(0, flat_t.size, block):
        tb = flat_t[i:i + block, None]
        flat_out[i:i + block] = np.sin(tb * w + phases) @ amplitudes
    return out


def mimo_phase_shifts(n_u: int) -> np.ndarray:
    """
    Return the phase shifts phi_lm = 2 pi (l-1)(m-1) / n_u (eq. 9).

    exp(j phi) is the DFT matrix, so the MIMO excitation matrix R(w_k) has condition number
    1 on every excited line (Sec. 4.1).

    Parameters
    ----------
    n_u : int
        Number of inputs (and of experiments, n_ex = n_u).

    Returns
    -------
    ndarray, shape (n_u, n_u)
        Shift in rad of channel l (row) in experiment m (column).

    Raises
    ------
    DesignError
        ``n_u`` < 1.

    """
    if n_u < 1:
        raise DesignError(f'{n_u=} must be at least 1')
    idx = np.arange(n_u)
    return 2.0 * np.pi * np.outer(idx, idx) / n_u


def crest_factor(x: np.ndarray, axis: int | None = None) -> np.ndarray | float:
    """
    Return the crest factor max|x| / rms(x) (Sec. 4: peak over root-mean-square value).

    Parameters
    ----------
    x : array_like
        Signal.
    axis : int, optional
        Axis along which to compute; None (default) uses the whole array.

    Returns
    -------
    float or ndarray
        The crest factor (an array when ``axis`` is given).

    """
    x = np.asarray(x, dtype=float)
    rms = np.sqrt(np.mean(x ** 2, axis=axis))
    return np.max(np.abs(x), axis=axis) / rms


def random_phases(n_lines: int, rng: np.random.Generator) -> np.ndarray:
    """
    Draw independent uniform phases in [0, 2 pi), so E[exp(j phi_rand)] = 0 (Sec. 4).

    Parameters
    ----------
    n_lines : int
        Number of lines n_s.
    rng : numpy.random.Generator
        Source of the random numbers.

    Returns
    -------
    ndarray, shape (n_lines,)
        Phases in rad.

    """
    return rng.uniform(0.0, 2.0 * np.pi, size=n_lines)


@dataclass
class MultisineDesign:
    """
    An odd random-phase multisine design (Sec. 4.2); made by :func:`design_odd_multisine`.

    Parameters
    ----------
    f_low, f_high : float
        Band [fl~, fu~] in Hz.
    ts : float
        Analysis sample time Ts in s (eq. 10).
    nf : int
        DFT length, samples of one period at Ts (eq. 12).
    f0 : float
        Fundamental frequency 1/(Ts nf) in Hz (eq. 11).
    harmonics : ndarray of int
        The odd harmonic numbers h; the excited frequencies are ``h * f0``.
    bound : float
        Peak value every realisation is scaled to (max |r| over all channels and
        experiments).
    n_ref : int, optional
        Size of the reference set F~ (80).
    f_ref : ndarray, optional
        The reference set F~ in Hz (not stored by :meth:`to_dict`).

    """

    f_low: float
    f_high: float
    ts: float
    nf: int
    f0: float
    harmonics: np.ndarray
    bound: float
    n_ref: int = 80
    f_ref: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def freq_hz(self) -> np.ndarray:
        """Return the excited frequencies ``harmonics * f0`` in Hz."""
        return self.harmonics * self.f0

    @property
    def period(self) -> float:
        """Return the duration of one period, nf * Ts = 1/f0 [s]."""
        return self.nf * self.ts

    def period_samples(self, fs: float) -> int:
        """
        Return the number of samples of one period at the sample rate ``fs``.

        Parameters
        ----------
        fs : float
            Sample rate in Hz.

        Returns
        -------
        int
            period * fs.

        Raises
        ------
        DesignError
            The period is not a whole number of samples at ``fs``.

        """
        n = self.period * fs
        if abs(n - round(n)) > 1e-6 * max(1.0, n):
            raise DesignError(
                f'period {self.period:g} s is not a whole number of samples at {fs=:g} Hz')
        return int(round(n))

    def to_dict(self) -> dict:
        """
        Return the design as a JSON-ready dict.

        Returns
        -------
        dict
            The fields except ``f_ref``; ``harmonics`` as a list.

        """
        return {'f_low': self.f_low, 'f_high': self.f_high, 'ts': self.ts, 'nf': self.nf,
                'f0': self.f0, 'harmonics': self.harmonics.tolist(), 'bound': self.bound,
                'n_ref': self.n_ref}

    @classmethod
    def from_dict(cls, d: dict) -> 'MultisineDesign':
        """
        Build a design from the dict of :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            Needs every key :meth:`to_dict` writes; ``n_ref`` defaults to 80.

        Returns
        -------
        MultisineDesign
            The design (with an empty ``f_ref``).

        """
        return cls(float(d['f_low']), float(d['f_high']), float(d['ts']), int(d['nf']),
                   float(d['f0']), np.asarray(d['harmonics'], dtype=np.int64),
                   float(d['bound']), int(d.get('n_ref', 80)))


def design_odd_multisine(f_low: float, f_high: float, *, bound: float,
                         resolution_hz: float, n_ref: int = 80,
                         fs: float | None = None) -> MultisineDesign:
    """
    Design an odd random-phase multisine exactly as Section 4.2.

    Ts from eq. 10, nf from eq. 12 (power of two), f0 from eq. 11, the lines as the odd
    multiples of f0 nearest to the log-spaced reference set F~.

    Parameters
    ----------
    f_low, f_high : float
        Band [fl~, fu~] in Hz.
    bound : float
        Peak value max |r| of every realisation (e.g. torque limit or velocity amplitude).
    resolution_hz : float
        Desired frequency resolution f0~ in Hz (eq. 12). No default here: the paper's
        Section 6 design uses 0.1, the Section 7 procedures ``MultisineConfig.resolution_hz``.
    n_ref : int, optional
        Size of the log-spaced reference set F~ (80 in the paper).
    fs : float, optional
        Sample rate of the recording in Hz; Ts becomes a whole multiple of 1/fs.

    Returns
    -------
    MultisineDesign
        The design (Ts, nf, f0, harmonics, bound, F~).

    Raises
    ------
    DesignError
        A parameter is out of range (the message names it): the band is not positive and
        increasing, ``f_high`` is at or above the Nyquist frequency of ``fs``, or no odd line
        lies below the analysis Nyquist frequency 1/(2 Ts).

    Examples
    --------
    The paper's Section 6 design: Ts = 3 ms, nf = 4096, a period of 12.288 s.

    >>> d = design_odd_multisine(1.0, 60.0, bound=150.0, resolution_hz=0.1, fs=1000.0)
    >>> d.ts, d.nf, round(d.period, 3)
    (0.003, 4096, 12.288)

    """
    _check_band(f_low, f_high)
    _check_positive(bound=bound, resolution_hz=resolution_hz)
    if fs is not None:
        _check_positive(fs=fs)
        if f_high >= 0.5 * fs:
            raise DesignError(
                f'{f_high=} Hz is at or above the Nyquist frequency {0.5 * fs:g} Hz of {fs=:g}')
    ts = analysis_sample_time(f_high, None if fs is None else 1.0 / fs)
    nf = dft_length(resolution_hz, ts)
    f0 = fundamental_frequency(ts, nf)
    f_ref = reference_frequency_set(f_low, f_high, n_ref)
    harmonics = odd_harmonics_nearest(f_ref, f0)
    if harmonics[-1] * f0 >= 0.5 / ts:
        raise DesignError(f'{f_high=} Hz leaves no odd line below the analysis Nyquist '
                          f'frequency {0.5 / ts:g} Hz')
    return MultisineDesign(float(f_low), float(f_high), ts, nf, f0, harmonics, float(bound),
                           int(n_ref), f_ref)


@dataclass
class MultisineRealisation:
    """
    One MIMO realisation: random phases, the eq. 9 shifts and the common line amplitude.

    Made by :func:`multisine_realisation`.

    Parameters
    ----------
    design : MultisineDesign
        The design whose lines are excited.
    phases : ndarray, shape (n_s,)
        Random phases phi_rand,s in rad, one per line.
    shifts : ndarray, shape (n_u, n_u)
        MIMO phase shifts phi_lm (eq. 9), channel by experiment.
    amplitude : float
        Common amplitude A_s of every line.

    """

    design: MultisineDesign
    phases: np.ndarray
    shifts: np.ndarray
    amplitude: float

    @property
    def n_u(self) -> int:
        """Return n_u, the number of channels (and of experiments)."""
        return self.shifts.shape[0]

    def evaluate(self, t: np.ndarray) -> np.ndarray:
        """
        Return the signal of every experiment and channel at the times ``t``.

        Parameters
        ----------
        t : array_like, shape (N,)
            Times in s.

        Returns
        -------
        ndarray, shape (n_ex, N, n_u)
            Channel l of experiment m is r(t, phi_lm) (eq. 8 with the eq. 9 shift).

        """
        t = np.asarray(t, dtype=float)
        out = np.empty((self.n_u, t.size, self.n_u))
        for m in range(self.n_u):
            for ch in range(self.n_u):
                out[m, :, ch] = multisine(t, self.design.freq_hz, self.amplitude, self.phases,
                                          self.shifts[ch, m])
        return out


def multisine_realisation(design: MultisineDesign, n_u: int, rng: np.random.Generator, *,
                          fs: float, oversample: int = 8) -> MultisineRealisation:
    """
    Draw one MIMO realisation (eq. 8 with eq. 9 shifts) scaled to ``design.bound``.

    The equal amplitudes are scaled so max |r| over all channels and experiments equals the
    bound, the peak being searched on a grid ``oversample`` times finer than ``fs`` so that the
    continuous signal, not only its samples, respects the bound.

    Parameters
    ----------
    design : MultisineDesign
        The design.
    n_u : int
        Number of inputs (experiments n_ex = n_u).
    rng : numpy.random.Generator
        Source of the random phases.
    fs : float
        Sample rate in Hz.
    oversample : int, optional
        Refinement of the grid on which the peak is searched.

    Returns
    -------
    MultisineRealisation
        The realisation, its ``amplitude`` set so the peak equals the bound.

    Raises
    ------
    DesignError
        ``n_u`` < 1, or the period is not a whole number of samples at ``fs``.

    """
    if n_u < 1:
        raise DesignError(f'{n_u=} must be at least 1')
    phases = random_phases(design.harmonics.size, rng)
    unit = MultisineRealisation(design, phases, mimo_phase_shifts(n_u), 1.0)
    n = design.period_samples(fs) * int(oversample)
    peak = np.max(np.abs(unit.evaluate(np.arange(n) * (design.period / n))))
    unit.amplitude = design.bound / peak
    return unit
