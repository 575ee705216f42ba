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
A multiplicative uncertainty weight W(s) covering the FRFs of a campaign and their variance.

In the spirit of MATLAB's ``ucover``: every measured plant P_k (the poses and amplitudes of a
campaign) and the plants its estimate cannot rule out lie in the set P_0 (1 + Delta W),
|Delta| <= 1, around the nominal estimate P_0 when |W(jw)| >= r(w) at every line, with

    r(w) = max_k (|P_k - P_0| + c sigma_k) / |P_0|,

sigma_k the standard deviation of the estimate P_k and c = COVERAGE_SD (the nominal itself
contributes c sigma_0 / |P_0|). The loop C P_0 is then robustly stable for the whole set when
|W T_0| < 1 at every frequency, T_0 = C P_0 / (1 + C P_0), and the worst modulus margin over
the set is min_w (|1 + L_0| - |W L_0|).

W is a product of biproper second-order sections

    W(s) = g prod_i (s^2 + 2 zn_i wn_i s + wn_i^2) / (s^2 + 2 zd_i wd_i s + wd_i^2) wd_i^2 / wn_i^2

(stable and minimum phase: every damping is positive; zn > zd around wn = wd is the bump a
moving resonance leaves in r), fitted to log r on the measured lines with over-estimates
costing 1 and under-estimates UNDER_COST, then scaled by g so that |W| >= r holds on every
line. The lowest number of sections whose median excess over r is below EXCESS_DB is kept.
Outside the measured band W is an extrapolation: nothing was measured there.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

__all__ = ['COVERAGE_SD', 'EXCESS_DB', 'MAX_SECTIONS', 'UNDER_COST', 'UncertaintyWeight',
           'fit_weight', 'relative_bound']

#: standard deviations of an FRF estimate the uncertainty set includes (about 95 % of a
#: circular Gaussian's probability lies within 2.45 sigma; 2 per estimate keeps the set tight
#: where the spread of the poses, not the noise, dominates)
COVERAGE_SD = 2.0
#: the weight's median excess over the bound [dB] below which more sections are not tried
EXCESS_DB = 3.0
#: most second-order sections in W (order 2 MAX_SECTIONS)
MAX_SECTIONS = 3
#: residual evaluations per fit (the final gain makes any fit cover the bound; more only
#: tightens it)
MAX_EVALUATIONS = 60
#: cost of a line where the fit lies below the bound, relative to one above it: the final
#: gain lifts W over every line anyway, so a fit that dips is paid for everywhere
UNDER_COST = 10.0


def relative_bound(responses: np.ndarray, variances: np.ndarray | None, nominal: int,
                   coverage: float = COVERAGE_SD) -> np.ndarray:
    """
    Return r(w): the relative distance of every measured plant from the nominal one.

    Parameters
    ----------
    responses : ndarray of complex, shape (n_poses, n_freq)
        The FRF of one channel at every pose, on the same lines.
    variances : ndarray, shape (n_poses, n_freq), or None
        Their variances E|P_hat - P|^2 (None: the spread alone).
    nominal : int
        Index of P_0.
    coverage : float, optional
        Standard deviations of each estimate included.

    Returns
    -------
    ndarray, shape (n_freq,)
        max_k (|P_k - P_0| + c sigma_k) / |P_0|.

    """
    p = np.asarray(responses, dtype=complex)
    dist = np.abs(p - p[nominal])
    if variances is not None:
        dist = dist + coverage * np.sqrt(np.asarray(variances, dtype=float))
    return dist.max(axis=0) / np.abs(p[nominal])


@dataclass(frozen=True)
class UncertaintyWeight:
    """
    A fitted multiplicative uncertainty weight W(s) (module doc).

    Attributes
    ----------
    gain : float
        g, the low-frequency gain.
    sections : ndarray, shape (m, 4)
        Per section wn [rad/s], zn, wd [rad/s], zd.
    freq_hz : ndarray
        The lines it was fitted on [Hz].
    bound : ndarray
        r at those lines.

    """

    gain: float
    sections: np.ndarray
    freq_hz: np.ndarray
    bound: np.ndarray

    @property
    def order(self) -> int:
        """Return the number of poles."""
        return 2 * len(self.sections)

    def response(self, freq_hz: np.ndarray) -> np.ndarray:
        """Return W(j 2 pi f) (complex)."""
        s = 2j * np.pi * np.asarray(freq_hz, dtype=float)
        return self.gain * _sections(self.sections, s)

    def num_den(self) -> tuple[np.ndarray, np.ndarray]:
        """Return W's numerator and denominator polynomials, descending powers of s."""
        num, den = np.array([self.gain]), np.array([1.0])
        for wn, zn, wd, zd in self.sections:
            num = np.polymul(num, np.array([1.0, 2 * zn * wn, wn ** 2]) * wd ** 2 / wn ** 2)
            den = np.polymul(den, np.array([1.0, 2 * zd * wd, wd ** 2]))
        return num, den

    def excess_db(self) -> float:
        """Return the median of 20 log10 |W| / r over the fitted lines [dB] (>= 0)."""
        return float(np.median(20 * np.log10(np.abs(self.response(self.freq_hz)) / self.bound)))

    def summary(self) -> str:
        """Return one line for people."""
        w = np.abs(self.response(self.freq_hz))
        k = int(np.argmax(w))
        return (f'W(s) order {self.order}: |W| {w.min():.3g}-{w.max():.3g} (peak at '
                f'{self.freq_hz[k]:.3g} Hz), median {self.excess_db():.1f} dB over the bound')


