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
The chirp iteration of Sec. 5.3 (eqs. 17-19) as phases, for an n_u-axis robot.

:class:`ChirpIteration` plans MIMO chirps (eq. 26 phases) whose reference is iterated until
the plant input reaches the desired torque amplitudes (Table 1), the predicted torque kept
below the limits and, given a position bound, its planned position inside it
(:mod:`.chirp_position`); its settings are :class:`ChirpConfig`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from frf_ident.core.excitation.chirp import (chirp_instantaneous_frequency, chirp_phase,
                                             chirp_phase_flips, ChirpDesign)
from frf_ident.core.excitation.chirp_dft import (chirp_analysis_frequencies, chirp_excerpt_dft,
                                                 chirp_spectra)
from frf_ident.core.excitation.chirp_position import cap_position, PositionCap
from frf_ident.core.excitation.multisine import reference_frequency_set
from frf_ident.core.excitation.plan_checks import (check_band, check_finite, POSITION_MARGIN,
                                                   TORQUE_MARGIN)
from frf_ident.core.excitation.procedures import Phase
from frf_ident.errors import DesignError, SafetyError
import numpy as np


TABLE1_AMPLITUDES = np.array([[100.0, 50.0], [150.0, 75.0], [120.0, 60.0]])   # N m, <>40 Hz
TABLE1_BREAKS_HZ = [40.0]


@dataclass
class ChirpConfig:
    """Section 7 chirp settings: 2-60 Hz, 20 s, eq. 26 phases, Table 1 torque amplitudes."""

    f_low: float = 2.0
    f_high: float = 60.0
    duration: float = 20.0
    u_des: np.ndarray = field(default_factory=lambda: TABLE1_AMPLITUDES.copy())
    breaks_hz: list[float] = field(default_factory=lambda: list(TABLE1_BREAKS_HZ))
    r_initial: np.ndarray = field(default_factory=lambda: np.array([0.006, 0.006, 0.012]))
    max_iterations: int = 6
    tolerance_db: float = 1.0
    n_lines: int = 80
    lead_s: float = 0.5
    settle_s: float = 1.0
    max_gain_step: float = 100.0
    torque_margin: float = TORQUE_MARGIN
    position_margin: float = POSITION_MARGIN
    regularisation: float = 1e-3

    def __post_init__(self) -> None:
        self.u_des = np.atleast_2d(np.asarray(self.u_des, dtype=float))
        self.r_initial = np.atleast_1d(np.asarray(self.r_initial, dtype=float))
        check_band(self.f_low, self.f_high)
        check_finite(duration=self.duration, tolerance_db=self.tolerance_db,
                     lead_s=self.lead_s, settle_s=self.settle_s,
                     max_gain_step=self.max_gain_step, torque_margin=self.torque_margin,
                     position_margin=self.position_margin,
                     regularisation=self.regularisation, minimum=0.0,
                     positive=('duration', 'tolerance_db', 'max_gain_step', 'torque_margin',
                               'position_margin'))
        if self.torque_margin > 1.0 or self.n_lines < 1:
            raise DesignError(f'torque_margin={self.torque_margin} must be at most 1 and '
                              f'n_lines={self.n_lines} at least 1')
        if self.position_margin > 1.0:
            raise DesignError(f'position_margin={self.position_margin} must be at most 1')
        if not (np.all(np.isfinite(self.u_des)) and np.all(np.isfinite(self.r_initial))):
            raise DesignError(f'u_des {self.u_des.tolist()} and r_initial '
                              f'{self.r_initial.tolist()} must be finite')
        if np.any(self.u_des <= 0) or np.any(self.r_initial <= 0):
            raise DesignError(f'u_des {self.u_des.tolist()} and r_initial '
                              f'{self.r_initial.tolist()} must be positive')
        if self.max_iterations < 1:
            raise DesignError(f'max_iterations={self.max_iterations} must be at least 1')

    def remedy(self) -> str:
        """
        Return what lowers the first step's torque, for a refusal message.

        Returns
        -------
        str
            The setting to lower, with its value.

        """
        return f'lower the chirp r_initial ({self.r_initial.tolist()} rad/s)'


