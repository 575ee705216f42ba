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
Missing samples of a periodic record estimated from its other periods, with their uncertainty.

The local model of the Local Polynomial Method with missing data (Ugryumova, Pintelon and
Vandersteen, IEEE TIM 2015; Pintelon and Schoukens 2012, ch. 7) for P steady-state periods
of a periodic excitation: in the DFT of the whole record (P periods, N = P n samples) the
lines k = P h carry the periodic response, each with its own free value (the BLA is
nonparametric: no polynomial ties neighbouring harmonics), and every other line carries
what is not periodic. The missing samples x are extra real unknowns: with Z0 the DFT of the
record with zeros at them and E the DFT of unit samples at their instants, for white noise
they minimise the energy at the non-harmonic lines,

    min_x || P_nh (Z0 + E x) ||^2,

whose solution in the time domain is the mean over the periods in which that sample of the
period is present (the projection onto the periodic signals is the mean over periods, phase
by phase). What is not periodic is not always white: a drift, an imperfect compensation or
the tail of a transient changes slowly, and the other periods' mean misses it. Like the
LPM's transient term in frequency, a local polynomial in time models it: a straight line
through the residual (record minus period mean) on both sides of each gap, its value in the
gap added (:data:`TREND_SIDE_SAMPLES`). :func:`fill_periods` computes this, with

- the noise variance from the spread over the present samples about the period mean, with
  its degrees of freedom sum_phi (n_phi - 1) (the dof correction: each estimated sample uses
  one);
