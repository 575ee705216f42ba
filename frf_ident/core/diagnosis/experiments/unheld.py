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
Candidates the experiments route does not offer: what the simulator cannot hold, and why.

A simulator injected into the diagnosis (MuJoCo for a model naming an MJCF,
frf_ident/io/mjcf/candidate.py) may be unable to hold some effects (an MJCF has no
backlash): it names them in ``unheld`` (:func:`..common.unheld_by`). The route could not judge
such a candidate by simulation, so it is not offered: it goes to ``rejected`` with the reason
(:func:`not_held`). The spring-shape fits (stiffening, backlash) are not run either on an
axis rigid in the band (:func:`spring_shapes_skipped`).
"""
from __future__ import annotations

import math

from .rigid_axes import rigid_in_band
from .search import Search
from ..common import Effect, SPRING_SHAPES
from ..thresholds import LOAD_DEPENDENCE_MIN_LOG

__all__ = ['not_held', 'spring_shapes_skipped']


def not_held(s: Search, e: Effect) -> Effect | None:
    """
    Keep a candidate the simulator cannot hold out of the search, with the reason; else None.

    An engine injected as the simulator (MuJoCo for an MJCF) that cannot hold an effect
    (``Evaluator.unheld``) could not judge it: it is listed in ``rejected`` with why, not
    offered.
    """
    why = s.ev.unheld.get(e.name)
    if why is None:
        return None
    e.reason = f'not simulated: {why}'
    s.cands.append(e)
    s.say(f'  {e.axis} {e.name}: {e.reason}')
    return e


def spring_shapes_skipped(s: Search, i: int, s_ms: float, s_ch: float) -> set[str]:
    """
    Return the spring-shape fits (stiffening, backlash) axis i does not run.

    None on an axis rigid in the band (its spring lies far above the band: nothing to
    bend); none the simulator cannot hold, each named in ``rejected`` where the stiffness the
    two loads see differs (the evidence that would have called for it).
    """
    shapes = set(SPRING_SHAPES)
    if rigid_in_band(s.ext, i):
        return shapes
    out = shapes & set(s.ev.unheld)
    if abs(s_ch - s_ms) >= LOAD_DEPENDENCE_MIN_LOG:
        for name in sorted(out):
            if not any(c.name == name and c.axis_index == i for c in s.cands):
                seen = (f'stiffness seen by the chirp (high load) x{math.exp(s_ch - s_ms):.3f} '
                        f'that of the multisine (low load)')
                not_held(s, Effect(name, s.robot.axes[i].name, 0.0, {}, seen, i))
    return out
