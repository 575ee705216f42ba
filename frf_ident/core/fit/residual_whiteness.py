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
Where a fit's residual is more than the FRF's noise: line by line, in bands, across frequency.

The cost test (:mod:`frf_ident.core.fit.cost`) says whether a fit misses anything; this module
says where. Its input is the residual of a fit divided by the FRF's standard deviation, one
complex number per line with E|e|^2 = 1 under the noise alone (Pintelon & Schoukens, System
Identification, 2nd ed., Sec. 11.4 and 19.4, the validation FdiTools runs):

1. **Bands of neighbouring lines**: the sum of 2|e|^2 over every run of w neighbouring lines
   (w = 1, 2, 4, ... up to ``max_width``) follows chi-square(2 w) under noise; a run above the
   chi-square quantile of ``alpha`` shared by every run tested (Bonferroni) marks its lines. A
   resonance the model lacks puts its misfit on a few neighbouring lines, each perhaps below
   a single line's limit, their sum far above; a single line far off (w = 1) is found too.
   Marked lines that touch form one :class:`ResidualBand`: its edges, its centre (the lines'
   frequencies weighted by their excess over the noise), its width and its peak line.
2. **Whiteness across frequency**: the autocorrelation of the residual over neighbouring
   lines, rho(m) for lags m = 1 .. ``lags``; under noise (N - m) |rho(m)|^2 is exponential
   with mean 1, so the lag's 95 % bound is sqrt(ln 20 / (N - m)) and sum (N - m) |rho(m)|^2
   is Gamma(lags, 1) (the portmanteau statistic, p value ``white_p``). A smooth misfit (a shifted
   resonance, a missing mode) correlates neighbouring lines; noise does not.

A residual is white (:attr:`ResidualTest.white`) when no band is marked and the portmanteau
statistic stays below its (1 - alpha) quantile.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math

import numpy as np
from scipy import stats

__all__ = ['RESIDUAL_ALPHA', 'ResidualBand', 'ResidualTest', 'WHITENESS_LAGS', 'residual_test']

#: false-alarm probability of each of the two tests over all the runs / lags it examines:
#: 1e-3, as the cost test (frf_ident/core/fit/cost.py MISSING_STRUCTURE_ALPHA)
RESIDUAL_ALPHA = 1e-3
#: lags of the whiteness test (neighbouring lines); a resonance's misfit spans a few lines
WHITENESS_LAGS = 4
#: the widest run of neighbouring lines summed (a power of two)
MAX_WIDTH = 8
#: a run above its limit marks only its lines that carry the excess: the contiguous lines of
#: largest sum of 2|e|^2 minus this level (twice the noise's mean of 2; a line at the noise
#: passes it with probability exp(-2) = 0.14)
CORE_LEVEL = 4.0


@dataclass(frozen=True)
class ResidualBand:
    """A run of neighbouring lines whose residual is above the noise."""

    #: first and last line of the run [Hz]
    lo_hz: float
    hi_hz: float
    #: the lines' frequencies weighted by their excess 2|e|^2 - 2 over the noise [Hz]
    centre_hz: float
    #: the line with the largest 2|e|^2 [Hz]
    peak_hz: float
    #: sum of 2|e|^2 over the run and its expectation under noise (2 per line)
    statistic: float
    expected: float
    #: the lines of the run
    n_lines: int

    @property
    def width_hz(self) -> float:
        """Return hi_hz - lo_hz (0 for a single line)."""
        return self.hi_hz - self.lo_hz

    @property
    def excess(self) -> float:
        """Return the run's statistic over its expectation (1: at the noise)."""
        return self.statistic / max(self.expected, 1e-300)

    def text(self) -> str:
        """Return one line for people: edges, centre, peak and excess."""
        return (f'{self.lo_hz:.4g}-{self.hi_hz:.4g} Hz (centre {self.centre_hz:.4g} Hz, peak '
                f'{self.peak_hz:.4g} Hz, {self.excess:.3g} x the noise over {self.n_lines} '
                f'line(s))')


@dataclass(frozen=True)
class ResidualTest:
    """The residual of a fit tested line by line, in bands and across frequency."""

    #: the lines [Hz] (ascending) and 2|e|^2 per line (chi-square(2) under noise)
    freq_hz: np.ndarray
    line_statistic: np.ndarray
    #: the bands above the noise, strongest (largest statistic) first
    bands: list[ResidualBand] = field(default_factory=list)
    #: |rho(m)| of lags 1 .. WHITENESS_LAGS and their 95 % bounds
    autocorrelation: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bound_95: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: portmanteau p value of the whiteness test (NaN with too few lines)
    white_p: float = float('nan')
    alpha: float = RESIDUAL_ALPHA

    @property
    def correlated(self) -> bool:
        """Return True when the portmanteau test rejects whiteness at ``alpha``."""
        return bool(self.white_p < self.alpha)

    @property
    def white(self) -> bool:
        """Return True when no band is above the noise and the lines are uncorrelated."""
        return not self.bands and not self.correlated

    @property
    def cost_ratio(self) -> float:
        """Return the mean of 2|e|^2 / 2 over the lines (1 at the noise)."""
        return float(np.mean(self.line_statistic) / 2) if self.line_statistic.size else math.nan

    def summary(self) -> str:
        """Return one line for people: the verdict, the bands, the whiteness p value."""
        if self.white:
            return (f'white: no band above the noise, lines uncorrelated (p={self.white_p:.2g}, '
                    f'cost ratio {self.cost_ratio:.3g})')
        parts = [b.text() for b in self.bands]
        if self.correlated:
            parts.append(f'neighbouring lines correlated (p={self.white_p:.2g})')
        return 'not white: ' + '; '.join(parts)


