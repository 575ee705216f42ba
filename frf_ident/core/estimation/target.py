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
The uncertainty target of a multisine run: when to stop, and how many periods are left.

A run may stop at the first whole period after which every excited line of the chosen
channels has a magnitude standard deviation (1 sigma, dB, ``FrequencyResponse.std_db``) at or
below the target. The period cap is the run's design: n_realisations x n_periods, whose
position and torque were checked before it started; stopping early only shortens it.

The coupling channels of a robot are 40-60 dB below its axes' own responses (the 3-axis
model: median |P_ij| -105..-140 dB against -68..-77 dB on the diagonal), so their relative
uncertainty stays far above a dB target a diagonal reaches: by default the target applies to
the diagonal P_ii, the channels the loop check and the physical fit use (``channels='all'``
applies it to every channel).
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from frf_ident.errors import DesignError
import numpy as np

__all__ = ['MIN_STOP_PERIODS', 'UncertaintyTarget']

#: a segment stopped at the target holds at least this many steady periods: two give a noise
#: variance, the third lets the transient test (frf_ident/core/estimation/transient.py, which
#: compares consecutive pairs with the later ones) judge the record when it is analysed
#: without its descriptors
MIN_STOP_PERIODS = 3


@dataclass(frozen=True)
class UncertaintyTarget:
    """
    Stop rule of a multisine run.

    Parameters
    ----------
    sd_db : float
        Largest 1-sigma magnitude uncertainty [dB] over the excited lines; 0: no target (the
        run goes to its cap).
    channels : {'diagonal', 'all'}, optional
        The channels the target applies to (see the module docstring).

    """

    sd_db: float = 0.0
    channels: str = 'diagonal'

    def __post_init__(self) -> None:
        """Refuse a target that is not a finite number >= 0 or unknown channels."""
        if not (math.isfinite(self.sd_db) and self.sd_db >= 0):
            raise DesignError(f'target_sd_db={self.sd_db} must be a finite number >= 0 '
                              f'(0: no target)')
        if self.channels not in ('diagonal', 'all'):
            raise DesignError(f"target_channels={self.channels!r}: expected 'diagonal' or "
                              f"'all'")

    @property
    def enabled(self) -> bool:
        """Tell whether the run stops at the target (sd_db > 0)."""
        return self.sd_db > 0

    def worst_db(self, sd_db: np.ndarray) -> float:
        """
        Return the largest sd over the target's channels and lines (nan while undefined).

        Parameters
        ----------
        sd_db : ndarray, shape (n_out, n_in, F)
            Magnitude standard deviation [dB] per channel and line.

        Returns
        -------
        float

        """
        sd = np.asarray(sd_db, float)
        if self.channels == 'diagonal' and sd.shape[0] == sd.shape[1]:
            sd = sd[np.arange(sd.shape[0]), np.arange(sd.shape[0])]
        return float(np.max(sd)) if sd.size and np.all(np.isfinite(sd)) else float('nan')

    def met(self, sd_db: np.ndarray, segment_periods: int) -> bool:
        """
        Tell whether the run may stop after this period.

        Parameters
        ----------
        sd_db : ndarray, shape (n_out, n_in, F)
            The estimate's magnitude sd [dB].
        segment_periods : int
            Steady periods the running segment holds (at least :data:`MIN_STOP_PERIODS`).

        Returns
        -------
        bool

        """
        worst = self.worst_db(sd_db)
        return (self.enabled and segment_periods >= MIN_STOP_PERIODS
                and math.isfinite(worst) and worst <= self.sd_db)

    def periods_left(self, sd_db: np.ndarray, periods: int) -> int | None:
        """
        Predict the periods still needed: the sd falls as 1/sqrt(periods).

        Parameters
        ----------
        sd_db : ndarray, shape (n_out, n_in, F)
            The estimate's magnitude sd [dB].
        periods : int
            MIMO periods it is made of.

        Returns
        -------
        int or None
            0 when met; None without a target or an sd yet.

        """
        worst = self.worst_db(sd_db)
        if not self.enabled or not math.isfinite(worst) or periods < 1:
            return None
        need = periods * (worst / self.sd_db) ** 2
        return max(0, math.ceil(need - periods - 1e-9))
