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
"""The state the stages of the experiments route share (:mod:`.pipeline`)."""
from __future__ import annotations

from dataclasses import dataclass, field
import textwrap
from typing import Callable

from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
import numpy as np

from .evaluator import Evaluator
from .noise_gain import HeldOutGain
from .structure import StructureReading
from ..common import Effect

__all__ = ['named', 'Search']


@dataclass
class Search:
    """The state the stages of :func:`diagnose_experiments` share."""

    ev: Evaluator
    robot: RobotParams                  # the nominal model (with the record's sensor)
    say: Callable[[str], None]          # the search trace
    sim0: Recording                     # the nominal model's simulation
    ext: RobotParams                    # the model so far
    cur: np.ndarray                     # its misfit per axis on the fit part
    kept: list[Effect] = field(default_factory=list)
    cands: list[Effect] = field(default_factory=list)      # every candidate offered
    stage0: list[Effect] = field(default_factory=list)     # frequency-domain fit candidates
    stage1: list[Effect] = field(default_factory=list)     # torque-residual candidates
    stage2: list[Effect] = field(default_factory=list)     # FRF-shape candidates
    #: every FRF-shape candidate of every stage-2 round (``stage2`` and ``cands`` keep an
    #: axis' last reading of each effect only)
    stage2_read: list[Effect] = field(default_factory=list)
    rivals: dict[int, list[Effect]] = field(default_factory=dict)
    shaped: set[int] = field(default_factory=set)   # axes that took an FRF-shape effect
    again: list[Effect] = field(default_factory=list)  # second-pass candidates
    #: per axis the joint refit worked on, its misfit before the refit
    refitted: dict[int, float] = field(default_factory=dict)
    #: stage 0's residual tests of the linear fit (None: no multisine variance, or no stage 0)
    structure: StructureReading | None = None
    #: the model file as given, where ``robot`` is it with the sensor the record shows
    #: (:mod:`..sensor`: the search reads every effect against the sensor); None: the same
    nominal: RobotParams | None = None
    #: the held-out check's gain test of each effect it judged (by id)
    gains: dict[int, HeldOutGain] = field(default_factory=dict)


def named(kept: list[Effect]) -> str:
    """
    Return 'kept: axis name, name; axis name' for a log line, grouped by axis.

    Grouped and wrapped at 100 characters (continuation lines indented): five effects as
    name@axis made a 170-character stage line, wider than a terminal.
    """
    if not kept:
        return 'kept: none'
    axes: dict[str, list[str]] = {}
    for c in kept:
        axes.setdefault(c.axis, []).append(c.name)
    text = 'kept: ' + '; '.join(f'{a} ' + ', '.join(n) for a, n in axes.items())
    return '\n    '.join(textwrap.wrap(text, 100, break_on_hyphens=False))