def _sections(sec: np.ndarray, s: np.ndarray) -> np.ndarray:
    out = np.ones_like(s)
    for wn, zn, wd, zd in sec:
        out = out * (s ** 2 + 2 * zn * wn * s + wn ** 2) / (s ** 2 + 2 * zd * wd * s + wd ** 2) \
            * (wd ** 2 / wn ** 2)
    return out


def _fit_sections(f: np.ndarray, lr: np.ndarray, m: int, start: np.ndarray) -> np.ndarray:
    """Return x = log [g, (wn, zn, wd, zd)...] of the one-sided fit of log |W| to log r."""
    s = 2j * np.pi * f

    def parts(x):
        sec = np.exp(x[1:]).reshape(m, 4)
        wn, zn, wd, zd = (sec[:, q:q + 1] for q in range(4))
        num = s ** 2 + 2 * zn * wn * s + wn ** 2                      # (m, F)
        den = s ** 2 + 2 * zd * wd * s + wd ** 2
        e = x[0] + np.sum(np.log(np.abs(num / den)) + 2 * np.log(wd / wn), axis=0) - lr
        return sec, num, den, e

    def resid(x):
        e = parts(x)[3]
        return np.where(e < 0, UNDER_COST * e, e)

    def jac(x):
        (wn, zn, wd, zd), num, den, e = (lambda t: ((t[0][:, q:q + 1] for q in range(4)),
                                                    *t[1:]))(parts(x))
        cols = [(wn * (2 * zn * s + 2 * wn) / num).real - 2, (zn * 2 * wn * s / num).real,
                -(wd * (2 * zd * s + 2 * wd) / den).real + 2, -(zd * 2 * wd * s / den).real]
        j = np.empty((f.size, x.size))
        j[:, 0] = 1.0
        j[:, 1:] = np.stack(cols, axis=1).transpose(2, 0, 1).reshape(f.size, 4 * m)
        return np.where((e < 0)[:, None], UNDER_COST * j, j)
    w_lo, w_hi = np.log(2 * np.pi * f[0] / 10), np.log(2 * np.pi * f[-1] * 10)
    z_lo, z_hi = np.log(0.01), np.log(10.0)
    lo = np.r_[-np.inf, np.tile([w_lo, z_lo, w_lo, z_lo], m)]
    hi = np.r_[np.inf, np.tile([w_hi, z_hi, w_hi, z_hi], m)]
    x0 = np.clip(start, lo + 1e-9, hi - 1e-9)
    return optimize.least_squares(resid, x0, jac=jac, bounds=(lo, hi), method='trf',
                                  max_nfev=MAX_EVALUATIONS).x


def _starts(f: np.ndarray, lr: np.ndarray, m: int) -> list[np.ndarray]:
    """Return starts: flat sections over the band, and one peak section at the bound's top."""
    wf = 2 * np.pi * np.geomspace(f[0], f[-1], m + 2)[1:-1]
    flat = np.r_[np.median(lr), np.log(np.column_stack([wf, np.ones(m), wf, np.ones(m)]).ravel())]
    k = int(np.argmax(lr))
    peak_w = 2 * np.pi * f[k]
    height = max(float(np.exp(lr[k] - np.median(lr))), 1.0)
    sec = np.column_stack([wf, np.ones(m), wf, np.ones(m)])
    sec[0] = [peak_w, 0.5, peak_w, 0.5 / height]
    return [flat, np.r_[np.median(lr), np.log(sec.ravel())]]


def fit_weight(freq_hz: np.ndarray, bound: np.ndarray,
               max_sections: int = MAX_SECTIONS) -> UncertaintyWeight:
    """
    Fit W(s) with |W| >= ``bound`` on every line (module doc).

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Increasing lines [Hz].
    bound : ndarray, shape (n_freq,)
        r(w) > 0 (:func:`relative_bound`).
    max_sections : int, optional
        Most second-order sections tried.

    Returns
    -------
    UncertaintyWeight
        The lowest order whose median excess is below EXCESS_DB, else the lowest excess.

    Raises
    ------
    ValueError
        A bound that is not positive and finite.

    """
    f = np.asarray(freq_hz, dtype=float)
    r = np.asarray(bound, dtype=float)
    if not np.all(np.isfinite(r) & (r > 0)):
        raise ValueError('the uncertainty bound must be positive and finite on every line')
    lr = np.log(r)
    s = 2j * np.pi * f
    best = None
    for m in range(1, max_sections + 1):
        for x0 in _starts(f, lr, m):
            x = _fit_sections(f, lr, m, x0)
            sec = np.exp(x[1:]).reshape(m, 4)
            g = float(np.max(r / np.abs(_sections(sec, s))))
            w = UncertaintyWeight(g, sec, f, r)
            if best is None or w.excess_db() < best.excess_db() - 1e-9:
                best = w
        if best.excess_db() <= EXCESS_DB:
            break
    return best
