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
Standard errors that cover a model error: the parameter shifts a missing structure can cause.

Where the cost test fails (:mod:`frf_ident.core.fit.cost`) the residual holds structure the
model lacks, and the Cramer-Rao errors describe the noise only. Part of that structure the fit
has absorbed into its parameters (that part is the bias), and the residual cannot show it: at
the minimum the residual is orthogonal to every parameter's column of the Jacobian. So the
bias is bounded through assumed shapes of the model error:

- a shape is a smooth relative error of one channel, ``delta(f) P(f)`` with ``delta`` a hat
  function of log frequency (:data:`SHAPES` knots over the fitted band), real or imaginary;
- of the excess cost ``cost - dof`` (what the noise does not explain), the whole is put on one
  shape at a time: the amplitude c_j that makes the shape's *visible* part (what the fit's
  parameters cannot absorb) that large, ``c_j^2 |(I - H) B_j|^2 = cost - dof``;
- its absorbed part shifts the parameters by ``S_j = J^+ B_j c_j`` (``J^+`` the pseudo-inverse
  of the normalised Jacobian): the bias such a model error would leave;
- a parameter's (or a derived quantity's) model-error bound is the largest shift over the
  shapes, added in quadrature to its Cramer-Rao error (:func:`bound`).

The worst single shape rather than their sum: the excess is explained once. Calibrated by
Monte-Carlo on the reference plant of test/plants/reference.py with an extra link-side mode
the two-mass model lacks (test/core/fit/test_model_error.py, docs/fit.md): with these shapes
the true parameters lie within two reported errors in >= 90 % of the runs, where the Cramer-Rao
errors cover a few per cent. Shapes the parameters absorb almost wholly
(:data:`VISIBLE_FLOOR`) are left out: the data cannot tell them from a parameter change, so
any excess is no evidence of their size.
"""
from __future__ import annotations

import numpy as np

__all__ = ['SHAPES', 'VISIBLE_FLOOR', 'bound', 'shape_basis', 'shifts']

#: knots of the hat functions over log frequency that shape a relative model error: 4 (three
#: pieces over the band) covered the reference plant's missing mode at 10-25 Hz in the
#: 1-40 Hz band; 8 or more shapes narrower than the mode's effect and missed its bias by up to
#: 2.4 reported errors (the Monte-Carlo of test/core/fit/test_model_error.py)
SHAPES = 4
#: shapes whose visible share |(I - H) B|^2 / |B|^2 lies below this are left out: the fit's
#: parameters describe them, and dividing the excess by a vanishing visible part would make
#: the bound arbitrary
VISIBLE_FLOOR = 1e-3


def shape_basis(freq_hz: np.ndarray, model: np.ndarray, weight: np.ndarray,
                knots: int = SHAPES) -> np.ndarray:
    """
    Return the model-error shapes in the layout of a normalised residual.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        The fitted lines [Hz] (positive).
    model : ndarray of complex, shape (n_channels, n_freq)
        The fitted model of every channel.
    weight : ndarray, shape (n_channels, n_freq)
        The residual's weight sqrt(2) / sigma of every line.
    knots : int, optional
        Hat functions over log frequency per channel.

    Returns
    -------
    ndarray, shape (2 n_channels n_freq, 2 knots n_channels)
        Columns: per channel and knot, the relative error delta P (real delta), then
        j delta P (imaginary delta); rows [real parts; imaginary parts] of the channels'
        lines in order, as :func:`~frf_ident.core.fit.cost.normalised_residual` stacks them.

    """
    x = np.log(np.asarray(freq_hz, dtype=float))
    centres = np.linspace(x.min(), x.max(), knots)
    width = centres[1] - centres[0] if knots > 1 and x.max() > x.min() else 1.0
    hats = np.clip(1.0 - np.abs(x[:, None] - centres[None]) / width, 0.0, None)  # (F, K)
    n_ch, nf = model.shape
    cols = np.zeros((n_ch, nf, n_ch, 2, knots), dtype=complex)
    base = model * weight
    for c in range(n_ch):
        cols[c, :, c, 0] = base[c][:, None] * hats
        cols[c, :, c, 1] = 1j * base[c][:, None] * hats
    b = cols.reshape(n_ch * nf, -1)
    return np.vstack([b.real, b.imag])


def shifts(jacobian: np.ndarray, basis: np.ndarray, excess: float) -> np.ndarray:
    """
    Return the parameter shift each model-error shape explaining the excess cost would cause.

    Parameters
    ----------
    jacobian : ndarray, shape (n_res, n_par)
        Jacobian of the normalised residual at the minimum (parameters in their own units).
    basis : ndarray, shape (n_res, n_shapes)
        The shapes (:func:`shape_basis`).
    excess : float
        Cost minus degrees of freedom (0 or less: no model error, zero shifts).

    Returns
    -------
    ndarray, shape (n_par, n_shapes)
        Column j: the shift J^+ B_j c_j (zero for shapes below :data:`VISIBLE_FLOOR`).

    """
    n_par = jacobian.shape[1]
    if not excess > 0:
        return np.zeros((n_par, basis.shape[1]))
    q, r = np.linalg.qr(jacobian)
    visible = basis - q @ (q.T @ basis)
    vis2 = np.sum(visible ** 2, axis=0)
    tot2 = np.sum(basis ** 2, axis=0)
    keep = vis2 > VISIBLE_FLOOR * tot2
    amp = np.zeros(basis.shape[1])
    amp[keep] = np.sqrt(excess / vis2[keep])
    absorbed = np.linalg.lstsq(r, q.T @ basis, rcond=None)[0]      # J^+ B, (n_par, n_shapes)
    return absorbed * amp[None, :]


def bound(shift: np.ndarray, gradient: np.ndarray | None = None) -> np.ndarray:
    """
    Return the model-error bound of the parameters, or of quantities derived from them.

    Parameters
    ----------
    shift : ndarray, shape (n_par, n_shapes)
        From :func:`shifts`.
    gradient : ndarray, shape (n_q, n_par), optional
        d quantity / d parameter of derived quantities (default: the parameters themselves).

    Returns
    -------
    ndarray, shape (n_q,) or (n_par,)
        The largest absolute shift over the shapes.

    """
    moved = shift if gradient is None else np.asarray(gradient) @ shift
    if moved.shape[-1] == 0:
        return np.zeros(moved.shape[0])
    return np.max(np.abs(moved), axis=-1)
