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
Periodic-disturbance compensation (Sec. 4.4 E): the constant-velocity run's series to subtract.

The run's series read sample by sample (as the paper does) or at the excited run's positions,
so that position-periodic disturbances such as torque ripple cancel.
"""
from __future__ import annotations

from typing import Any

import numpy as np


def _position_table(cv: dict[str, np.ndarray], key: str, i: int
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool] | None:
    """
    Return the constant-velocity run's series of axis i in increasing position, or None.

    (positions, values, sample indices, whether the run has a gap) over the finite samples;
    None where the run does not move monotonically (no position maps to one time).
    """
    ok = np.flatnonzero(np.isfinite(cv['q'][:, i]) & np.isfinite(cv[key][:, i]))
    qc, vc = cv['q'][ok, i], cv[key][ok, i]
    if qc.size < 2 or not (np.all(np.diff(qc) > 0) or np.all(np.diff(qc) < 0)):
        return None
    rev = qc[0] > qc[-1]
    qs, vs, idx = (qc[::-1], vc[::-1], ok[::-1]) if rev else (qc, vc, ok)
    return qs, vs, idx, bool(np.any(np.abs(np.diff(idx)) > 1))


def disturbance_at(cv: dict[str, np.ndarray], key: str, q: np.ndarray,
                   align: str, tables: dict[tuple[str, int], Any] | None = None
                   ) -> np.ndarray:
    """
    Return the constant-velocity run's series to subtract (Sec. 4.4 E).

    align 'time': sample by sample, as the paper does. 'position': per axis, the run's series
    read at the excited run's positions (the run moves monotonically, so position maps to
    time): position-periodic disturbances such as torque ripple then cancel even when the
    excited run starts a little elsewhere or the multisine displaces it. ``tables`` keeps
    each axis' :func:`_position_table` for the next segment compensated by the same run.
    """
    x = cv[key][:q.shape[0]]
    if align == 'time':
        return x
    tables = {} if tables is None else tables
    out = np.empty_like(x)
    for i in range(q.shape[1]):
        if (key, i) not in tables:
            tables[(key, i)] = _position_table(cv, key, i)
        tab = tables[(key, i)]
        if tab is None:
            out[:, i] = x[:, i]          # not monotonic: fall back to time alignment
            continue
        qs, vs, idx, gaps = tab
        out[:, i] = np.interp(q[:, i], qs, vs)
        if gaps:
            # a position the run passed during a gap has no value to subtract
            k = np.clip(np.searchsorted(qs, q[:, i]), 1, qs.size - 1)
            out[np.abs(idx[k] - idx[k - 1]) > 1, i] = np.nan
    return out
