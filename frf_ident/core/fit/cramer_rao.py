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
The Cramer-Rao covariance of a least-squares fit at its minimum, from its Jacobian.

For a residual of unit variance the covariance of the parameters is (J^T J)^-1. Where two
parameters trade (a stiffness and a damping, a mode's inertia and its frequency) J^T J is
ill-conditioned, and its pseudo-inverse, computed as such, returns negative variances (40 of
the 500 Jacobians with two nearly equal columns of test/core/fit/test_cramer_rao.py, which
prints the count; a random diagnosis scene ended in a math domain error). The Gram matrix
of the Jacobian's pseudo-inverse, J^+ J^+T, is the same matrix where J has full rank and
positive semi-definite by construction wherever it has not.
"""
from __future__ import annotations

import numpy as np

__all__ = ['cramer_rao']


def cramer_rao(jac: np.ndarray) -> np.ndarray:
    """
    Return the covariance of the parameters for a unit-variance residual, J^+ J^+T.

    Parameters
    ----------
    jac : ndarray, shape (n_residuals, n_params)
        The residual's Jacobian at the minimum.

    Returns
    -------
    ndarray, shape (n_params, n_params)
        Positive semi-definite; directions the data do not determine (singular values below
        the pseudo-inverse's cutoff) get no variance, as with the pseudo-inverse of J^T J.

    Examples
    --------
    >>> cramer_rao(np.array([[2.0, 0.0], [0.0, 1.0], [0.0, 1.0]]))
    array([[0.25, 0.  ],
           [0.  , 0.5 ]])

    """
    jp = np.linalg.pinv(np.asarray(jac, float))
    return jp @ jp.T
