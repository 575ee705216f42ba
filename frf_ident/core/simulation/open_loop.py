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
Running excitation designs on a plant and estimating the FRF (open loop; the paper's Sec. 6).

These are the building blocks of the academic example: a multisine best linear approximation
over n_p realisations x n_q periods and a chirp estimate with the Sec. 5.1 processing, both on
a :class:`~frf_ident.core.simulation.plant.FlexibleJointPlant` driven directly by torque.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.spectra import (best_linear_approximation, BLAResult,
                                               detection_line_levels, frf_from_spectra,
                                               periodic_spectra)
from frf_ident.core.excitation.chirp import ChirpDesign
from frf_ident.core.excitation.chirp_dft import chirp_analysis_frequencies, chirp_spectra
from frf_ident.core.excitation.multisine import (multisine_realisation, MultisineDesign,
                                                 MultisineRealisation, reference_frequency_set)
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.errors import DesignError
import numpy as np

__all__ = ['OpenLoopChirpRun', 'OpenLoopMultisineRun', 'resonance_peak', 'run_open_loop_chirp',
           'run_open_loop_multisine', 'stage_grid']


def stage_grid(n_samples: int, fs: float, substeps: int, t_start: float = 0.0) -> np.ndarray:
    """
    Return the times of the integrator's stage grid (2 m points per sample, plus the end).

    Parameters
    ----------
    n_samples : int
        Number of samples N.
    fs : float
        Sample rate in Hz.
    substeps : int
        Integrator substeps m per sample.
    t_start : float, optional
        Time of the first point in s.

    Returns
    -------
    ndarray, shape (2 m N + 1,)
        Times in s, spacing 1 / (2 m fs).

    """
    return t_start + np.arange(2 * substeps * n_samples + 1) / (2 * substeps * fs)


@dataclass
class OpenLoopMultisineRun:
    """
    Result of an open-loop multisine experiment: the BLA and its raw material.

    Parameters
    ----------
    frf : FrequencyResponse
        The BLA tau_m -> dq_m at the excited lines, with noise and total variances.
    bla : BLAResult
        The full BLA result (per-realisation estimates, cond(U)).
    input_power : float
        Mean u^2 over the measured periods of every realisation and experiment [(N m)^2].
    crest_factor : float
        Mean crest factor of u over the realisations and experiments.
    detection : dict
        Output levels at excited, non-excited odd and even lines of the first experiment
        (``DetectionLevels.to_dict()``).

    """

    frf: FrequencyResponse
    bla: BLAResult
    input_power: float
    crest_factor: float
    detection: dict


def run_open_loop_multisine(plant: FlexibleJointPlant, design: MultisineDesign, *,
                            n_realisations: int, n_periods: int = 1,
                            transient_periods: int = 1, rng: np.random.Generator,
                            realisations: list[MultisineRealisation] | None = None,
                            ) -> OpenLoopMultisineRun:
    """
    Estimate the multisine BLA (eq. 14) with the torque injected directly at the plant input.

    Each realisation starts from rest, runs ``transient_periods`` discarded periods then
    ``n_periods`` measured ones; the excitation is evaluated on the integrator's stage grid so
    the plant sees the continuous-time signal. MIMO plants get n_u experiments per
    realisation with the eq. 9 shifts.

    Parameters
    ----------
    plant : FlexibleJointPlant
        The plant, driven by torque (reset before every experiment).
    design : MultisineDesign
        The multisine design; its period must be a whole number of plant samples.
    n_realisations : int
        Number of realisations n_p.
    n_periods : int, optional
        Measured periods per realisation n_q.
    transient_periods : int, optional
        Periods discarded before the measured ones.
    rng : numpy.random.Generator
        Source of the random phases (unused for given ``realisations``).
    realisations : list of MultisineRealisation, optional
        Precomputed realisations (at least ``n_realisations``), used instead of drawing new
        ones.

    Returns
    -------
    OpenLoopMultisineRun
        The BLA as a FrequencyResponse and its raw material.

    Raises
    ------
    DesignError
        ``n_realisations`` or ``n_periods`` < 1, or the period is not a whole number of
        samples.

    """
    if n_realisations < 1 or n_periods < 1:
        raise DesignError(f'{n_realisations=} and {n_periods=} must be at least 1')
    fs = 1.0 / plant.dt
    n_u = plant.n_axes
    n_per = design.period_samples(fs)
    total = (transient_periods + n_periods) * n_per
    m = int(plant.params.substeps)
    grid = stage_grid(total, fs, m)
    Us, Ys, y_periods, powers, crests = [], [], [], [], []
    for p in range(n_realisations):
        real = realisations[p] if realisations else multisine_realisation(design, n_u, rng, fs=fs)
        sig = real.evaluate(grid)                      # (n_ex, grid, n_u)
        U_p, Y_p, yp = [], [], []
        for m_ex in range(n_u):
            plant.reset()
            res = plant.simulate(torque_fine=sig[m_ex])
            u = res.effort[transient_periods * n_per:].reshape(n_periods, n_per, n_u)
            y = res.velocity[transient_periods * n_per:].reshape(n_periods, n_per, n_u)
            U_p.append(periodic_spectra(u, design.harmonics, axis=1))
            Y_p.append(periodic_spectra(y, design.harmonics, axis=1))
            yp.append(y)
            powers.append(np.mean(u ** 2))
            crests.append(np.max(np.abs(u)) / np.sqrt(np.mean(u ** 2)))
        Us.append(np.stack(U_p, axis=-1))               # (n_q, n_freq, n_u, n_ex)
        Ys.append(np.stack(Y_p, axis=-1))
        y_periods.append(yp[0])
    bla = best_linear_approximation(np.stack(Ys), np.stack(Us))
    names = plant.joint_names
    frf = FrequencyResponse(design.freq_hz, bla.response, [f'tau_m/{j}' for j in names],
                            [f'dq_m/{j}' for j in names], bla.noise_variance, bla.total_variance,
                            {'design': 'multisine', 'n_p': n_realisations, 'n_q': n_periods,
                             'cond_max': float(np.max(bla.cond))})
    det = detection_line_levels(np.stack(y_periods), design.harmonics,
                                int(design.harmonics[-1]))
    return OpenLoopMultisineRun(frf, bla, float(np.mean(powers)), float(np.mean(crests)),
                                det.to_dict())


@dataclass
class OpenLoopChirpRun:
    """
    Result of open-loop chirp experiments: the estimate and the recorded signals.

    Parameters
    ----------
    frf : FrequencyResponse
        The estimate tau_m -> dq_m at the analysis frequencies (no variances).
    input_power : float
        Mean u^2 over [t0, t1) of every experiment [(N m)^2].
    u : ndarray, shape (n_ex, N, n_u)
        Plant input (motor torque) of each experiment.
    y : ndarray, shape (n_ex, N, n_u)
        Plant output (motor velocity) of each experiment.
    t : ndarray, shape (N,)
        Sample times in s.

    """

    frf: FrequencyResponse
    input_power: float
    u: np.ndarray
    y: np.ndarray
    t: np.ndarray


def run_open_loop_chirp(plant: FlexibleJointPlant, design: ChirpDesign, phases: np.ndarray, *,
                        analysis_freqs: np.ndarray | None = None, n_ref: int = 80,
                        ) -> OpenLoopChirpRun:
    """
    Run chirp experiments (eqs. 15-16) injected at the plant input, estimated as Sec. 5.1.

    One experiment per column of ``phases``, each from rest; P = Y U^+ (eq. 7) per analysis
    frequency.

    Parameters
    ----------
    plant : FlexibleJointPlant
        The plant, driven by torque.
    design : ChirpDesign
        The chirp design.
    phases : ndarray, shape (n_u, n_ex)
        MIMO phase matrix (eq. 9, or eq. 26 from
        :func:`~frf_ident.core.excitation.chirp.chirp_phase_flips`).
    analysis_freqs : array_like, optional
        Candidate analysis frequencies in Hz; default the ``n_ref`` log-spaced frequencies
        of the band. Only those with four periods inside the sweep are analysed.
    n_ref : int, optional
        Size of the default log-spaced set.

    Returns
    -------
    OpenLoopChirpRun
        The estimate and the recorded signals.

    Raises
    ------
    DesignError
        ``f_high`` is at or above the Nyquist frequency, or no analysis frequency has four
        periods inside the chirp.

    """
    fs = 1.0 / plant.dt
    design.check_sample_rate(fs)
    n = int(round(design.t1 * fs)) + 1
    m = int(plant.params.substeps)
    sig = design.evaluate(stage_grid(n, fs, m), phases)
    f_cand = reference_frequency_set(design.f_low, design.f_high, n_ref) \
        if analysis_freqs is None else np.asarray(analysis_freqs, dtype=float)
    freqs = chirp_analysis_frequencies(f_cand, design.time_at, design.t0, design.t1)
    if freqs.size == 0:
        raise DesignError('no analysis frequency has four periods inside the chirp')
    tc = design.time_at(freqs)
    U, Y, us, ys = [], [], [], []
    for m_ex in range(phases.shape[1]):
        plant.reset()
        res = plant.simulate(torque_fine=sig[m_ex])
        U.append(chirp_spectra(res.effort, fs, freqs, tc))
        Y.append(chirp_spectra(res.velocity, fs, freqs, tc))
        us.append(res.effort)
        ys.append(res.velocity)
    P, cond = frf_from_spectra(np.stack(Y, axis=-1), np.stack(U, axis=-1))
    names = plant.joint_names
    i0, i1 = int(design.t0 * fs), int(design.t1 * fs)
    power = float(np.mean(np.stack(us)[:, i0:i1] ** 2))
    frf = FrequencyResponse(freqs, P, [f'tau_m/{j}' for j in names],
                            [f'dq_m/{j}' for j in names], meta={
                                'design': 'chirp', 'cond_max': float(np.max(cond))})
    return OpenLoopChirpRun(frf, power, np.stack(us), np.stack(ys), res.t)


def resonance_peak(freq_hz: np.ndarray, response: np.ndarray, band: tuple[float, float]
                   ) -> tuple[float, float]:
    """
    Return frequency [Hz] and magnitude [dB] of the largest peak of |response| in ``band``.

    Refined by a parabola through the three lines around the maximum in (log f, dB) when
    that parabola has its vertex between them.

    Parameters
    ----------
    freq_hz : array_like, shape (n_freq,)
        Frequencies in Hz, increasing.
    response : array_like, shape (n_freq,)
        Complex (or magnitude) response at ``freq_hz``.
    band : tuple of float
        (low, high) in Hz, inclusive.

    Returns
    -------
    tuple of float
        (resonance frequency in Hz, peak magnitude in dB).

    Raises
    ------
    ValueError
        No line lies inside ``band``.

    """
    f = np.asarray(freq_hz, dtype=float)
    mag = 20 * np.log10(np.maximum(np.abs(response), 1e-300))
    idx = np.flatnonzero((f >= band[0]) & (f <= band[1]))
    if idx.size == 0:
        raise ValueError(f'no line inside {band=}')
    k = idx[np.argmax(mag[idx])]
    if 0 < k < f.size - 1:
        x = np.log(f[k - 1:k + 2])
        y = mag[k - 1:k + 2]
        a, b, c = np.polyfit(x, y, 2)
        if a < 0:
            xv = -b / (2 * a)
            if x[0] <= xv <= x[2]:
                return float(np.exp(xv)), float(np.polyval([a, b, c], xv))
    return float(f[k]), float(mag[k])