- the standard deviation of an estimate minus the true sample, sigma sqrt(1 + 1/n_phi + h)
  (its own noise is unobserved; 1/n_phi is the diagonal of sigma^2 (E^H P_nh E)^-1 - 1 at
  that phase, h the leverage of the line's prediction);
- what the BLA's spread over periods needs to stay unbiased: each period's share of estimated
  samples (:attr:`PeriodicFill.lost`, the dof it loses) and the variance of the period mean
  over that of a record without gaps (:attr:`PeriodicFill.factor`, mean over phases of
  P / n_phi).

``test/core/estimation/test_missing_periodic.py`` checks the period mean against the least-
squares solution written with explicit DFT matrices, and the standard deviations and the
BLA's variance against Monte-Carlo runs.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from frf_ident.core.estimation.missing import MissingSamples
import numpy as np

__all__ = ['FilledPeriods', 'GAP_HINT', 'PeriodicFill', 'fill_periods', 'fill_steady_periods']

#: the residual's straight line across a gap is fitted to the present samples within the
#: gap's length on each side, at least this many (a line through 16 white samples on each side
#: predicts the middle of a short gap with about 1/32 of the residual's variance)
TREND_SIDE_SAMPLES = 16

#: what a refusal says when the periods a gap touched had to be dropped after all
GAP_HINT = ('a missing sample is estimated from the other periods, so each sample of the period '
            'must be present in at least one of them')


@dataclass(frozen=True)
class FilledPeriods:
    """
    What estimated samples do to the spread over periods of the periods an estimate uses.

    Parameters
    ----------
    lost : ndarray, shape (n_q,)
        Per period, its estimated samples over the period length: the degrees of freedom of
        the spread over periods it loses (an estimate equals the period mean).
    factor : ndarray, shape (n_q,)
        Per period, :attr:`PeriodicFill.factor` of the periods it was estimated with: the
        variance of their mean over that without gaps.

    """

    lost: np.ndarray
    factor: np.ndarray

    def spread_scale(self) -> float:
        """
        Return what the gap-free variance of the mean from the spread is multiplied by.

        The spread over the n periods, sum |X_q - mean|^2 / (n - 1) / n, then estimates the
        variance of their mean: (n - 1) / (n - 1 - sum lost) corrects the dof, the mean factor
        the variance of a mean of fewer samples at the estimated phases.

        Returns
        -------
        float
            1 without estimated samples; inf when no dof is left.

        """
        n = self.lost.size
        dof = n - 1 - float(np.sum(self.lost))
        return (n - 1) / dof * float(np.mean(self.factor)) if dof > 0 else np.inf


@dataclass
class PeriodicFill:
    """
    A periodic record with its missing samples estimated from the other periods.

    Parameters
    ----------
    values : ndarray, shape (n_q, n_per, n_ch)
        The record with every fillable missing sample estimated (NaN where a sample is missing
        in all averaged periods, and where the record had NaN outside its gaps).
    missing : ndarray of bool, shape (n_q, n_per)
        The samples that were missing.
    count : ndarray of int, shape (n_per,)
        Averaged periods in which each sample of the period is present (n_phi).
    average : ndarray of bool, shape (n_q,)
        The periods the estimate averages over (the steady ones).
    noise_ss : ndarray, shape (n_ch,)
        Sum of squares of the present samples about the period mean (averaged periods).
    noise_dof : int
        Its degrees of freedom, sum over phases of (n_phi - 1).
    leverage : ndarray, shape (n_q, n_per)
        At each missing sample, the variance of the predicted non-periodic part over the
        residual's (0 elsewhere).

    """

    values: np.ndarray
    missing: np.ndarray
    count: np.ndarray
    average: np.ndarray
    noise_ss: np.ndarray
    noise_dof: int
    leverage: np.ndarray

    @property
    def complete(self) -> bool:
        """Whether every missing sample was estimated (each present in an averaged period)."""
        return not np.any(self.missing.any(axis=0) & (self.count == 0))

    @property
    def lost(self) -> np.ndarray:
        """Estimated samples of each period over the period length: the dof each one loses."""
        return self.missing.sum(axis=1) / self.missing.shape[1]

    @property
    def factor(self) -> float:
        """
        Variance of the mean over the averaged periods over that without gaps (>= 1).

        The period mean at phase phi averages n_phi present samples instead of P: its noise
        variance is sigma^2 / n_phi instead of sigma^2 / P; over a band the mean over phases
        (white noise; close for noise correlated over much less than a gap or much more).
        """
        n_a = int(self.average.sum())
        c = self.count[self.count > 0]
        return float(np.mean(n_a / c)) if c.size else 1.0

    @property
    def noise_sd(self) -> np.ndarray:
        """Per-sample noise standard deviation of each channel (nan without a dof)."""
        if self.noise_dof < 1:
            return np.full(self.noise_ss.shape, np.nan)
        return np.sqrt(self.noise_ss / self.noise_dof)

    def periods(self) -> FilledPeriods:
        """
        Return every period's share of estimated samples, with this fill's factor.

        Returns
        -------
        FilledPeriods

        """
        return FilledPeriods(self.lost, np.full(self.lost.size, self.factor))

    def sd(self) -> np.ndarray:
        """
        Return the standard deviation of each estimate minus the true sample.

        Returns
        -------
        ndarray, shape (n_missing, n_ch)
            sigma sqrt(1 + 1/n_phi) per missing sample (in the order of
            ``np.nonzero(missing)``), nan where it was not estimated.

        """
        q, phi = np.nonzero(self.missing)
        n = self.count[phi].astype(float)
        with np.errstate(divide='ignore'):
            k = np.where(n > 0, np.sqrt(1.0 + 1.0 / n + self.leverage[q, phi]), np.nan)
        return k[:, None] * self.noise_sd[None, :]

    def account(self, channels: list[str], *, keep: np.ndarray | None = None,
                periods: np.ndarray | None = None) -> MissingSamples:
        """
        Return the :class:`~frf_ident.core.estimation.missing.MissingSamples` of these periods.

        Parameters
        ----------
        channels : list of str
            Names of the channels of ``values``.
        keep : ndarray of bool, shape (n_ch,), optional
            The channels to account for (e.g. the noisy ones, not an exact reference).
        periods : ndarray of bool, shape (n_q,), optional
            The periods to account for (default all).

        Returns
        -------
        MissingSamples

        """
        keep = np.ones(len(channels), bool) if keep is None else np.asarray(keep, bool)
        periods = np.ones(self.missing.shape[0], bool) if periods is None else \
            np.asarray(periods, bool)
        q = np.nonzero(self.missing)[0]
        sd = self.sd()[periods[q]][:, keep]
        miss = self.missing[periods]
        return MissingSamples(
            int(miss.sum()), miss.size, int(miss.any(axis=1).sum()), int(periods.sum()),
            'period', [c for c, k in zip(channels, keep) if k],
            np.nansum(sd ** 2, axis=0), self.noise_ss[keep],
            np.full(int(keep.sum()), float(self.noise_dof)), 'periodic')


def fill_periods(x: np.ndarray, missing: np.ndarray, *, average: np.ndarray | None = None,
                 trend: bool = True) -> PeriodicFill:
    """
    Estimate the missing samples of consecutive periods from the other periods.

    Parameters
    ----------
    x : array_like, shape (n_q, n_per, n_ch)
        The periods (any values at the missing samples, typically NaN). A channel that is NaN
        throughout (an interface the robot does not publish) stays NaN.
    missing : array_like of bool, shape (n_q, n_per)
        True at the samples a gap removed.
    average : array_like of bool, shape (n_q,), optional
        The periods to average over (the steady ones); default all. Periods left out are
        filled too (from the averaged ones) but not used for the estimate.
    trend : bool
        Add the non-periodic part predicted by a straight line across each gap (False: the
        period mean alone, the solution for white noise).

    Returns
    -------
    PeriodicFill
        The record with its missing samples estimated, the counts and the noise level.

    Examples
    --------
    >>> x = np.array([[1.0, 2.0], [np.nan, 2.2], [1.2, 1.8]])[:, :, None]   # 3 periods of 2
    >>> f = fill_periods(x, np.isnan(x[:, :, 0]), trend=False)
    >>> float(f.values[1, 0, 0]), f.count.tolist(), f.noise_dof
    (1.1, [2, 3], 3)

    """
    x = np.asarray(x, dtype=float)
    missing = np.asarray(missing, dtype=bool)
    n_q = x.shape[0]
    average = np.ones(n_q, bool) if average is None else np.asarray(average, bool)
    present = ~missing & average[:, None]                            # (n_q, n_per)
    count = present.sum(axis=0)
    with np.errstate(invalid='ignore'):
        xs = np.where(present[:, :, None], x, 0.0)
        mean = xs.sum(axis=0) / np.maximum(count, 1)[:, None]         # (n_per, n_ch)
    dev = np.where(present[:, :, None], x - mean[None], 0.0)
    noise_ss = np.sum(dev ** 2, axis=(0, 1))
    dof = int(np.sum(np.maximum(count - 1, 0)))
    line, leverage = _residual_trend(np.where(missing[:, :, None], np.nan, x - mean[None]),
                                     missing) if trend else (0.0, np.zeros(missing.shape))
    values = np.where(missing[:, :, None], np.where(count[None, :, None] > 0,
                                                    mean[None] + line, np.nan), x)
    return PeriodicFill(values, missing, count, average, noise_ss, dof, leverage)


def _residual_trend(res: np.ndarray, missing: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the non-periodic part predicted in each gap, and its leverage.

    ``res`` (n_q, n_per, n_ch) is the record minus the period mean (NaN at the missing
    samples). Per gap (a run of missing samples in time order) a straight line is fitted to
    the residual on :func:`_sides` of it (a constant where one side is outside the record)
    and its value taken in the gap; the leverage h is x0 (X^T X)^-1 x0^T of each predicted
    sample (the variance of the prediction over the residual's, white residual).
    """
    shape = missing.shape
    r = res.reshape(-1, res.shape[2])
    gone = missing.ravel()
    trend = np.zeros_like(r)
    lev = np.zeros(gone.size)
    cols = np.isfinite(r[~gone]).all(axis=0) if np.any(~gone) else np.zeros(r.shape[1], bool)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], gone.astype(np.int8), [0]])))
    for a, b in zip(edges[::2], edges[1::2]):
        fit = _sides(gone, a, b)
        if fit.size == 0:
            continue
        gap = np.arange(a, b)
        c = 0.5 * (a + b - 1)
        both = fit.min() < a < b <= fit.max()
        X = np.stack([np.ones(fit.size), fit - c], axis=1) if both else np.ones((fit.size, 1))
        X0 = np.stack([np.ones(gap.size), gap - c], axis=1) if both else np.ones((gap.size, 1))
        inv = np.linalg.inv(X.T @ X)
        coef = inv @ X.T @ r[fit][:, cols]
        trend[a:b, cols] = X0 @ coef
        lev[a:b] = np.einsum('ij,jk,ik->i', X0, inv, X0)
    return trend.reshape(res.shape), lev.reshape(shape)


def _sides(gone: np.ndarray, a: int, b: int) -> np.ndarray:
    """Present samples within max(gap, TREND_SIDE_SAMPLES) before a and after b."""
    n = max(b - a, TREND_SIDE_SAMPLES)
    idx = np.concatenate([np.arange(max(0, a - n), a), np.arange(b, min(gone.size, b + n))])
    return idx[~gone[idx]]


def fill_steady_periods(x: np.ndarray, missing: np.ndarray,
                        first_steady: Callable[[np.ndarray], int] | None = None
                        ) -> PeriodicFill:
    """
    Estimate missing samples from the steady periods of a record that may start settling.

    A start-up transient in the first periods would pass into every estimate averaged over
    them: the record is filled from all periods first, ``first_steady`` finds the first
    steady period of that, and the record is filled again from the periods from there (when
    every missing sample is present in one of them).

    Parameters
    ----------
    x, missing
        As :func:`fill_periods`.
    first_steady : callable, optional
        Filled periods (n_q, n_per, n_ch) -> index of the first steady period (a transient
        test); None: all periods are steady.

    Returns
    -------
    PeriodicFill

    """
    fill = fill_periods(x, missing)
    if first_steady is None or not fill.complete:
        return fill
    first = int(first_steady(fill.values))
    if first == 0:
        return fill
    again = fill_periods(x, missing, average=np.arange(x.shape[0]) >= first)
    return again if again.complete else fill
