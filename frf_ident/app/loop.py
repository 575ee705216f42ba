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
The controller check on a measured FRF: margins of L = C P-hat with their uncertainty.

Per axis, python-control's ``stability_margins`` on the FRD data of L_i = C_i P_ii gives the
gain, phase and modulus margins and the crossover; the same on draws of the FRF from its
variance (:func:`frf_ident.core.loop.check.draw_responses`) gives their standard deviations.
For several axes, the peak of the largest singular value of S = (I + P C)^-1 adds what the
coupling does. :func:`propose_gains` reads PI gains off the FRF for a target phase margin and
bandwidth; :func:`loop_check` then checks them on the measured FRF itself.
"""
from __future__ import annotations

import warnings

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.loop.check import (AxisMargins, draw_responses, DRAWS, loop_response,
                                       LoopCheck, Margin, pi_response, sensitivity_peak)
from frf_ident.core.loop.design import PIProposal, propose_pi
from frf_ident.errors import FrfIdentInputError
import numpy as np

__all__ = ['axis_channels', 'frf_variance', 'loop_check', 'margins', 'propose_gains']


def frf_variance(frf: FrequencyResponse) -> np.ndarray | None:
    """Return the total variance of ``frf`` if present, else its noise variance, else None."""
    return frf.total_variance if frf.total_variance is not None else frf.noise_variance


def axis_channels(frf: FrequencyResponse) -> list[tuple[str, int, int]]:
    """
    Return (axis, output index, input index) of every axis's own channel P_ii.

    Parameters
    ----------
    frf : FrequencyResponse
        Torque -> velocity FRF; each input is an axis, its output is the output of the same
        name (else the output of the same index).

    Returns
    -------
    list of tuple
        One entry per input.

    Raises
    ------
    FrfIdentInputError
        An input has no output of its name and no output at its index.

    """
    out = []
    for i, name in enumerate(frf.inputs):
        if name in frf.outputs:
            out.append((name, frf.outputs.index(name), i))
        elif i < frf.noutputs:
            out.append((name, i, i))
        else:
            raise FrfIdentInputError(f'FRF input {name!r} has no output of its name '
                                     f'(outputs {frf.outputs})')
    return out


def margins(loop: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """
    Return python-control's margins of SISO loop responses given as FRD data.

    Parameters
    ----------
    loop : ndarray of complex, shape (..., n_freq)
        L at ``omega``; leading axes are separate loops (e.g. draws).
    omega : ndarray, shape (n_freq,)
        Frequencies [rad/s].

    Returns
    -------
    ndarray, shape (..., 4)
        Gain margin [dB], phase margin [deg], gain crossover [Hz], modulus margin; NaN where
        python-control finds no crossover.

    """
    import control
    flat = loop.reshape(-1, loop.shape[-1])
    res = np.full((flat.shape[0], 4), np.nan)
    for k, lk in enumerate(flat):
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')
            gm, pm, sm, _, wgc, _ = control.stability_margins(
                control.frd(lk, omega, smooth=True), method='frd')
        res[k] = [20 * np.log10(gm) if gm and np.isfinite(gm) else np.inf, pm,
                  wgc / (2 * np.pi), sm]
    return res.reshape(loop.shape[:-1] + (4,))


def _margin(nominal: float, draws: np.ndarray | None) -> Margin:
    if draws is None:
        return Margin(float(nominal), float('nan'))
    ok = draws[np.isfinite(draws)]
    return Margin(float(nominal), float(ok.std(ddof=1)) if ok.size > 2 else float('nan'))


def loop_check(frf: FrequencyResponse, kp: np.ndarray, ki: np.ndarray, *,
               dt: float | None = None, draws: int = DRAWS, seed: int = 0) -> LoopCheck:
    """
    Check the velocity PI on the measured loop: margins with their uncertainty.

    Parameters
    ----------
    frf : FrequencyResponse
        Torque -> velocity FRF (square for the MIMO sensitivity peak); its total variance
        (else noise variance) gives the uncertainty.
    kp, ki : array_like, shape (n_axes,)
        PI gains per axis (in input order).
    dt : float, optional
        Sample time of the discrete PI as the simulation runs it; None: continuous PI.
    draws : int, optional
        Monte-Carlo draws of the FRF for the standard deviations.
    seed : int, optional
        Seed of the draws.

    Returns
    -------
    LoopCheck
        Per-axis margins, the MIMO sensitivity peak, and how many draws were used.

    Raises
    ------
    FrfIdentInputError
        The number of gains is not the number of axes.

    """
    chans = axis_channels(frf)
    kp, ki = np.atleast_1d(np.asarray(kp, float)), np.atleast_1d(np.asarray(ki, float))
    if kp.size != len(chans) or ki.size != len(chans):
        raise FrfIdentInputError(f'controller gains: expected {len(chans)} kp and ki values '
                                 f'(one per FRF input {frf.inputs}), got {kp.size} and '
                                 f'{ki.size}')
    var = frf_variance(frf)
    n_draws = draws if var is not None else 0
    rng = np.random.default_rng(seed)
    sample = (draw_responses(frf.response, var, n_draws, rng) if n_draws else None)
    c = np.stack([pi_response(frf.freq_hz, kp[j], ki[j], dt) for j in range(len(chans))])
    axes = []
    for j, (name, o, i) in enumerate(chans):
        nom = margins(frf.response[o, i] * c[j], frf.omega)
        drawn = margins(sample[:, o, i] * c[j], frf.omega) if n_draws else None
        axes.append(AxisMargins(name, float(kp[j]), float(ki[j]),
                                *[_margin(nom[q], None if drawn is None else drawn[:, q])
                                  for q in range(4)]))
    peak = None
    if len(chans) > 1 and frf.noutputs == frf.ninputs:
        nominal = float(sensitivity_peak(loop_response(frf.response, c)))
        drawn = sensitivity_peak(loop_response(sample, c)) if n_draws else None
        peak = _margin(nominal, drawn)
    return LoopCheck(axes, peak, n_draws, dt)


def propose_gains(frf: FrequencyResponse, bandwidth_hz: float, phase_margin_deg: float
                  ) -> list[PIProposal]:
    """
    Propose PI gains per axis from the measured FRF (see :mod:`frf_ident.core.loop.design`).

    Parameters
    ----------
    frf : FrequencyResponse
        Torque -> velocity FRF.
    bandwidth_hz : float
        Target crossover [Hz].
    phase_margin_deg : float
        Target phase margin [deg].

    Returns
    -------
    list of PIProposal
        One per axis, in input order.

    Raises
    ------
    FrfIdentInputError
        The bandwidth lies outside the measured band.

    """
    out = []
    for name, o, i in axis_channels(frf):
        try:
            out.append(propose_pi(frf.freq_hz, frf.response[o, i], bandwidth_hz,
                                  phase_margin_deg))
        except ValueError as err:
            raise FrfIdentInputError(f'--bandwidth: axis {name}: {err}') from err
    return out
