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
The targets a tuned velocity loop must meet, with their defaults in one place.

Defaults are the usual textbook values for a servo loop (Astrom & Murray, *Feedback Systems*,
ch. 12; Skogestad & Postlethwaite ch. 2): a phase margin of 45 deg, a gain margin of 6 dB
(a factor 2), and a modulus margin of 0.5, i.e. a sensitivity peak of at most 2 (6 dB), which
bounds the amplification of disturbances and guarantees at least 6 dB / 30 deg by itself.
``robust``: the loop must also pass |W T| < 1 for the campaign's uncertainty weight
(:mod:`frf_ident.core.loop.uncertainty`). Off by default: the test is always reported, but an
unstructured multiplicative weight is conservative over a campaign: where the poses change
the plant's gain by more than 100 % (the rigid-body gain at low frequency, an antiresonance
that moves) |W| > 1 while |T| = 1, so no controller passes it although the loop may be fine
at every measured pose (which the margin targets check directly).
"""
from __future__ import annotations

from dataclasses import dataclass, fields
import math

__all__ = ['GAIN_MARGIN_DB', 'MODULUS_MARGIN', 'PHASE_MARGIN_DEG', 'TuneTargets']

#: default phase margin [deg]
PHASE_MARGIN_DEG = 45.0
#: default gain margin [dB]
GAIN_MARGIN_DB = 6.0
#: default modulus margin min |1 + L| (sensitivity peak 1 / 0.5 = 6 dB)
MODULUS_MARGIN = 0.5


@dataclass(frozen=True)
class TuneTargets:
    """
    What a tuned loop must meet at every pose of a campaign.

    Attributes
    ----------
    crossover_hz : float or None
        Wanted gain crossover [Hz] of the worst pose; None: as high as the margins allow.
    phase_margin_deg : float
        Least phase margin [deg].
    gain_margin_db : float
        Least gain margin [dB].
    modulus_margin : float
        Least min |1 + L|.
    robust : bool
        Require |W T| < 1 for the campaign's uncertainty weight too (default: reported only).

    Raises
    ------
    ValueError
        A target that is not a positive finite number (the crossover may be None).

    """

    crossover_hz: float | None = None
    phase_margin_deg: float = PHASE_MARGIN_DEG
    gain_margin_db: float = GAIN_MARGIN_DB
    modulus_margin: float = MODULUS_MARGIN
    robust: bool = False

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == 'robust' or (f.name == 'crossover_hz' and v is None):
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                    or v <= 0:
                raise ValueError(f'target {f.name}={v!r}: expected a positive number')
        if self.modulus_margin >= 1.0 or self.phase_margin_deg >= 90.0:
            raise ValueError(f'targets modulus_margin={self.modulus_margin} (< 1) and '
                             f'phase_margin_deg={self.phase_margin_deg} (< 90): a velocity '
                             f'PI cannot do better')

    def summary(self) -> str:
        """Return one line for people."""
        wc = 'as high as possible' if self.crossover_hz is None else \
            f'{self.crossover_hz:g} Hz'
        return (f'targets: crossover {wc}, phase margin >= {self.phase_margin_deg:g} deg, gain '
                f'margin >= {self.gain_margin_db:g} dB, modulus margin >= '
                f'{self.modulus_margin:g}' + (', |W T| < 1' if self.robust else ''))
