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
The noise the record's repeated multisine periods show.

The raw material of the noise floors every misfit of :class:`.evaluator.Evaluator` is
measured in: velocity and torque noise variance per axis.
"""
from __future__ import annotations

from frf_ident.core.recording import Recording
import numpy as np

__all__ = ['period_noise']


def period_noise(rec: Recording, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the noise variance of velocity and effort per axis from the multisine periods.

    Noise variance of velocity and effort per axis measured from the multisine periods:
    half the mean square difference of consecutive steady-state periods (periodic signal
    cancels, noise doubles). NaN where the recording has no repeated periods.
    """
    dv, du = [], []
    for s in rec.segments:
        info = s.info
        if info.get('design') != 'multisine' or int(info.get('periods', 0)) < 2:
            continue
        P = int(info.get('period_samples', 0))
        sl = rec.slice(s.t_start, s.t_end)
        k0 = sl.start + P * int(info.get('transient_periods', 0))
        k1 = min(sl.stop, sl.start + P * (int(info.get('transient_periods', 0))
                                          + int(info['periods'])))
        if P < 2 or k1 - k0 < 2 * P or not mask[k0:k1].all():
            continue
        dv.append(rec.velocity[k0 + P:k1] - rec.velocity[k0:k1 - P])
        du.append(rec.effort[k0 + P:k1] - rec.effort[k0:k1 - P])
    n = rec.velocity.shape[1]
    if not dv:
        return np.full(n, np.nan), np.full(n, np.nan)
    return (0.5 * np.mean(np.concatenate(dv) ** 2, axis=0),
            0.5 * np.mean(np.concatenate(du) ** 2, axis=0))
