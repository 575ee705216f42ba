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
The cost-function test: is the residual of a fit what the FRF noise explains.

With the residual of every frequency line divided by the FRF's standard deviation (its real
and imaginary parts scaled to unit variance, see :func:`normalised_residual`), the minimum of
the maximum-likelihood cost follows a chi-square law with 2 F - p degrees of freedom (F lines,
p parameters) when the model structure is right (Pintelon & Schoukens, System Identification,
2nd ed., Sec. 9.5 / 19.4). A cost far above that says the model lacks structure (a mode, a
delay) that the data show; this module only decides and reports, the fits compute.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

__all__ = ['CostTest', 'MISSING_STRUCTURE_ALPHA', 'cost_test', 'normalised_residual']

#: false-alarm probability of the test: a cost above the chi-square (1 - alpha) quantile
#: flags missing structure. 1e-3 keeps the false-alarm rate of a right model low even when
#: the variance came from a handful of periods (which makes the cost's tail a little heavier
#: than chi-square); the missing second mode of the tests exceeds it by orders of magnitude.
MISSING_STRUCTURE_ALPHA = 1e-3


@dataclass(frozen=True)
class CostTest:
    """
    The minimum ML cost of a fit beside its chi-square expectation.

    Attributes
    ----------
    cost : float
        Sum of the squared normalised residuals (real and imaginary parts).
    dof : int
        Degrees of freedom 2 F - p: the cost's expectation for a right model.
    p_value : float
        Probability of a cost this large or larger for a right model; NaN without variance.
    limit : float
        The (1 - :data:`MISSING_STRUCTURE_ALPHA`) quantile of chi-square(dof).
    weighted : bool
        True when the FRF's own variance weighted the residual; False when no variance
        was available (then the test cannot decide and ``structure_missing`` is False).

    """

    cost: float
    dof: int
    p_value: float
    limit: float
    weighted: bool

    @property
    def ratio(self) -> float:
        """Return cost / dof: about 1 for a right model, far above 1 when structure is missing."""
        return self.cost / max(self.dof, 1)

    @property
    def structure_missing(self) -> bool:
        """Return True when the cost exceeds its limit (only with a weighted residual)."""
        return self.weighted and self.cost > self.limit

    @property
    def verdict(self) -> str:
        """
        Return what the errors mean, in one line.

        'parameters describe the data' where the noise explains the residual; 'structure
        missing: treat errors as lower bounds' where it does not (the reported errors then
        include the model-error bound of :mod:`frf_ident.core.fit.model_error`, which assumes
        a smooth model error); without variance the test cannot decide.
        """
        if not self.weighted:
            return 'no FRF variance: the cost test cannot decide; errors from the residual'
        if self.structure_missing:
            return 'structure missing: treat errors as lower bounds'
        return 'parameters describe the data'

    def summary(self) -> str:
        """Return one line for people: cost, expectation and the verdict."""
        if not self.weighted:
            return (f'cost {self.cost:.3g} (no FRF variance: the cost test cannot decide, '
                    f'standard errors from the residual)')
        verdict = ('structure missing' if self.structure_missing
                   else 'residual explained by the noise')
        return (f'cost {self.cost:.1f} vs chi2({self.dof}) limit {self.limit:.1f} '
                f'(ratio {self.ratio:.2f}, p={self.p_value:.2g}): {verdict}')


def normalised_residual(model: np.ndarray, measured: np.ndarray,
                        variance: np.ndarray | None) -> np.ndarray:
    """
    Return the real residual vector whose entries have unit variance under the noise.

    Parameters
    ----------
    model, measured : ndarray of complex, shape (n_freq,)
        Model and measured FRF.
    variance : ndarray, shape (n_freq,), or None
        Variance E|P_hat - P|^2 of the measured FRF (a circular complex error: half of it in
        the real part, half in the imaginary part). None: a relative error |P_hat| is
        assumed instead (the residual is then not unit-variance; see :class:`CostTest`).

    Returns
    -------
    ndarray, shape (2 n_freq,)
        sqrt(2) [Re e, Im e] / sigma with e = model - measured.

    """
    sigma = np.sqrt(variance) if variance is not None else np.abs(measured)
    e = (model - measured) * (np.sqrt(2.0) / sigma)
    return np.concatenate([e.real, e.imag])


def cost_test(residual: np.ndarray, n_params: int, weighted: bool) -> CostTest:
    """
    Test the minimum cost of a fit against chi-square(2 F - p).

    Parameters
    ----------
    residual : ndarray, shape (2 F,)
        The normalised residual at the minimum (:func:`normalised_residual`).
    n_params : int
        Number p of fitted real parameters.
    weighted : bool
        Whether the residual was normalised by the FRF's variance.

    Returns
    -------
    CostTest
        The cost, its degrees of freedom, p-value and limit.

    """
    cost = float(np.sum(residual ** 2))
    dof = int(residual.size - n_params)
    if dof < 1:
        return CostTest(cost, dof, float('nan'), float('nan'), weighted)
    p = float(stats.chi2.sf(cost, dof)) if weighted else float('nan')
    limit = float(stats.chi2.isf(MISSING_STRUCTURE_ALPHA, dof))
    return CostTest(cost, dof, p, limit, weighted)
