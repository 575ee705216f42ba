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
The Section 7 multisine procedure on a constant velocity (Sec. 4.4 and 7) as phases.

:func:`multisine_procedure` plans an odd random multisine on a constant velocity (amplitude
<= 0.75 of it, every axis within +-4 deg), n_p realisations x n_q periods, MIMO by eq. 9,
plus one constant-velocity-only run for periodic-disturbance compensation; its settings are
:class:`MultisineConfig`. :func:`multisine_tail` gives the phases that end a procedure
stopped in a segment (faded out over ``STOP_FADE_S``).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any

from frf_ident.core.excitation.multisine import (design_odd_multisine, multisine_realisation,
                                                 MultisineDesign)
from frf_ident.core.excitation.plan_checks import check_band, check_finite, check_position_bound
from frf_ident.core.excitation.procedures import Phase
from frf_ident.errors import DesignError
import numpy as np


def _ramp(v_from: np.ndarray, v_to: np.ndarray, n: int) -> np.ndarray:
    s = (np.arange(n) + 0.5) / n
    w = 0.5 - 0.5 * np.cos(np.pi * s)
    return v_from + np.outer(w, v_to - v_from)


@dataclass
class MultisineConfig:
    """
    Section 7 multisine settings.

    ``resolution_hz`` 0.1 gives the paper's 12.3 s periods; the default 0.25 Hz (4.1 s) keeps
    simulations short at the same line density in dB/decade above 2 Hz.
    """

    f_low: float = 2.0
    f_high: float = 60.0
    resolution_hz: float = 0.25
    n_realisations: int = 10
    n_periods: int = 5
    transient_periods: int = 1
    amplitude_ratio: float = 0.75
    position_bound_deg: float = 4.0
    ramp_s: float = 0.5
    settle_s: float = 1.5
    return_s: float = 2.0
    compensate: bool = True
    seed: int = 0

    def __post_init__(self) -> None:
        check_band(self.f_low, self.f_high)
        check_finite(resolution_hz=self.resolution_hz, ramp_s=self.ramp_s,
                     settle_s=self.settle_s, return_s=self.return_s, minimum=0.0,
                     positive=('resolution_hz', 'ramp_s'))
        for name in ('transient_periods', 'seed'):
            if getattr(self, name) < 0:
                raise DesignError(f'{name}={getattr(self, name)} must be at least 0')
        if self.n_periods < 1:
            raise DesignError(f'n_periods={self.n_periods} must be at least 1')
        if self.n_realisations < 1:
            raise DesignError(f'n_realisations={self.n_realisations} must be at least 1')
        if not 0 < self.amplitude_ratio <= 0.75:
            raise DesignError(f'amplitude_ratio={self.amplitude_ratio} must be in (0, 0.75] '
                              f'(the multisine stays <= 0.75 of the constant velocity)')
        if not self.position_bound_deg > 0:
            raise DesignError(f'position_bound_deg={self.position_bound_deg} must be positive')

    def remedy(self) -> str:
        """
        Return what lowers this design's torque, for a refusal message.

        Returns
        -------
        str
            The settings to lower, with their values.

        """
        return (f'lower the multisine amplitude_ratio ({self.amplitude_ratio:g}) or '
                f'position_bound_deg ({self.position_bound_deg:g}: the constant velocity)')


def constant_velocity_for_bound(bound_rad: float, travel_time: float, ramp_time: float,
                                ms_position_peak: float) -> float:
    """
    Largest constant velocity whose travel from -bound stays inside +bound (Sec. 4.4 D).

    The move spans 2 bound minus twice the multisine's own position excursion, over the
    segment plus one ramp (the two half ramps).
    """
    room = 2.0 * bound_rad - 2.0 * ms_position_peak
    if room <= 0:
        raise DesignError(f'position bound {math.degrees(bound_rad):.2f} deg leaves no room '
                          f'for a constant velocity')
    return room / (travel_time + ramp_time)


