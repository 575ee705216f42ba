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
Segments a recording covers only in part: left out, named, so the rest is estimated.

A recorder started inside a segment (``ros2 bag record`` after the run began; a transient-local
descriptor arrives late), stopped inside one, or a ``--t-range`` that cuts one, leaves a
segment whose samples are not all in the record. Its estimate would fail ("outside the
record") or be biased; it is left out with a warning and ``meta['segments_left_out']``.
"""
from __future__ import annotations

from typing import Any

from frf_ident.core.recording import Segment

#: a segment edge may lie this share of a sample period outside the record's first/last
#: sample and still count as covered (stamps and descriptor times agree to rounding)
EDGE_TOLERANCE = 0.5


def split_covered(segments: list[Segment], t_first: float, t_last: float,
                  dt: float) -> tuple[list[Segment], list[Segment]]:
    """
    Split segments into those the samples ``t_first .. t_last`` cover and the cut ones.

    A segment spans [t_start, t_end): its last sample is at t_end - dt.

    Parameters
    ----------
    segments
        The recording's segments.
    t_first, t_last
        Times [s] of the record's first and last sample.
    dt
        Sample period [s].

    Returns
    -------
    tuple of list of Segment
        (covered, cut): cut ones overlap the record in part; segments wholly outside it are
        in neither.

    """
    tol = EDGE_TOLERANCE * dt
    covered, cut = [], []
    for s in segments:
        if s.t_end - dt < t_first - tol or s.t_start > t_last + tol:
            continue                        # not in the record at all
        if s.t_start >= t_first - tol and s.t_end - dt <= t_last + tol:
            covered.append(s)
        else:
            cut.append(s)
    return covered, cut


def cut_warning(s: Segment, t_first: float, t_last: float) -> str:
    """Return the one-line warning naming a segment the record covers only in part."""
    info: dict[str, Any] = s.info
    what = ', '.join(f'{k} {info[k]}' for k in ('realisation', 'experiment', 'iteration')
                     if info.get(k) is not None)
    return (f'segment {s.t_start:.3f}..{s.t_end:.3f} s ({info.get("design", "?")}'
            f'{", " + what if what else ""}) is only partly in the record '
            f'[{t_first:.3f}, {t_last:.3f}] s: left out')
