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
Steady-state periods of a periodic record: a transient test on consecutive periods.

A record of a periodic excitation that was not designed here (an import, a robot's own bag)
may start with the system's response still settling. In steady state two consecutive
periods differ by noise only, so the energy of their difference is that of the later pairs;
a start-up transient adds its own (it decays: the first pairs differ most). Leading periods
whose difference from the next stands out against the later pairs (an F test at the false
alarm rate :data:`TRANSIENT_ALPHA`) are transient and left out; the last period is never
dropped. With fewer than three periods there is no later pair to compare with: nothing is
dropped and :attr:`SteadyState.tested` says so.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

__all__ = ['REFERENCE_PAIRS', 'TRANSIENT_ALPHA', 'SteadyState', 'steady_periods']

#: false-alarm probability of calling a steady period transient (per record, split over
#: the channels): 1e-3 keeps a steady record whole in all but one of a thousand records;
#: a transient 3 dB above the noise of a 100-line band already exceeds the threshold
TRANSIENT_ALPHA = 1e-3

#: a pair of periods is compared with (at most) this many pairs after it: the decision on
#: a period then depends on the periods near it only, so a record and its first part (a
#: streamed block) decide alike; 4 pairs give the reference 8 (lines x 2) degrees of freedom
#: per line, enough for an F threshold below 2x on a band of 50 lines
REFERENCE_PAIRS = 4


@dataclass(frozen=True)
class SteadyState:
    """
    Which periods of a periodic record are in steady state.

    Parameters
    ----------
    first : int
        Index of the first steady period (the number of transient periods before it).
    n_periods : int
        Periods tested.
    ratio : ndarray, shape (n_periods - 1,)
        Energy of the difference of period q and q + 1 over the mean energy of the later
        differences (largest over the channels); nan for the last pair.
    threshold : ndarray, shape (n_periods - 1,)
        The ratio above which pair q is called transient (F test); nan for the last pair.
    tested : bool
        False with fewer than three periods (nothing to compare with; nothing dropped).

    """

    first: int
    n_periods: int
    ratio: np.ndarray
    threshold: np.ndarray
    tested: bool

    @property
    def steady(self) -> int:
        """Return the number of steady periods (from ``first`` to the last)."""
        return self.n_periods - self.first

    def describe(self) -> str:
        """
        One sentence: how many periods were transient and why.

        Returns
        -------
        str
            e.g. 'transient test: period 1 of 3 differs from the next by 41x the later
            periods' difference (threshold 1.4x): 2 steady periods used'.

        """
        if not self.tested:
            return (f'transient test: {self.n_periods} period(s), too few to compare (needs '
                    f'3); all used')
        if self.first == 0:
            return (f'transient test: all {self.n_periods} periods steady (first difference '
                    f'{self.ratio[0]:.2g}x the later ones, threshold {self.threshold[0]:.2g}x)')
        worst = ', '.join(f'{r:.3g}x' for r in self.ratio[:self.first])
        return (f'transient test: period(s) 1..{self.first} of {self.n_periods} differ from '
                f"the next by {worst} the later periods' difference (threshold "
                f'{self.threshold[0]:.2g}x): {self.steady} steady periods used')


def _effective_lines(w: np.ndarray) -> float:
    """Equivalent number of independent lines of a sum with line powers ``w``."""
    s = float(np.sum(w))
    return max(1.0, s * s / max(float(np.sum(w * w)), 1e-300))


def steady_periods(spectra: np.ndarray, *, alpha: float = TRANSIENT_ALPHA) -> SteadyState:
    """
    Find the first steady-state period of consecutive period spectra.

    The difference energy d_q = sum_k |X_{q+1,k} - X_{q,k}|^2 (per channel, over the lines
    k) of pair q is compared with the mean d of the next :data:`REFERENCE_PAIRS` pairs (of
    the later ones, fewer at the end); in steady state the ratio
    is F-distributed with 2 K and 2 K m degrees of freedom (K the effective number of lines,
    m the later pairs). Pair q above the 1 - alpha / n_channels quantile makes period q
    transient; the test goes on with the next pair and stops at the first steady one.

    Parameters
    ----------
    spectra : ndarray, shape (n_periods, n_lines, n_channels)
        DFT of consecutive periods (complex) at the analysed lines, e.g. inputs and outputs
        side by side.
    alpha : float, optional
        False-alarm probability of the test.

    Returns
    -------
    SteadyState
        The first steady period and the test's numbers.

    """
    X = np.asarray(spectra)
    if X.ndim == 2:
        X = X[:, :, None]
    n_q, _, n_ch = X.shape
    nan = np.full(max(n_q - 1, 0), np.nan)
    if n_q < 3:
        return SteadyState(0, n_q, nan, nan.copy(), False)
    diff = np.abs(np.diff(X, axis=0)) ** 2                 # (n_q - 1, lines, channels)
    d = diff.sum(axis=1)                                   # (n_q - 1, channels)
    ratio, threshold = nan.copy(), nan.copy()
    first = 0
    for q in range(n_q - 2):
        later = diff[q + 1:q + 1 + REFERENCE_PAIRS]
        ref = later.sum(axis=1).mean(axis=0)               # (channels,)
        k = np.array([_effective_lines(later[:, :, c].mean(axis=0)) for c in range(n_ch)])
        m = later.shape[0]
        live = ref > 0
        r = np.where(live, d[q] / np.where(live, ref, 1.0), 0.0)
        c = stats.f.ppf(1.0 - alpha / n_ch, 2 * k, 2 * k * m)
        ratio[q] = float(np.max(r))
        threshold[q] = float(c[int(np.argmax(r / c))])
        if np.any(r > c):
            first = q + 1
        else:
            break
    return SteadyState(first, n_q, ratio, threshold, True)
