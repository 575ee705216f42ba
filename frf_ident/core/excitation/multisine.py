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
    """Return the reference set F~: ``n`` log-spaced frequencies in [fl, fu] (Sec. 4.2)."""
    _check_band(f_low, f_high)
    if n < 2:
        raise DesignError(f'{n=} reference frequencies: need at least 2')
    return np.geomspace(f_low, f_high, int(n))


def analysis_sample_time(f_high: float, dt: float | None = None) -> float:
    """
    Analysis sample time Ts ~ 1/(5 fu) (Sec. 4.2).

    With the recording's sample time ``dt`` given, Ts is the largest whole multiple of dt not
    above 1/(5 fu) (so the data are resampled by an integer factor): 1 kHz and fu = 60 Hz give
    the paper's Ts = 3 ms.
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
    """DFT length nf = ceil(1/(f0~ Ts)) (eq. 12), zero-padded up to a power of two (footnote 3)."""
    _check_positive(resolution_hz=resolution_hz, ts=ts)
    n = math.ceil(1.0 / (resolution_hz * ts) - 1e-9)
    return 1 << max(1, (n - 1).bit_length())


def fundamental_frequency(ts: float, nf: int) -> float:
    """Return the DFT resolution and multisine fundamental f0 = 1/(Ts nf) (eq. 11)."""
    _check_positive(ts=ts, nf=nf)
    return 1.0 / (ts * nf)


def odd_harmonics_nearest(f_ref: np.ndarray, f0: float) -> np.ndarray:
    """
    Odd multiples of f0 nearest to each reference frequency, duplicates removed (Sec. 4.2).

    Returns the sorted unique odd harmonic numbers h (frequencies h * f0).
    """
    f_ref = np.asarray(f_ref, dtype=float)
    # nearest odd integer to x: 2*round((x-1)/2)+1
    h = 2 * np.round((f_ref / f0 - 1.0) / 2.0).astype(np.int64) + 1
    h = np.maximum(h, 1)
    return np.unique(h)


def multisine(t: np.ndarray, freq_hz: np.ndarray, amplitudes: np.ndarray,
              phases: np.ndarray, phi: float = 0.0) -> np.ndarray:
    """
    Multisine r(t, phi) = sum_s A_s sin(2 pi f_s t + phi_rand,s + phi) (eq. 8).

    Evaluated in blocks so long signals stay within bounded memory.
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
    Phase shifts phi_lm = 2 pi (l-1)(m-1) / n_u of channel l in experiment m (eq. 9).

    Returns an (n_u, n_ex = n_u) array. exp(j phi) is the DFT matrix, so the MIMO excitation
    matrix R(w_k) has condition number 1 on every excited line.
    """
    if n_u < 1:
        raise DesignError(f'{n_u=} must be at least 1')
    idx = np.arange(n_u)
    return 2.0 * np.pi * np.outer(idx, idx) / n_u


def crest_factor(x: np.ndarray, axis: int | None = None) -> np.ndarray | float:
    """Crest factor max|x| / rms(x) (Sec. 4: peak over root-mean-square value)."""
    x = np.asarray(x, dtype=float)
    rms = np.sqrt(np.mean(x ** 2, axis=axis))
    return np.max(np.abs(x), axis=axis) / rms


def random_phases(n_lines: int, rng: np.random.Generator) -> np.ndarray:
    """Independent uniform phases in [0, 2 pi): E[exp(j phi_rand)] = 0 (Sec. 4)."""
    return rng.uniform(0.0, 2.0 * np.pi, size=n_lines)


@dataclass
class MultisineDesign:
    """
    An odd random-phase multisine design (Sec. 4.2).

    ``harmonics`` are the odd harmonic numbers h, excited frequencies ``h * f0``. ``bound`` is
    the peak value every realisation is scaled to (max |r| over all channels and experiments).
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
        return self.harmonics * self.f0

    @property
    def period(self) -> float:
        """Duration of one period, nf * Ts = 1/f0 [s]."""
        return self.nf * self.ts

    def period_samples(self, fs: float) -> int:
        """Sample per period at rate fs; raises unless the period is a whole number of samples."""
        n = self.period * fs
        if abs(n - round(n)) > 1e-6 * max(1.0, n):
            raise DesignError(
                f'period {self.period:g} s is not a whole number of samples at {fs=:g} Hz')
        return int(round(n))

    def to_dict(self) -> dict:
        return {'f_low': self.f_low, 'f_high': self.f_high, 'ts': self.ts, 'nf': self.nf,
                'f0': self.f0, 'harmonics': self.harmonics.tolist(), 'bound': self.bound,
                'n_ref': self.n_ref}

    @classmethod
    def from_dict(cls, d: dict) -> 'MultisineDesign':
        return cls(float(d['f_low']), float(d['f_high']), float(d['ts']), int(d['nf']),
                   float(d['f0']), np.asarray(d['harmonics'], dtype=np.int64),
                   float(d['bound']), int(d.get('n_ref', 80)))


def design_odd_multisine(f_low: float, f_high: float, *, bound: float,
                         resolution_hz: float = 0.1, n_ref: int = 80,
                         fs: float | None = None) -> MultisineDesign:
    """
    Design an odd random-phase multisine exactly as Section 4.2.

    Parameters
    ----------
    f_low, f_high
        Band [fl~, fu~] in Hz.
    bound
        Peak value max |r| of every realisation (e.g. torque limit or velocity amplitude).
    resolution_hz
        Desired frequency resolution f0~ (eq. 12).
    n_ref
        Size of the log-spaced reference set F~ (80 in the paper).
    fs
        Sample rate of the recording; Ts becomes a whole multiple of 1/fs.

    Example: ``design_odd_multisine(1, 60, bound=150, fs=1000)`` gives Ts = 3 ms, nf = 4096,
    a period of 12.288 s (the paper's Section 6 design).

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
    """One MIMO realisation: random phases, the eq. 9 shifts and the common line amplitude."""

    design: MultisineDesign
    phases: np.ndarray
    shifts: np.ndarray
    amplitude: float

    @property
    def n_u(self) -> int:
        return self.shifts.shape[0]

    def evaluate(self, t: np.ndarray) -> np.ndarray:
        """
        Return the signal at times t.

        Shape (n_ex, len(t), n_u); channel l of experiment m is r(t, phi_lm).
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
    """
    if n_u < 1:
        raise DesignError(f'{n_u=} must be at least 1')
    phases = random_phases(design.harmonics.size, rng)
    unit = MultisineRealisation(design, phases, mimo_phase_shifts(n_u), 1.0)
    n = design.period_samples(fs) * int(oversample)
    peak = np.max(np.abs(unit.evaluate(np.arange(n) * (design.period / n))))
    unit.amplitude = design.bound / peak
    return unit
