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
The running multisine BLA while a run goes on: one estimate per complete MIMO period.

:class:`LiveMultisine` takes the samples of a streamed multisine procedure as they come
(joint states, the excitation of each sample, the segment descriptors) and, after every whole
period, the estimate of the periods so far. It feeds
:class:`~frf_ident.core.estimation.multisine_estimate.MultisineSpectra` with each segment's
series up to its last whole period, exactly as the offline estimator feeds it a recorded
segment, so the estimate after the last period is the offline estimate of the recording (same
arithmetic).

A MIMO realisation is one experiment per axis (eq. 9); its period q exists once every
experiment has run period q, so the estimate changes only in a realisation's last experiment
(the others' periods are kept and used then). Samples go in at the node's joint-state rate
(a few array writes each); the spectra and the BLA are computed by :meth:`LiveMultisine.update`,
which the caller runs off its control path.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.multisine_estimate import MultisineSpectra
import numpy as np

__all__ = ['LiveEstimate', 'LiveMultisine', 'multiple_coherence', 'NONLINEAR_RATIO',
           'PeriodDone']

#: median total / noise variance ratio over the lines at which the nonlinear distortion
#: counts as significant (the live sd is then the total one): without distortion the ratio
#: is F-distributed about 1 (its median 0.76 for 2 realisations of 5 periods, 0.99 for many);
#: a distortion as large as the noise doubles it
NONLINEAR_RATIO = 2.0


def multiple_coherence(X: list[np.ndarray], R: list[np.ndarray]) -> np.ndarray:
    """
    Return the multiple coherence of each signal with all references, per line.

    gamma_i^2 = (S_xr S_rr^-1 S_rx)_ii / S_xx_ii over every period of every experiment (a
    period of one experiment is one record): the share of the signal's power the references
    explain linearly. With periodic references it is |mean X|^2 / mean |X|^2 per SISO line,
    1 without noise, and falls as noise grows; with no more records than references it is 1
    by construction (undefined): nan.

    Parameters
    ----------
    X : list of ndarray, shape (n_q, F, n_x, n_ex)
        The signal's period spectra, one array per realisation.
    R : list of ndarray, shape (n_q, F, n_r, n_ex)
        The references' spectra, alike.

    Returns
    -------
    ndarray, shape (n_x, F)

    """
    Xs = np.concatenate([np.moveaxis(x, 0, -1).reshape(x.shape[1:3] + (-1,)) for x in X], -1)
    Rs = np.concatenate([np.moveaxis(r, 0, -1).reshape(r.shape[1:3] + (-1,)) for r in R], -1)
    if Xs.shape[-1] <= Rs.shape[1]:
        return np.full((Xs.shape[1], Xs.shape[0]), np.nan)
    Sxr = Xs @ np.conj(np.swapaxes(Rs, -1, -2))            # (F, n_x, n_r)
    Srr = Rs @ np.conj(np.swapaxes(Rs, -1, -2))
    explained = np.einsum('fij,fjk,fik->fi', Sxr, np.linalg.pinv(Srr), np.conj(Sxr)).real
    power = np.sum(np.abs(Xs) ** 2, axis=-1)
    return (explained / np.maximum(power, 1e-300)).T


@dataclass
class LiveEstimate:
    """
    The BLA of the periods so far, with what a viewer and the target rule need.

    Parameters
    ----------
    frf : FrequencyResponse
        The estimate (n_out, n_in, F), as the offline estimator gives it for the same data.
    coherence : ndarray, shape (n_out, F)
        Multiple coherence of each (compensated) output with the references; nan while
        undefined (one period).
    input_coherence : ndarray, shape (n_in, F)
        The same for the plant inputs (torques).
    periods : int
        MIMO periods used (over all realisations).
    realisations : int
        Complete realisations among them.
    t : float
        End [s] of the period that completed this estimate.
    final : bool
        True for the estimate of the whole run (the procedure ended).
    planned_periods : int or None
        MIMO periods the design holds (realisations x periods; None: not known).

    """

    frf: FrequencyResponse
    coherence: np.ndarray
    input_coherence: np.ndarray
    periods: int
    realisations: int
    t: float
    final: bool = False
    planned_periods: int | None = None

    def variance_kind(self) -> str | None:
        """
        Return which variance the live sd is: 'total', 'noise' or None (one period).

        The total variance (spread over realisations) has 2 (n_p - 1) degrees of freedom per
        line, the noise variance (spread over periods) many more: the largest sd over a few
        hundred lines from two realisations is 2.4 times the truth. So the noise variance
        stands for the total while the nonlinear part is not significant: the median over
        the lines of total / noise below :data:`NONLINEAR_RATIO` in every channel.
        """
        f = self.frf
        if f.total_variance is None or f.noise_variance is None:
            return f.variance_kind()
        ratio = np.median(f.total_variance / np.maximum(f.noise_variance, 1e-300), axis=-1)
        return 'total' if np.any(ratio >= NONLINEAR_RATIO) else 'noise'

    def _relative_sd(self) -> np.ndarray:
        kind = self.variance_kind()
        if kind is None:
            return np.full(self.frf.response.shape, np.nan)
        var = self.frf.total_variance if kind == 'total' else self.frf.noise_variance
        return np.sqrt(np.maximum(var, 0.0)) / np.maximum(np.abs(self.frf.response), 1e-300)

    @property
    def magnitude_sd_db(self) -> np.ndarray:
        """
        Return the 1-sigma magnitude uncertainty [dB], (n_out, n_in, F); nan without one.

        20 log10(1 + sigma / |P|), as ``FrequencyResponse.std_db``, of
        :meth:`variance_kind`'s variance.
        """
        return 20.0 * np.log10(1.0 + self._relative_sd())

    @property
    def phase_sd_deg(self) -> np.ndarray:
        """Return the 1-sigma phase uncertainty [deg] (first order), (n_out, n_in, F)."""
        return np.degrees(np.minimum(self._relative_sd(), np.pi))

    def worst_sd_db(self) -> float:
        """Return the largest magnitude sd over every channel and line [dB] (nan: none yet)."""
        sd = self.magnitude_sd_db
        return float(np.max(sd)) if np.all(np.isfinite(sd)) else float('nan')


@dataclass
class PeriodDone:
    """
    A whole period of a segment is in: what :meth:`LiveMultisine.update` processes.

    Parameters
    ----------
    key : tuple of int
        (realisation, experiment), or (-1, -1) for the constant-velocity run.
    periods : int
        Steady periods of the segment complete so far (0 for the run's end).
    k_end : int
        Sample index one past the period's last sample.
    last : bool
        True when the segment ended with it (no further period follows).

    """

    key: tuple[int, int]
    periods: int
    k_end: int
    last: bool


class _Segment:
    """The series of one streamed segment, filled one joint state at a time."""

    def __init__(self, info: dict[str, Any], k0: int, k1: int, n: int) -> None:
        self.info, self.k0, self.k1 = info, k0, k1
        self.cv = info.get('design') == 'constant_velocity'
        self.key = (int(info.get('realisation', -1)), int(info.get('experiment', -1)))
        size = k1 - k0
        self.a = {k: np.full((size, n), np.nan) for k in ('u', 'y', 'r', 'q')}
        self.n_per = int(info['period_samples'])
        self.n_tr = int(info['transient_periods'])
        self.n_q = int(info['periods'])
        self.done = 0            # steady periods reported complete

    def complete_rows(self, k_u: int) -> int:
        """Rows whose torque is in (every other series comes with or before it)."""
        return max(0, min(k_u + 1, self.k1) - self.k0)


class LiveMultisine:
    """
    Running multisine BLA of a streamed procedure (see the module docstring).

    Parameters
    ----------
    joint_names : list of str
        The joints, in the order of the samples given.
    fs : float
        Sample rate [Hz].
    effort_lag : int
        Joint state k carries the torque of sample ``k - effort_lag`` (1 in the lockstep
        simulation, 0 on a robot; the descriptors' ``effort_lag``).

    """

    def __init__(self, joint_names: list[str], fs: float, effort_lag: int) -> None:
        self.joints = list(joint_names)
        self.n = len(self.joints)
        self.fs = float(fs)
        self.lag = int(effort_lag)
        self.spectra: MultisineSpectra | None = None
        self.open: list[_Segment] = []
        self.segments: dict[tuple[int, int], _Segment] = {}
        self.stopped: set[tuple[int, int]] = set()

    # -- the streamed side (cheap: called for every sample) ----------------------------------
    def start(self, info: dict[str, Any], k0: int, k1: int) -> None:
        """
        Start following a multisine or constant-velocity segment from sample ``k0``.

        Parameters
        ----------
        info : dict
            Its descriptor (other designs are ignored).
        k0, k1 : int
            Its first sample and one past its last.

        """
        if info.get('design') not in ('multisine', 'constant_velocity'):
            return
        seg = _Segment(info, k0, k1, self.n)
        self.open.append(seg)
        self.segments[seg.key] = seg

    def excitation(self, k: int, x: np.ndarray) -> None:
        """
        Take the excitation part of sample ``k`` (what /frf/excitation carries).

        Parameters
        ----------
        k : int
            Sample index.
        x : ndarray, shape (n,)
            Excitation [rad/s].

        """
        for seg in self.open:
            if seg.k0 <= k < seg.k1:
                seg.a['r'][k - seg.k0] = x

    def sample(self, k: int, q: np.ndarray, y: np.ndarray,
               effort: np.ndarray | None) -> list[PeriodDone]:
        """
        Take joint state ``k``; return the periods it completed.

        Parameters
        ----------
        k : int
            Sample index of the joint state.
        q, y : ndarray, shape (n,)
            Measured position [rad] and velocity [rad/s].
        effort : ndarray, shape (n,) or None
            The torque the joint state carries (of sample ``k - effort_lag``).

        Returns
        -------
        list of PeriodDone
            Usually empty; one entry when a whole period (or the run) completed.

        """
        out = []
        for seg in list(self.open):
            if seg.k0 <= k < seg.k1:
                seg.a['q'][k - seg.k0] = q
                seg.a['y'][k - seg.k0] = y
            j = k - self.lag
            if effort is not None and seg.k0 <= j < seg.k1:
                seg.a['u'][j - seg.k0] = effort
            out += self._drain(seg, j)
        return out

    def _drain(self, seg: _Segment, k_u: int) -> list[PeriodDone]:
        """Every period (or the run's end) up to torque sample ``k_u``, one entry each."""
        out: list[PeriodDone] = []
        while True:
            got = self._completed(seg, k_u)
            out += got
            if not got or got[-1].last:
                return out

    def block(self, k0: int, q: np.ndarray, y: np.ndarray, u: np.ndarray,
              x: np.ndarray) -> list[PeriodDone]:
        """
        Take the samples ``k0 ..`` of a recorded block at once (the offline runner).

        Parameters
        ----------
        k0 : int
            Sample index of the block's first row.
        q, y, u, x : ndarray, shape (N, n)
            Position, velocity, torque (of the same samples) and excitation.

        Returns
        -------
        list of PeriodDone
            The periods the block completed.

        """
        k1 = k0 + q.shape[0]
        out = []
        for seg in list(self.open):
            a, b = max(seg.k0, k0), min(seg.k1, k1)
            if a < b:
                for key, src in (('q', q), ('y', y), ('u', u), ('r', x)):
                    seg.a[key][a - seg.k0:b - seg.k0] = src[a - k0:b - k0]
            out += self._drain(seg, k1 - 1)
        return out

    def stop(self, key: tuple[int, int], k_end: int) -> list[PeriodDone]:
        """
        End the segment ``key`` at sample ``k_end`` (the run stopped at its target).

        Parameters
        ----------
        key : tuple of int
            (realisation, experiment).
        k_end : int
            One past its last whole period's last sample.

        Returns
        -------
        list of PeriodDone
            The segment's end (its periods are all in already).

        """
        seg = self.segments[key]
        seg.k1 = k_end
        seg.n_q = seg.done
        self.stopped.add(key)
        return self._completed(seg, k_end - 1)

    def _completed(self, seg: _Segment, k_u: int) -> list[PeriodDone]:
        rows = seg.complete_rows(k_u)
        if seg.cv:
            if rows >= seg.k1 - seg.k0:
                self.open.remove(seg)
                return [PeriodDone(seg.key, 0, seg.k1, True)]
            return []
        steady = (rows - seg.n_tr * seg.n_per) // seg.n_per
        if steady <= seg.done or seg.done >= seg.n_q:
            return []
        seg.done += 1                 # one period per call: each is judged on its own
        last = seg.done >= seg.n_q
        if last:
            self.open.remove(seg)
        k_end = seg.k0 + (seg.n_tr + seg.done) * seg.n_per
        return [PeriodDone(seg.key, seg.done, k_end, last)]

    # -- the estimate (seconds of work at most; off the control path) ---------------------------
    def update(self, done: PeriodDone) -> LiveEstimate | None:
        """
        Add a completed period's data; return the estimate when it changed, else None.

        Parameters
        ----------
        done : PeriodDone
            From :meth:`sample` or :meth:`stop`.

        Returns
        -------
        LiveEstimate or None
            None until a realisation holds a period of every experiment, and for periods of
            experiments whose realisation is not complete yet.

        """
        seg = self.segments[done.key]
        if seg.cv:
            self._spectra(seg.info).set_constant_velocity(seg.a)
            return None
        ms = self._spectra(seg.info)
        info = dict(seg.info, periods=done.periods)
        if done.periods < seg.n_q or done.key in self.stopped:
            info['periods_planned'] = int(seg.info['periods'])
        n_ex = int(seg.info.get('n_axes', 1))
        final_of_realisation = done.key[1] == n_ex - 1
        if not (done.last or final_of_realisation):
            return None          # the estimate needs the realisation's last experiment
        need = (seg.n_tr + done.periods) * seg.n_per
        ms.add_arrays({k: v[:need] for k, v in seg.a.items()}, info, seg.k0 / self.fs,
                      self.fs, self.joints)
        if not final_of_realisation or not ms.any_complete():
            return None
        if sum(v.size for v in ms.used_periods().values()) < 2:
            return None          # the estimator's own minimum: two periods to average
        return self.estimate(t=done.k_end / self.fs)

    def estimate(self, t: float, final: bool = False) -> LiveEstimate:
        """
        Return the estimate of every period added so far.

        Parameters
        ----------
        t : float
            Time [s] it refers to (the end of the newest period).
        final : bool, optional
            Mark it as the run's final estimate.

        Returns
        -------
        LiveEstimate

        """
        ms = self.spectra
        cv = ms.cv is not None
        frf, _ = ms.frf(compensate=cv)
        R = ms.period_spectra('r', cv)
        coh = multiple_coherence(ms.period_spectra('y', cv), R)
        coh_u = multiple_coherence(ms.period_spectra('u', cv), R)
        used = ms.used_periods()
        planned = [int(g.info.get('n_realisations', 1)) * g.n_q
                   for g in self.segments.values() if not g.cv]
        return LiveEstimate(frf, coh, coh_u, int(sum(v.size for v in used.values())),
                            len(used), float(t), final, max(planned) if planned else None)

    def _spectra(self, info: dict[str, Any]) -> MultisineSpectra:
        if self.spectra is None:
            self.spectra = MultisineSpectra(info)
        return self.spectra
