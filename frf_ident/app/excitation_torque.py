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
The torque of the excitation session's samples: which joint state carries it, and its gaps filled.

Sample pairing of the torque (what the chirp iteration collects; docs/CONTRACT.md §3):
lockstep -- the simulated plant answers command k with joint state k+1, whose effort is the
torque applied from t_k, so the torque of sample k is the effort of joint state k+1;
free-running -- the effort of joint state k is the torque applied at t_k (a robot's measured
torque; the free-running plant node reports it so), so the torque of sample k is in joint state k.
Every segment descriptor declares this lag (``effort_lag``); recorders keep joint states as
published and the bag reader applies it, so every recorder and replay path pairs alike.
"""
from __future__ import annotations

import numpy as np

__all__ = ['fill_torque_gaps', 'MAX_TORQUE_GAP', 'torque_sample_offset']

#: the longest run of missed joint states whose torque a chirp step fills in [samples]
MAX_TORQUE_GAP = 2


def torque_sample_offset(lockstep: bool) -> int:
    """
    Joint state k carries the torque of sample ``k - offset`` (see the module docstring).

    Parameters
    ----------
    lockstep
        True for the lockstep simulation, False free-running (real robot).

    Returns
    -------
    int
        1 in lockstep, 0 free-running.

    """
    return 1 if lockstep else 0


def fill_torque_gaps(u: np.ndarray, max_gap: int = MAX_TORQUE_GAP) -> np.ndarray:
    """
    Fill the torque samples of joint states the node missed, linearly between their neighbours.

    At an end of the segment the nearest sample is held.

    A free-running node acts on the newest joint state only, so a busy one misses some (their
    torque stays NaN). Gaps of up to ``max_gap`` samples are filled. A filled sample at a
    sine's crest at the chirp's 60 Hz and 1 kHz reads 7 % (one missed) or 16 % (two) low, but
    the step's peak and spectrum come from every sample over many cycles: with every third
    joint state missed the peak torque was 0.02 % off (test/app/test_excitation_safety.py).

    Parameters
    ----------
    u : ndarray, shape (N, n)
        Torque per sample [N m], NaN where no joint state was seen.
    max_gap : int, optional
        The longest run of missing samples that is filled.

    Returns
    -------
    ndarray, shape (N, n)
        ``u`` with its gaps filled.

    Raises
    ------
    RuntimeError
        A gap is longer than ``max_gap``.

    """
    miss = np.isnan(u).any(axis=1)
    if not miss.any():
        return u
    k = np.arange(len(u))
    edges = np.diff(np.r_[0, miss.astype(int), 0])
    longest = int((np.flatnonzero(edges < 0) - np.flatnonzero(edges > 0)).max())
    if longest > max_gap:
        raise RuntimeError(f'{int(miss.sum())} of {len(u)} torque samples missing from '
                           f'/joint_states, the longest gap {longest} samples (at most '
                           f'{max_gap} are filled): did the node fall behind '
                           'or the robot drop joint states?')
    out = u.copy()
    for j in range(u.shape[1]):
        out[miss, j] = np.interp(k[miss], k[~miss], u[~miss, j])
    return out
