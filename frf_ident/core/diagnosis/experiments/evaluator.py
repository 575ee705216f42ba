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
Simulate candidate models on the recorded excitation and score them per axis.

The experiments route's evaluator: the recording split into fit and held-out experiments, the
noise floors the data show, the closed-loop simulation of a model (:meth:`Evaluator.simulate`)
and its misfit per axis in units of those floors.
"""
from __future__ import annotations

from typing import Any, Sequence
import weakref

from frf_ident.core.estimation.chirp_estimate import chirp_frf
from frf_ident.core.estimation.described import multisine_frf
from frf_ident.core.model.params import RobotParams
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.controller import PIVelocity
import numpy as np

from .floors import held_out_chirp_scale, period_noise
from .parallel import WorkerPool
from ..common import (as_simulation, bridge_gaps, diag_ratio, drive_reference, frf_error_db, nrmse,
                      rms_about_mean, segment_mask, simulate_like, Simulator, split_recording,
                      unheld_by)
from ..records import AxisScore, Scores
from ..residual import inverse_dynamics_residual
from ..thresholds import EST_CACHE, FLOOR_MIN, INDEPENDENT_SAMPLE_S, SETTLE_S, SIM_CACHE, SIM_JOBS


def frf_estimates(rec: Recording) -> dict[str, Any]:
    """Return the two estimates the diagnosis compares: compensated multisine BLA and the chirp."""
    out: dict[str, Any] = {}
    if any(s.info.get('design') == 'multisine' for s in rec.segments):
        cv = any(s.info.get('design') == 'constant_velocity' for s in rec.segments)
        out['multisine'] = multisine_frf(rec, compensate=cv)[0]
    if any(s.info.get('design') == 'chirp' for s in rec.segments):
        out['chirp'] = chirp_frf(rec)
    return out


def missing_reference(rec: Recording) -> np.ndarray:
    """
    Return the samples whose reference is missing, widened by a settling time.

    Samples whose reference is missing (NaN), widened by SETTLE_S after each stretch: the
    controller's input there is unknown, so simulation and measurement are not compared.
    """
    bad = ~np.all(np.isfinite(rec.reference), axis=1)
    if bad.any():
        settle = int(SETTLE_S * rec.fs)
        idx = np.flatnonzero(bad)
        out = bad.copy()
        ends = idx[np.r_[np.diff(idx) > 1, True]]
        for e in ends:
            out[e:e + settle + 1] = True
        return out
    return bad


class Evaluator:
    """
    Simulates candidate models on the recorded excitation and scores them per axis.

    Every loss term of an axis (diagonal FRF misfit of multisine and chirp, torque and velocity
    output error) is expressed in units of its noise floor measured in the data: the BLA noise
    variance from the multisine periods for the FRFs, the period-to-period variance of the
    measured torque and velocity for the time signals. A model that explains the axis to its
    noise scores about 1. ``simulator``: :class:`..common.Simulator` (default our plant).
    """

    def __init__(self, rec: Recording, ctrl: PIVelocity, *, jobs: int = SIM_JOBS,
                 simulator: Simulator | None = None) -> None:
        #: processes that simulate the models of one :meth:`prefetch` at once
        self.jobs = jobs
        self.simulator: Simulator = simulate_like if simulator is None else simulator
        self.unheld = unheld_by(simulator)      # effects it cannot hold: name -> why
        # rows lost in gaps of the bag are bridged and lose their reference: left out below
        self.rec, self.ctrl = bridge_gaps(rec)[0], ctrl
        rec = self.rec
        self.missing = missing_reference(rec)
        #: the reference every model is driven with (simulate_like forms it per call otherwise)
        self.drive = drive_reference(rec)
        fit, val, self.validation_text = split_recording(rec)
        self.fit, self.val = (drop_segments(fit, self.missing), drop_segments(val, self.missing))
        self.meas_fit = frf_estimates(self.fit)
        self.meas_val = frf_estimates(self.val) if self.val.segments else {}
        self.fit_mask = segment_mask(self.fit) & ~self.missing
        self.val_mask = segment_mask(self.val) & ~self.missing
        n = rec.velocity.shape[1]
        self.n = n
        self.base_terms: dict[str, np.ndarray] | None = None
        fl: dict[str, np.ndarray] = {}
        count: dict[str, float] = {}
        ms = self.meas_fit.get('multisine')
        rel = np.full(n, np.nan)
        if ms is not None and ms.noise_variance is not None:
            idx = np.arange(min(ms.response.shape[:2]))
            rel = np.mean(ms.noise_variance[idx, idx] / np.abs(ms.response[idx, idx]) ** 2,
                          axis=-1)
        for k, est in self.meas_fit.items():
            fl[k] = np.where(np.isfinite(rel), rel, FLOOR_MIN)
            count[k] = float(est.freq_hz.size)
        nv, nu = period_noise(rec, ~self.missing)
        m = self.fit_mask
        for key, var, x in (('effort', nu, rec.effort), ('velocity', nv, rec.velocity)):
            sig = np.var(x[m], axis=0) if m.any() else np.ones(n)
            fl[key] = np.where(np.isfinite(var), var / np.maximum(sig, 1e-300), FLOOR_MIN)
            # filtered closed-loop signals: about one independent sample per 10 ms
            count[key] = max(m.sum() * rec.dt / INDEPENDENT_SAMPLE_S, 10.0)
        self.floors = {k: np.maximum(v, FLOOR_MIN) for k, v in fl.items()}
        #: the floors of the held-out part: the chirp's at the held-out iteration's own level
        self.floors_held = dict(self.floors)
        if 'chirp' in self.floors and self.val.segments:
            self.floors_held['chirp'] = np.maximum(
                self.floors['chirp'] * held_out_chirp_scale(self.fit, self.val,
                                                            self.meas_fit['chirp']), FLOOR_MIN)
        self.counts = count
        self.lowest = np.full(n, np.inf)
        self.n_sims = 0
        self._sims: dict[str, Recording] = {}
        # estimates of a kept simulation on the fit part, where a worker computed them
        self._est: dict[str, dict] = {}
        self._residual: tuple[Any, Any] = (None, None)
        # loss terms of every model judged, by (repr, held out): a few numbers each
        self._terms: dict[tuple[str, bool], dict[str, np.ndarray]] = {}
        # measured signals on the fit / held-out mask and their RMS, by (signal, held out)
        self._measured: dict[tuple[str, bool], list[tuple[np.ndarray, Any]]] = {}
        self._workers: WorkerPool | None = None

    def residual(self, robot: RobotParams) -> tuple[np.ndarray, ...]:
        """
        Return the inverse-dynamics residual of a model on the recording.

        :func:`..residual.inverse_dynamics_residual` of ``robot``; the last model's is kept
        (every axis' friction and gravity readings of one model share it; models are replaced,
        never edited in place, so identity is the key).

        Parameters
        ----------
        robot : RobotParams
            The model.

        Returns
        -------
        f, q, v, a : ndarray, shape (N-1, n)
            Residual torque and position, velocity, acceleration between samples.

        """
        if self._residual[0] is not robot:
            rec = self.rec
            self._residual = (robot, inverse_dynamics_residual(rec.position, rec.velocity,
                                                               rec.effort, rec.dt, robot))
        return self._residual[1]

    def simulate(self, robot: RobotParams) -> Recording:
        """
        Return the closed-loop simulation of a model on the recorded excitation.

        :attr:`simulator` of ``robot`` on the (gap-bridged) recording, counted in
        :attr:`n_sims`. The same model is simulated again where a candidate is checked before
        its round (a damping mismatch before its viscous rival is refitted): the last
        SIM_CACHE simulations are kept, keyed by the model's repr.

        Parameters
        ----------
        robot : RobotParams
            The model.

        Returns
        -------
        Recording
            Simulated position, velocity and effort with the recording's segments.

        """
        key = repr(robot)
        if key not in self._sims:
            self._keep(key, self.simulator(self.rec, robot, self.ctrl, reference=self.drive))
        return self._sims[key]

    def prefetch(self, robots: Sequence[RobotParams]) -> None:
        """
        Simulate independent models at once (:attr:`jobs` processes) for :meth:`simulate`.

        The models not simulated yet (the first SIM_CACHE - 4 of them) are simulated by
        the evaluator's :class:`.parallel.WorkerPool` (forked at the first prefetch, kept
        until :meth:`close`) and kept, so the next :meth:`simulate` of each finds it: the same
        simulations and results as one after the other, in less wall time.
        With ``jobs`` 1 nothing is done here.

        Parameters
        ----------
        robots : sequence of RobotParams
            Models the caller simulates next.

        """
        if self.jobs < 2:
            return
        todo = {repr(r): r for r in robots}
        todo = {k: r for k, r in todo.items() if k not in self._sims}
        todo = dict(list(todo.items())[:SIM_CACHE - 4])
        if len(todo) < 2:
            return
        for key, (q, v, u, est) in zip(todo, self._pool().run(list(todo.values()))):
            self._keep(key, as_simulation(self.rec, q, v, u))
            self._keep_estimates(key, est)

    def _pool(self) -> WorkerPool:
        """Return the workers that simulate a model and estimate its fit part (forked once)."""
        if self._workers is None:
            rec, ctrl, fit, drive, simulate = (self.rec, self.ctrl, self.fit, self.drive,
                                               self.simulator)

            def run(robot: RobotParams) -> tuple:
                sim = simulate(rec, robot, ctrl, reference=drive)
                return (sim.position, sim.velocity, sim.effort,
                        frf_estimates(replace_segments(sim, fit)))
            # the three signals of a simulation come back through shared memory
            self._workers = WorkerPool(run, self.jobs, shared_bytes=3 * rec.velocity.nbytes + 256,
                                       max_items=SIM_CACHE - 4)
            weakref.finalize(self, self._workers.close)
        return self._workers

    def close(self) -> None:
        """Stop the simulation workers (:meth:`prefetch` starts them again when asked)."""
        if self._workers is not None:
            self._workers.close()

    def _keep(self, key: str, sim: Recording) -> None:
        """Count a new simulation and keep it (the oldest kept one goes beyond SIM_CACHE)."""
        self.n_sims += 1
        self._sims[key] = sim
        while len(self._sims) > SIM_CACHE:
            del self._sims[next(iter(self._sims))]

    def _keep_estimates(self, key: str, est: dict) -> None:
        """Keep a model's fit-part estimates (the oldest kept ones go beyond EST_CACHE)."""
        self._est[key] = est
        while len(self._est) > EST_CACHE:
            del self._est[next(iter(self._est))]

    def terms(self, robot: RobotParams, sim: Recording | None = None, *, held_out: bool = False
              ) -> dict[str, np.ndarray]:
        """
        Return the loss terms per axis of a model.

        Loss terms per axis (arrays of n): mean |ln(P_meas/P_model)|^2 over the lines of the
        diagonal element, torque and velocity NRMSE^2, on the fit (or held-out) part. Kept
        by model (``sim``, where given, is the model's simulation): a model judged again
        after its simulation left the SIM_CACHE kept ones (a candidate taken a round later) is
        not simulated again.
        """
        key = (repr(robot), held_out)
        if key not in self._terms:
            self._terms[key] = self._new_terms(robot, sim, held_out)
        return {k: v.copy() for k, v in self._terms[key].items()}

    def _new_terms(self, robot: RobotParams, sim: Recording | None, held_out: bool
                   ) -> dict[str, np.ndarray]:
        """Return :meth:`terms` of a model not judged before."""
        sim = sim if sim is not None else self.simulate(robot)
        est = (frf_estimates(replace_segments(sim, self.val)) if held_out and self.val.segments
               else self.fit_estimates(robot, sim))
        return self.terms_of(sim, est, held_out)

    def terms_of(self, sim: Recording, est: dict, held_out: bool) -> dict[str, np.ndarray]:
        """Return the loss terms of a simulation and its FRF estimates (fit or held out)."""
        meas = self.meas_val if held_out and self.meas_val else self.meas_fit
        m = self.val_mask if held_out and self.val_mask.any() else self.fit_mask
        out = {}
        for k, pm in meas.items():
            r = np.log(diag_ratio(pm, est[k]))
            out[k] = np.mean(np.abs(r) ** 2, axis=-1)
        for k in ('effort', 'velocity'):
            out[k] = self._output_error(k, getattr(sim, k), m, held_out)
        return out

    def _output_error(self, key: str, x: np.ndarray, m: np.ndarray, held_out: bool
                      ) -> np.ndarray:
        """
        Return :func:`..common.nrmse` ^ 2 per axis of a simulated signal on the mask ``m``.

        Both parts scaled by the fit part's RMS, the floor's scale (term / floor = mean square
        error / noise variance: with the held-out part's own RMS a weak held-out chirp put
        the true model at hundreds of floors). The measured side is formed once per part.
        """
        ref = self._measured.get((key, held_out))
        if ref is None:
            meas = getattr(self.rec, key)
            ref = [(meas[:, i][m], rms_about_mean(meas[:, i][self.fit_mask]))
                   for i in range(self.n)]
            self._measured[(key, held_out)] = ref
        return np.array([nrmse(a, x[:, i][m], scale=den) ** 2 for i, (a, den) in enumerate(ref)])

    def fit_estimates(self, robot: RobotParams, sim: Recording | None = None) -> dict:
        """
        Return :func:`estimates` of a model's simulation on the fit part.

        Kept (a worker computed them beside the simulation, or the first caller here; the
        last EST_CACHE, longer than the simulations), so the nominal model's are computed
        once for its misfit, stage 0 and stage 2, and a model's are at hand after its
        simulation was dropped. ``sim`` is the model's simulation where the caller has it.
        """
        key = repr(robot)
        if key not in self._est:
            sim = sim if sim is not None else self.simulate(robot)
            self._keep_estimates(key, frf_estimates(replace_segments(sim, self.fit)))
        return self._est[key]

    def loss(self, robot: RobotParams, axis: int) -> float:
        """Return the misfit of one axis (units of its noise floor) of a model, on the fit part."""
        return float(self.misfit(self.terms(robot))[axis])

    def misfit(self, terms: dict[str, np.ndarray], *, held_out: bool = False) -> np.ndarray:
        """
        Return per axis the mean of term / noise floor over the loss terms (1 = at noise).

        ``held_out``: the terms are the held-out part's (:attr:`floors_held`).
        """
        floors = self.floors_held if held_out else self.floors
        return np.mean([terms[k] / floors[k] for k in terms], axis=0)

    def held_out_misfit(self, robot: RobotParams, sim: Recording | None = None) -> np.ndarray:
        """Return :meth:`misfit` per axis of a model on the held-out part (its floors)."""
        return self.misfit(self.terms(robot, sim, held_out=True), held_out=True)

    def floor_seen(self, misfit: np.ndarray) -> np.ndarray:
        """
        Return per axis the noise floor in misfit units, lowered by what a model reached.

        The period-to-period floor (1 by construction) counts every response that does not
        repeat with the excitation period as noise, e.g. a torque ripple while the
        constant-velocity superposition moves the motor to another position each period. A
        model that predicts the fit part below it shows the true floor is lower: the floor is
        the smaller of 1 and the lowest misfit any evaluated model reached on the axis.

        Parameters
        ----------
        misfit : ndarray, shape (n_axes,)
            Misfit of a further model (on the fit part), taken into the record.

        Returns
        -------
        ndarray, shape (n_axes,)
            The floor per axis.

        """
        self.lowest = np.minimum(self.lowest, misfit)
        return np.minimum(self.lowest, 1.0)

    def misfit_sd(self) -> float:
        """
        Return the standard deviation of :meth:`misfit` under noise alone.

        Standard deviation of :meth:`misfit` under noise alone (exponentially distributed
        terms averaged over their independent lines / samples).
        """
        return float(np.sqrt(np.mean([1.0 / self.counts[k] for k in self.floors])
                             / len(self.floors)))

    def metrics(self, robot: RobotParams, sim: Recording | None = None) -> Scores:
        """Return the docs/CONTRACT.md §7 metrics on the held-out part, plus per axis."""
        sim = sim if sim is not None else self.simulate(robot)
        sv = replace_segments(sim, self.val if self.val.segments else self.fit)
        mv = self.meas_val if self.meas_val else self.meas_fit
        est = frf_estimates(sv)
        mask = self.val_mask if self.val_mask.any() else self.fit_mask
        per = {name: AxisScore(round(frf_error_db([(mv[k], est[k]) for k in mv], axis=i), 4),
                               round(nrmse(self.rec.velocity[:, i], sim.velocity[:, i], mask), 5))
               for i, name in enumerate(self.rec.joint_names)}
        return Scores(round(frf_error_db([(mv[k], est[k]) for k in mv]), 4),
                      round(nrmse(self.rec.velocity, sim.velocity, mask), 5), per)


def drop_segments(rec: Recording, missing: np.ndarray) -> Recording:
    """Return the recording without the segments that overlap samples without reference."""
    if not missing.any():
        return rec
    keep = [s for s in rec.segments if not missing[rec.slice(s.t_start, s.t_end)].any()]
    return replace_segments(rec, Recording(rec.t, rec.joint_names, rec.position, rec.velocity,
                                           rec.effort, segments=keep))


def replace_segments(rec: Recording, like: Recording) -> Recording:
    """Return ``rec`` with the segments of ``like`` (the same samples, another view)."""
    return Recording(rec.t, rec.joint_names, rec.position, rec.velocity, rec.effort,
                     rec.reference, rec.excitation, list(like.segments), rec.meta)
