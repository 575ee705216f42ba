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
Period and experiment counting of described segments.

The steady periods a multisine segment was designed with and holds, and how many
experiments (one per axis, eq. 9) a multisine realisation or chirp iteration has.
"""
from __future__ import annotations

from typing import Any


def planned_periods(info: dict[str, Any]) -> int:
    """
    Return the steady periods a multisine segment was designed with.

    Parameters
    ----------
    info : dict
        The segment's descriptor.

    Returns
    -------
    int
        ``periods_planned`` of a segment stopped at its uncertainty target, else ``periods``.

    """
    return int(info.get('periods_planned', info['periods']))


def segment_periods(info: dict[str, Any]) -> int:
    """
    Return the steady periods a multisine segment holds (fewer when stopped at a target).

    Parameters
    ----------
    info : dict
        The segment's descriptor.

    Returns
    -------
    int

    """
    return int(info['periods'])


def expected_experiments(experiments: set[int] | dict, info: dict[str, Any]) -> int:
    """
    Return how many experiments a multisine realisation or chirp iteration has.

    One per axis (eq. 9): the descriptor's ``n_axes`` when the recorder wrote it, else as
    many as the highest experiment index present says.

    Parameters
    ----------
    experiments
        The experiment indices present.
    info
        A segment descriptor of the design.

    Returns
    -------
    int

    """
    return max(1 + max(experiments, default=-1), int(info.get('n_axes', 0)))
