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
The excitation node's parameters and the session's safety limits.

:class:`SessionSettings` refuses settings that switch a safety check off; the constants are
the limits the session itself applies (abort ramp, saturation, joint-state rate).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math

from frf_ident.core.excitation.chirp_iteration import ChirpConfig
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.errors import DesignError

__all__ = ['abort_ramp_steps', 'MAX_ABORT_RAMP_S', 'MIN_ABORT_RAMP_STEPS', 'RATE_WINDOW',
           'REGULAR', 'SATURATION', 'SessionSettings', 'SLOW_STEP']


#: the longest ramp to zero an abort may take [s]
MAX_ABORT_RAMP_S = 0.1
#: the fewest samples an abort's ramp to zero takes (at low sample rates, where
#: abort_ramp_s holds fewer)
MIN_ABORT_RAMP_STEPS = 4

#: a measured torque at this share of its limit is a saturated drive: the run aborts (the
#: procedures aim at 0.95 of the limit at most, plan_checks.TORQUE_MARGIN)
SATURATION = 0.995
#: free-running: the joint states whose stamp steps judge their rate (at least half of them)
RATE_WINDOW = 16
#: free-running: a median step of this many samples between the joint states the node sees,
#: regular, refuses or aborts a run: the robot publishes at a fifth of the model's rate or
#: less. (A busy node that misses joint states still measures an unbiased FRF: the reference
#: stays the instrument, only the spectrum the robot gets changes; the free-running graph of
#: test/nodes/test_free_running.py runs on a loaded machine.)
SLOW_STEP = 5
#: free-running: the share of steps within 15 % (at least one sample) of their median that
#: makes them regular (a robot's stamps jitter by a share of its own period)
REGULAR = 0.75


def abort_ramp_steps(abort_ramp_s: float, dt: float) -> int:
    """
    Return the samples an abort's ramp to zero takes: every sample of ``abort_ramp_s``.

    At least MIN_ABORT_RAMP_STEPS. A fixed 4 steps moved the reference by a quarter of its
    value per sample whatever the rate: at 1 kHz 0.0064 rad/s from 0.0257, more than the
    multisine's own largest step of that run (0.0062; test/ros/test_ros_arming.py), so
    the abort jerked the robot harder than the experiment did.

    >>> abort_ramp_steps(0.01, 0.001), abort_ramp_steps(0.01, 0.01)
    (10, 4)
    """
    return max(MIN_ABORT_RAMP_STEPS, int(abort_ramp_s / dt + 1e-9))


@dataclass
class SessionSettings:
    """
    Parameters of the excitation node (defaults are the node's parameter defaults).

    Parameters
    ----------
    lockstep : bool, optional
        Lockstep simulation (references ahead of the joint states); default False:
        free-running (a real robot).
    lookahead : int, optional
        Lockstep: references published ahead of the newest joint state [samples].
    stale_s : float, optional
        Watchdog, lockstep: simulation time [s] the plant's clock (/clock) may run ahead of
        the newest joint state the node saw before a run aborts.
    plant_silent_s : float, optional
        Watchdog, lockstep: wall time [s] without any joint state (the simulated plant died
        or hangs) before a run aborts.
    stale_samples : int, optional
        Watchdog, free-running: the same limit in samples.
    start_grace_s : float, optional
        Wall time [s] the first answer of a run may take (the watchdog waits at least this).
    abort_ramp_s : float, optional
        Wall time [s] within which an abort ramps the reference to zero.
    plan_bound_deg : float, optional
        Bound [deg] of the planned position around the operating point (checked before a
        run); distinct from ``multisine.position_bound_deg``, the multisine design's bound of
        its constant-velocity run.
    live_position_bound_deg : float, optional
        Bound [deg] of the measured position around the operating point (a run aborts
        beyond it).
    progress_period_s : float, optional
        Wall time [s] between progress events.
    multisine : MultisineConfig, optional
        Design of the multisine procedure.
    chirp : ChirpConfig, optional
        Design of the chirp iteration.

    """

    lockstep: bool = False         # free-running unless the simulation says otherwise
    lookahead: int = 20            # lockstep: references published ahead [samples]
    # watchdog, lockstep: simulation s the plant's clock runs ahead of the newest joint state.
    # The plant waits for references, so its clock leads by `lookahead` samples (20 ms) at most
    # while nothing is lost: 0.5 s is a measurement that really went missing, however slowly
    # a loaded PC runs the simulation (issue 44: wall-time staleness aborted 3 of 4 runs at
    # load 4-12, stalls of 1.46 s wall)
    stale_s: float = 0.5
    # watchdog, lockstep: wall s without any joint state (a dead or hung simulated plant; its
    # /clock stops too). Far above the 1.46 s stalls of a loaded 2-core PC; only a dead plant
    # reaches it (a simulation drives no robot: there is no hurry)
    plant_silent_s: float = 10.0
    # watchdog, free-running, in samples: 50 ms at 1 kHz. A Python node on a Linux PC
    # without a real-time kernel saw joint-state gaps of 3.6-23 ms in 12 of 13 runs, 69 ms in
    # one (`make bench`, section nodes; README, 'stale_samples'): 10 aborted good runs
    stale_samples: int = 50
    start_grace_s: float = 0.2     # the first answer of a run may take this long
    abort_ramp_s: float = 0.01     # ramp to zero reference within this wall time
    plan_bound_deg: float = 4.0            # planned position bound around the operating point
    live_position_bound_deg: float = 8.0   # measured position bound (abort)
    progress_period_s: float = 0.5         # wall s between progress events
    multisine: MultisineConfig = field(default_factory=MultisineConfig)
    chirp: ChirpConfig = field(default_factory=ChirpConfig)

    def __post_init__(self) -> None:
        """Refuse settings that switch a safety check off or make it slow (DesignError)."""
        positive = {'stale_s': self.stale_s, 'stale_samples': self.stale_samples,
                    'plant_silent_s': self.plant_silent_s,
                    'start_grace_s': self.start_grace_s, 'abort_ramp_s': self.abort_ramp_s,
                    'plan_bound_deg': self.plan_bound_deg,
                    'live_position_bound_deg': self.live_position_bound_deg,
                    'progress_period_s': self.progress_period_s, 'lookahead': self.lookahead}
        for name, value in positive.items():
            if not (math.isfinite(value) and value > 0):
                raise DesignError(f'{name}={value} must be a positive number')
        if self.abort_ramp_s > MAX_ABORT_RAMP_S:
            raise DesignError(f'abort_ramp_s={self.abort_ramp_s} s: an abort must stop the '
                              f'robot within {MAX_ABORT_RAMP_S} s')
        if self.live_position_bound_deg < self.plan_bound_deg:
            raise DesignError(f'live_position_bound_deg={self.live_position_bound_deg} is below '
                              f'plan_bound_deg={self.plan_bound_deg}: every run would '
                              'abort on its planned motion')