def multisine_procedure(cfg: MultisineConfig, n_axes: int, fs: float) -> tuple[list[Phase],
                                                                               MultisineDesign]:
    """Phases of the Section 7 multisine experiment (constant-velocity run first)."""
    dt = 1.0 / fs
    design = design_odd_multisine(cfg.f_low, cfg.f_high, bound=1.0,
                                  resolution_hz=cfg.resolution_hz, fs=fs)
    n_per = design.period_samples(fs)
    n_seg = (cfg.transient_periods + cfg.n_periods) * n_per
    n_ramp = max(1, int(round(cfg.ramp_s * fs)))
    bound = math.radians(cfg.position_bound_deg)
    rng = np.random.default_rng(cfg.seed)
    reals = [multisine_realisation(design, n_axes, rng, fs=fs)
             for _ in range(cfg.n_realisations)]
    t = np.arange(n_per) / fs
    unit = [r.evaluate(t) for r in reals]                 # (n_ex, n_per, n_u), peak 1
    # position excursion of a unit multisine (zero-mean integral), then the velocity
    ms_pos = max(np.max(np.abs(np.cumsum(u - u.mean(axis=1, keepdims=True), axis=1) * dt))
                 for u in unit)
    v_c = 0.0
    for _ in range(20):   # fixed point: amplitude = ratio * v_c, excursion scales with it
        v_new = constant_velocity_for_bound(bound * 0.95, n_seg * dt, n_ramp * dt,
                                            cfg.amplitude_ratio * v_c * ms_pos)
        if abs(v_new - v_c) < 1e-12:
            break
        v_c = v_new
    amp = cfg.amplitude_ratio * v_c
    vc = np.full(n_axes, v_c)
    start = np.full(n_axes, -bound * 0.95)
    n_settle = max(1, int(round(cfg.settle_s * fs)))
    n_return = max(1, int(round(cfg.return_s * fs)))
    phases: list[Phase] = []
    common = {'procedure': 'multisine', 'design_params': design.to_dict(),
              'periods': cfg.n_periods, 'transient_periods': cfg.transient_periods,
              'period_samples': n_per, 'constant_velocity': vc.tolist(),
              'amplitude': amp, 'n_realisations': cfg.n_realisations, 'n_axes': n_axes,
              'freq_hz': design.freq_hz.tolist()}

    def run(exc: np.ndarray, info: dict[str, Any]) -> None:
        phases.append(Phase('move', n_return, target=start))
        phases.append(Phase('settle', n_settle))
        phases.append(Phase('excite', n_ramp, reference=_ramp(np.zeros(n_axes), vc, n_ramp),
                            excitation=np.zeros((n_ramp, n_axes))))
        ref = vc + exc
        phases.append(Phase('excite', n_seg, reference=ref, excitation=exc, segment=info))
        phases.append(Phase('excite', n_ramp, reference=_ramp(vc, np.zeros(n_axes), n_ramp),
                            excitation=np.zeros((n_ramp, n_axes))))
        phases.append(Phase('settle', n_settle))

    if cfg.compensate:
        run(np.zeros((n_seg, n_axes)), dict(common, design='constant_velocity',
                                            realisation=-1, experiment=-1))
    reps = cfg.transient_periods + cfg.n_periods
    for p, u in enumerate(unit):
        for m in range(n_axes):
            exc = amp * np.tile(u[m], (reps, 1))
            run(exc, dict(common, design='multisine', realisation=p, experiment=m))
    phases.append(Phase('move', n_return, target=np.zeros(n_axes)))
    phases.append(Phase('settle', n_settle))
    check_position_bound(phases, start, bound, dt)
    return phases, design


#: samples over which a multisine stopped at its target fades its excitation out (50 ms at
#: 1 kHz: no step in the reference; the constant velocity goes on meanwhile)
STOP_FADE_S = 0.05


def multisine_tail(phases: list[Phase], i_segment: int) -> list[Phase]:
    """
    Return the phases that end a multisine procedure stopped in segment ``i_segment``.

    :func:`multisine_procedure` follows each segment with its ramp down and a settle, and
    ends with the move back to the operating point and a settle: those run, the runs after
    the segment do not.

    Parameters
    ----------
    phases : list of Phase
        The procedure.
    i_segment : int
        Index of the segment's phase in ``phases``.

    Returns
    -------
    list of Phase

    """
    after = []
    for ph in phases[i_segment + 1:]:
        if ph.kind == 'move' or ph.segment is not None:
            break
        after.append(ph)
    return after + phases[-2:]
