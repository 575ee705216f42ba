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
A fitted rational model as python-control objects and as a MATLAB .mat file.

The model is :class:`~frf_ident.core.fit.rational.RationalFit` (common denominator,
continuous time). ``model.mat`` variables: ``A``, ``B``, ``C``, ``D`` (the realisation of
:meth:`RationalFit.state_space`, continuous time, SI units of the FRF), ``Num``
(n_out, n_in, n_num + 1) and ``Den`` (1, order + 1) in descending powers of s, ``InputName``,
``OutputName`` (cell arrays) and ``Ts`` 0; in MATLAB: ``S = load('model.mat');
sys = ss(S.A, S.B, S.C, S.D)``.
"""
from __future__ import annotations

import os
from pathlib import Path

from frf_ident.core.fit.rational import RationalFit
import numpy as np

__all__ = ['to_state_space', 'to_transfer_function', 'write_lti_mat']


def to_transfer_function(fit: RationalFit):
    """
    Return the fitted model as a python-control ``TransferFunction``.

    Parameters
    ----------
    fit : RationalFit
        The fitted model.

    Returns
    -------
    control.TransferFunction
        Continuous time, numerators N_ij and the shared denominator, channel names as labels.

    """
    import control
    num, den = fit.num, fit.den
    n_out, n_in, _ = num.shape
    return control.tf([[list(num[i, j]) for j in range(n_in)] for i in range(n_out)],
                      [[list(den) for _ in range(n_in)] for _ in range(n_out)],
                      inputs=list(fit.inputs), outputs=list(fit.outputs))


def to_state_space(fit: RationalFit):
    """
    Return the fitted model as a python-control ``StateSpace``.

    Parameters
    ----------
    fit : RationalFit
        The fitted model.

    Returns
    -------
    control.StateSpace
        The realisation (A, B, C, D) of :meth:`RationalFit.state_space`, channel names as
        labels.

    """
    import control
    A, B, C, D = fit.state_space()
    return control.ss(A, B, C, D, inputs=list(fit.inputs), outputs=list(fit.outputs))


def write_lti_mat(fit: RationalFit, path: str | os.PathLike[str]) -> Path:
    """
    Write the fitted model to a MATLAB v5 file (variables in the module doc).

    Parameters
    ----------
    fit : RationalFit
        The fitted model.
    path : str or os.PathLike
        File to write (overwritten).

    Returns
    -------
    Path
        ``path``.

    """
    from scipy.io import savemat
    A, B, C, D = fit.state_space()
    path = Path(path)
    savemat(path, {'A': A, 'B': B, 'C': C, 'D': D, 'Num': fit.num,
                   'Den': fit.den.reshape(1, -1), 'Ts': 0.0,
                   'InputName': np.array(list(fit.inputs), dtype=object).reshape(-1, 1),
                   'OutputName': np.array(list(fit.outputs), dtype=object).reshape(-1, 1)},
            oned_as='column')
    return path
