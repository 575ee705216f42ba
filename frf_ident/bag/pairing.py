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
The one pairing rule of state and effort (docs/CONTRACT.md §3, "Pairing of state and effort").

A bag holds /joint_states as they were published, by every recorder (``ros2 bag record``, the
estimator node, ``ros2 bag play`` into either, with or without ``--clock``): nobody re-pairs.
Which sample a joint state's effort belongs to is the producer's to say: every segment
descriptor of the excitation node carries ``effort_lag`` = L, meaning the effort of joint
state k is the torque applied from t_(k-L). The lockstep simulation answers command k with
joint state k+1 (L = 1); a robot, and the free-running plant, report in joint state k the
torque applied from t_k (L = 0, also when no descriptor says anything). The reader applies L
once, so every path gives the recording convention (y_k and u_k at t_k) and the same phase.
"""
from __future__ import annotations

from frf_ident.core.recording import Segment
from frf_ident.errors import BagError
import numpy as np

#: descriptor key (Segment.info) of the effort lag [samples]
KEY = 'effort_lag'
#: the lags a producer may declare: 0 (robot, free-running), 1 (lockstep simulation)
LAGS = (0, 1)


def effort_lag(segments: list[Segment], where: str) -> int:
    """
    Return the effort lag [samples] the descriptors declare (0 when none does).

    Parameters
    ----------
    segments
        The recording's segments (from /frf/experiment).
    where
        Bag name for the error message.

    Returns
    -------
    int
        L: the effort of joint state k is the torque applied from t_(k-L).

    Raises
    ------
    BagError
        The descriptors disagree, or declare a lag other than 0 or 1.

    """
    lags = sorted({s.info[KEY] for s in segments if KEY in s.info}, key=str)
    if not lags:
        return 0
    if len(lags) > 1 or lags[0] not in LAGS:
        raise BagError(f'{where}: /frf/experiment descriptors declare {KEY}={lags}; expected '
                       f'one of {list(LAGS)} for the whole bag (joint-state effort k is the '
                       f'torque of sample k - {KEY})')
    return int(lags[0])


def align_effort(effort: np.ndarray, lag: int) -> np.ndarray:
    """
    Return the effort of each sample k: joint state k + ``lag``'s (the last keeps its own).

    Parameters
    ----------
    effort
        Joint-state effort per sample, shape (N, n) [N m].
    lag
        Declared effort lag [samples] (0 or 1).

    Returns
    -------
    ndarray, shape (N, n)
        The effort on the recording convention (torque applied from t_k at row k).

    """
    if lag == 0 or effort.shape[0] < 2:
        return effort
    out = effort.copy()
    out[:-lag] = effort[lag:]
    return out