def residual_test(freq_hz: np.ndarray, residual: np.ndarray, *, alpha: float = RESIDUAL_ALPHA,
                  max_width: int = MAX_WIDTH, lags: int = WHITENESS_LAGS) -> ResidualTest:
    """
    Test a normalised residual line by line, in bands of neighbouring lines and for whiteness.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        The lines [Hz], ascending.
    residual : ndarray of complex, shape (n_freq,)
        (model - measured) / standard deviation per line: E|e|^2 = 1 under the noise alone
        (a circular complex error, half its variance in each part).
    alpha : float, optional
        False-alarm probability of the band test over all its runs and of the whiteness test.
    max_width : int, optional
        The widest run of neighbouring lines summed.
    lags : int, optional
        Lags of the whiteness test.

    Returns
    -------
    ResidualTest
        The statistic per line, the bands above the noise and the whiteness test.

    Examples
    --------
    >>> rng = np.random.default_rng(2)
    >>> f = np.arange(1.0, 61.0)
    >>> e = (rng.standard_normal(60) + 1j * rng.standard_normal(60)) / np.sqrt(2)
    >>> residual_test(f, e).white
    True
    >>> e[30:33] += 4.0                      # a misfit on three neighbouring lines
    >>> t = residual_test(f, e)
    >>> [(b.lo_hz, b.hi_hz, round(b.centre_hz, 1)) for b in t.bands]
    [(31.0, 33.0, 32.0)]

    """
    f = np.asarray(freq_hz, dtype=float)
    e = np.asarray(residual, dtype=complex)
    x = 2.0 * np.abs(e) ** 2
    n = f.size
    marked = np.zeros(n, bool)
    widths = [w for w in (2 ** k for k in range(8)) if w <= min(max_width, n)]
    n_runs = sum(n - w + 1 for w in widths)
    for w in widths:
        sums = np.convolve(x, np.ones(w), mode='valid')
        limit = stats.chi2.isf(alpha / max(n_runs, 1), 2 * w)
        for k in np.flatnonzero(sums > limit):
            a, b = _core(x[k:k + w])
            marked[k + a:k + b] = True
    bands = _bands(f, x, marked)
    rho, bound, p = _whiteness(e, lags)
    return ResidualTest(f, x, bands, rho, bound, p, alpha)


def _core(x: np.ndarray) -> tuple[int, int]:
    """
    Return the run [a, b) of a run above its limit that carries its excess.

    The contiguous lines of largest sum of 2|e|^2 - CORE_LEVEL (Kadane's maximum subarray):
    the run's lines at the noise are left out, so a strong line does not mark the noise lines
    that share a wide run with it.
    """
    best, a, b = -math.inf, 0, 1
    run, start = 0.0, 0
    for k, v in enumerate(x - CORE_LEVEL):
        if run <= 0:
            run, start = v, k
        else:
            run += v
        if run > best:
            best, a, b = run, start, k + 1
    return a, b


def _bands(f: np.ndarray, x: np.ndarray, marked: np.ndarray) -> list[ResidualBand]:
    """Return the runs of marked lines as bands, strongest first."""
    out = []
    k = 0
    while k < f.size:
        if not marked[k]:
            k += 1
            continue
        j = k
        while j + 1 < f.size and marked[j + 1]:
            j += 1
        sl = slice(k, j + 1)
        w = np.maximum(x[sl] - 2.0, 0.0)
        centre = float(f[sl] @ w / w.sum()) if w.sum() > 0 else float(f[sl].mean())
        out.append(ResidualBand(float(f[k]), float(f[j]), centre,
                                float(f[sl][int(np.argmax(x[sl]))]), float(x[sl].sum()),
                                2.0 * (j - k + 1), j - k + 1))
        k = j + 1
    return sorted(out, key=lambda b: -b.statistic)


def _whiteness(e: np.ndarray, lags: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Return |rho(m)| for m = 1 .. lags, their 95 % bounds and the portmanteau p value."""
    n = e.size
    lags = min(lags, n - 2)
    if lags < 1:
        return np.zeros(0), np.zeros(0), float('nan')
    r0 = float(np.mean(np.abs(e) ** 2))
    m = np.arange(1, lags + 1)
    rho = np.array([abs(np.mean(e[:-k] * np.conj(e[k:]))) for k in m]) / max(r0, 1e-300)
    q = float(np.sum((n - m) * rho ** 2))
    return rho, np.sqrt(math.log(20.0) / (n - m)), float(stats.gamma.sf(q, lags))