class ChirpIteration:
    """
    Iterative closed-loop excitation design of Sec. 5.3 for an n_u-axis robot.

    State: the current reference spectra R_i (n_lines, n_u, n_ex) in *chirp coordinates*
    (the excerpt DFT of the signal divided by that of a unit chirp, so a chirp of amplitude a
    and phase psi reads a e^{j psi}). Step i: run the experiments of :meth:`phases`, then
    :meth:`update` with the measured r and u: P_r->u = U R^-1 (eq. 7 on r -> u), the next
    R_{i+1} = P_r->u^-1 U_des (eq. 18), regularised, step-limited, capped where its planned
    position would leave ``position_bound`` [rad] (:func:`.chirp_position.cap_position`; None:
    no bound) and scaled so the predicted torque in time stays below the limit
    (:meth:`torque_scale`); r_{i+1}(t) synthesised from R_{i+1} (eq. 19).
    """

    def __init__(self, cfg: ChirpConfig, n_axes: int, fs: float,
                 torque_limit: np.ndarray, position_bound: float | None = None) -> None:
        self.cfg, self.n, self.fs = cfg, n_axes, fs
        self.position_bound = position_bound
        #: what the last update's position cap lowered (None: no bound or no update yet)
        self.position_cap: PositionCap | None = None
        self.dt = 1.0 / fs
        self.design = ChirpDesign(cfg.f_low, cfg.f_high, cfg.duration, np.ones((n_axes, 1)))
        self.design.check_sample_rate(fs)
        self.torque_limit = np.broadcast_to(np.asarray(torque_limit, float), (n_axes,)).copy()
        u_des = cfg.u_des[:n_axes]
        if u_des.shape[0] != n_axes:
            raise DesignError(f'u_des has {cfg.u_des.shape[0]} rows for {n_axes} axes')
        if np.any(u_des >= self.torque_limit[:, None]):
            raise SafetyError(f'desired torque amplitudes {u_des.tolist()} reach the torque '
                              f'limits {self.torque_limit.tolist()}')
        self.phi = chirp_phase_flips(n_axes)
        cand = reference_frequency_set(cfg.f_low, cfg.f_high, cfg.n_lines)
        self.freqs = chirp_analysis_frequencies(cand, self.design.time_at, self.design.t0,
                                                self.design.t1)
        self.t_centers = self.design.time_at(self.freqs)
        levels = np.stack([self.design_amplitude(ax, u_des) for ax in range(n_axes)])  # (n, F)
        self.u_des_amp = levels.T                                              # (F, n)
        E = np.exp(1j * self.phi)
        self.U_des = self.u_des_amp[:, :, None] * E[None]                     # (F, n, n_ex)
        r0 = np.broadcast_to(cfg.r_initial[:n_axes], (n_axes,))
        self.R = np.broadcast_to(r0[None, :, None] * E[None], self.U_des.shape).copy()
        self.iteration = 1
        self.history: list[dict[str, Any]] = []
        self._unit = self._unit_chirp_spectrum()

    def design_amplitude(self, axis: int, u_des: np.ndarray) -> np.ndarray:
        from frf_ident.core.excitation.chirp import amplitude_schedule
        return amplitude_schedule(self.cfg.breaks_hz, u_des[axis])(self.freqs)

    def _unit_chirp_spectrum(self) -> np.ndarray:
        """Excerpt DFT of the unit chirp sin(theta(t)) at every analysis line (Sec. 5.1)."""
        n = int(round(self.design.t1 * self.fs)) + 1
        t = np.arange(n) * self.dt
        x = np.sin(chirp_phase(t, self.design.a0, self.design.a1, self.design.t0))
        return np.array([chirp_excerpt_dft(x, self.fs, f, tc)
                         for f, tc in zip(self.freqs, self.t_centers)])

    # -- signals -------------------------------------------------------------------------------
    def reference_signals(self, R: np.ndarray | None = None) -> np.ndarray:
        """
        Synthesise r(t) for every experiment from chirp-coordinate spectra R (eq. 19).

        r_lm(t) = |R_lm(f(t))| sin(theta(t) + arg R_lm(f(t))), interpolated over log f.
        Returns (n_ex, n_samples, n_u) on [0, t1].
        """
        R = self.R if R is None else R
        n = int(round(self.design.t1 * self.fs)) + 1
        t = np.arange(n) * self.dt
        theta = chirp_phase(t, self.design.a0, self.design.a1, self.design.t0)
        lf = np.log(np.clip(chirp_instantaneous_frequency(t, self.design.a0, self.design.a1),
                            self.freqs[0], self.freqs[-1]))
        lx = np.log(self.freqs)
        out = np.zeros((self.n, n, self.n))
        taper = np.ones(n)
        nt = int(0.05 * self.fs)      # 50 ms cosine fade in/out: no step at the ends
        taper[:nt] = 0.5 - 0.5 * np.cos(np.pi * np.arange(nt) / nt)
        taper[-nt:] = taper[:nt][::-1]
        for m in range(self.n):
            for ch in range(self.n):
                mag = np.interp(lf, lx, np.abs(R[:, ch, m]))
                ph = np.interp(lf, lx, np.unwrap(np.angle(R[:, ch, m])))
                out[m, :, ch] = taper * mag * np.sin(theta + ph)
        return out

    def phases(self) -> list[Phase]:
        """Phases of the current iteration: one chirp experiment per input (eq. 26)."""
        sig = self.reference_signals()
        n_lead = int(round(self.cfg.lead_s * self.fs))
        n_settle = int(round(self.cfg.settle_s * self.fs))
        out: list[Phase] = []
        for m in range(self.n):
            out.append(Phase('move', n_settle, target=np.zeros(self.n)))
            out.append(Phase('settle', n_lead))
            seg = {'procedure': 'chirp', 'design': 'chirp', 'iteration': self.iteration,
                   'experiment': m, 'design_params': self.design.to_dict(),
                   'freq_hz': self.freqs.tolist(), 'n_axes': self.n,
                   'u_des': self.u_des_amp.T.tolist()}
            out.append(Phase('excite', sig.shape[1], reference=sig[m], excitation=sig[m],
                             segment=seg))
            out.append(Phase('settle', n_settle))
        return out

    def torque_scale(self, U_pred: np.ndarray, Um: np.ndarray, u_runs: list[np.ndarray]
                     ) -> tuple[float, np.ndarray]:
        """
        Return the scale of the next reference that keeps its torque below the limits.

        The bound is on the torque in time, not on its line amplitudes: the chirp part of
        each experiment's torque is synthesised from the predicted spectra U_pred (as r(t)
        is from R, eq. 19), and what the measured torque holds besides its own synthesised
        chirp part (the torque at rest, transients, friction) is added as measured. The
        scale s <= 1 keeps |s u_chirp(t) + u_rest(t)| below ``torque_margin`` times each
        axis' limit at every sample.

        Parameters
        ----------
        U_pred : ndarray, shape (n_lines, n_u, n_ex)
            Predicted torque spectra of the next reference (chirp coordinates).
        Um : ndarray, shape (n_lines, n_u, n_ex)
            Measured torque spectra of this iteration.
        u_runs : list of ndarray, shape (N, n_u)
            Measured torque of each experiment.

        Returns
        -------
        scale : float
            The factor for the next reference (1 when nothing binds).
        peak : ndarray, shape (n_u,)
            Predicted peak torque per axis after scaling.

        Raises
        ------
        SafetyError
            When the torque besides the chirp alone already exceeds the bound.

        """
        bound = self.cfg.torque_margin * self.torque_limit
        chirp_next, chirp_now = self.reference_signals(U_pred), self.reference_signals(Um)
        n = min(min(len(u) for u in u_runs), chirp_now.shape[1])
        a = chirp_next[:, :n]                                              # (n_ex, n, n_u)
        b = np.stack([u[:n] for u in u_runs]) - chirp_now[:, :n]

        def peak(s: float) -> np.ndarray:
            return np.max(np.abs(s * a + b), axis=(0, 1))

        # max |s a + b| / bound is convex in s: the scales it allows are an interval from 0
        over = peak(0.0) > bound
        if over.any():
            raise SafetyError(
                f'chirp iteration {self.iteration}: the torque besides the chirp alone reaches '
                f'{peak(0.0)[over].round(1).tolist()} N m on axes {np.flatnonzero(over).tolist()}'
                f', above {self.cfg.torque_margin:g} x the limits '
                f'{self.torque_limit[over].tolist()}: no chirp fits; refusing to go on')
        lo, hi = 0.0, 1.0
        if np.all(peak(hi) <= bound):
            lo = hi
        else:
            for _ in range(40):
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if np.all(peak(mid) <= bound) else (lo, mid)
        return lo, peak(lo)

    # -- the update (eqs. 18-19) ---------------------------------------------------------------
    def spectra(self, x: np.ndarray) -> np.ndarray:
        """Return one experiment's chirp-coordinate spectra, shaped (F, n), from samples (N, n)."""
        return chirp_spectra(x, self.fs, self.freqs, self.t_centers) / self._unit[:, None]

    def error_db(self, U: np.ndarray) -> np.ndarray:
        """Per line and channel: 20 log10 |U_lm| / U_des,l, worst over experiments (F, n)."""
        ratio = np.abs(U) / self.u_des_amp[:, :, None]
        err = 20 * np.log10(np.maximum(ratio, 1e-12))
        idx = np.argmax(np.abs(err), axis=2)
        return np.take_along_axis(err, idx[:, :, None], axis=2)[:, :, 0]

    def update(self, r_runs: list[np.ndarray], u_runs: list[np.ndarray],
               y_runs: list[np.ndarray] | None = None) -> dict[str, Any]:
        """
        Process the measured experiments of this iteration and design the next reference.

        ``r_runs``/``u_runs``: per experiment m, (N, n) samples from the chirp start t0.
        Returns the iteration summary (errors in dB, converged flag, predicted peak torque).
        """
        Rm = np.stack([self.spectra(r) for r in r_runs], axis=-1)   # (F, n, n_ex)
        Um = np.stack([self.spectra(u) for u in u_runs], axis=-1)
        err = self.error_db(Um)
        peak_u = [float(np.max(np.abs(u))) for u in u_runs]
        summary = {'iteration': self.iteration, 'max_abs_error_db': float(np.max(np.abs(err))),
                   'error_db_per_channel': np.max(np.abs(err), axis=0).tolist(),
                   'max_abs_torque': np.max(np.abs(np.stack(u_runs)), axis=(0, 1)).tolist(),
                   'peak_torque': max(peak_u), 'converged': False}
        if summary['max_abs_error_db'] <= self.cfg.tolerance_db:
            summary['converged'] = True
            self.history.append(summary)
            return summary
        P_ru = Um @ np.linalg.inv(Rm)                                  # eq. 7 for r -> u
        R_next = self._regularised_solve(P_ru, self.U_des)               # eq. 18
        # never more than max_gain_step times the previous reference on a line
        grow = np.abs(R_next) / np.maximum(np.abs(Rm), 1e-300)
        limit = np.minimum(1.0, self.cfg.max_gain_step / np.maximum(grow, 1e-300))
        R_next = R_next * limit
        if self.position_bound is not None:
            R_next, self.position_cap = cap_position(
                R_next, self.freqs, self.reference_signals, self.dt, self.position_bound,
                self.cfg.position_margin, self.cfg.f_low)
        scale, peak = self.torque_scale(P_ru @ R_next, Um, u_runs)
        R_next = R_next * scale
        cap = self.position_cap
        summary.update({'predicted_peak_torque': peak.tolist(),
                        'scaled_for_torque_limit': bool(scale < 1.0),
                        'position_cap': cap.to_dict() if cap and cap.capped else None,
                        'cond_P_ru_max': float(np.max(np.linalg.cond(P_ru)))})
        self.history.append(summary)
        self.R = R_next
        self.iteration += 1
        return summary

    def _regularised_solve(self, P: np.ndarray, B: np.ndarray) -> np.ndarray:
        """X = P^-1 B per line, Tikhonov-regularised where P is ill-conditioned."""
        U_, s, Vh = np.linalg.svd(P)
        lam = self.cfg.regularisation * s[:, :1]
        inv_s = s / (s ** 2 + lam ** 2)
        Pinv = np.conj(np.swapaxes(Vh, 1, 2)) @ (inv_s[:, :, None] * np.conj(
            np.swapaxes(U_, 1, 2)))
        return Pinv @ B
