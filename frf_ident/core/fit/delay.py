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
The input delay of a physical fit: its start from the phase, and how it is written for people.

A fitted delay starts from the phase slope of s P over the highest lines
(:func:`delay_from_phase`), refined once by the phase the delay-compensated start leaves
(:func:`delay_correction`). The model file counts the delay beyond the zero-order hold's half
sample (its ``time_delay``); :func:`delay_text` prints it in that convention.
"""
from __future__ import annotations

import numpy as np

__all__ = ['DELAY_START_SHARE', 'delay_correction', 'delay_from_phase', 'delay_text']

#: share of the lines (the highest in frequency, at least 3) whose phase slope starts a fitted
#: delay: above the resonance the velocity FRF times s tends to 1/Jm, so its phase there is the
#: delay's -omega tau plus a constant; a quarter keeps the resonance's phase out on the
#: section-6 joint and the 3-axis robot measured to 60 Hz (the refinement removes the rest)
DELAY_START_SHARE = 0.25


def delay_from_phase(freq_hz: np.ndarray, response: np.ndarray) -> float:
    """
    Return a delay read off the phase slope of s P(s) over the highest lines.

    The highest :data:`DELAY_START_SHARE` of the lines (at least 3): the unwrapped phase of
    s P(j omega) is fitted by a - omega tau (least squares); above the resonance s P tends to a
    positive constant (1 / Jm), so the slope is the delay. A start only: the resonance's
    phase tail biases it a little.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Frequencies in Hz (increasing).
    response : ndarray of complex, shape (n_freq,)
        Measured velocity FRF.

    Returns
    -------
    float
        The delay [s], at least 0.

    """
    f = np.asarray(freq_hz, dtype=float)
    order = np.argsort(f)
    top = order[-max(3, int(np.ceil(DELAY_START_SHARE * f.size))):]
    w = 2 * np.pi * f[top]
    phase = np.unwrap(np.angle(1j * w * np.asarray(response)[top]))
    slope = np.polyfit(w, phase, 1)[0]
    return max(float(-slope), 0.0)


def delay_correction(freq_hz: np.ndarray, measured: np.ndarray, model: np.ndarray,
                     sigma: np.ndarray) -> float:
    """Return the delay the phase of measured / model still shows (weighted, through 0)."""
    w = 2 * np.pi * freq_hz
    phase = np.angle(measured / model)
    weight = np.abs(measured) ** 2 / sigma ** 2              # 1 / variance of the phase
    return float(-np.sum(weight * w * phase) / np.sum(weight * w ** 2))


def delay_text(delay_s: float, std_s: float, hold_s: float = 0.0) -> str:
    """
    Return the delay in the model file's convention, for people.

    Parameters
    ----------
    delay_s : float
        The whole input delay of the fit [s].
    std_s : float
        Its standard error [s]; NaN when the delay was given.
    hold_s : float, optional
        The zero-order hold's half sample [s] the simulation has by itself; the model
        file's ``time_delay`` is ``delay_s - hold_s`` (at least 0).

    Returns
    -------
    str
        E.g. ``time_delay 0.0015 +- 0.00057 ms (fitted; the whole delay 0.5015 ms less the
        zero-order hold's 0.5 ms)``.

    Examples
    --------
    >>> delay_text(0.0005015, 5.7e-7, 0.0005).split('; ')[0]
    'time_delay 0.0015 +- 0.00057 ms (fitted'
    >>> delay_text(0.0005, float('nan'))
    'delay 0.5 ms (given)'

    """
    how = 'fitted' if np.isfinite(std_s) else 'given'
    sd = f' +- {1e3 * std_s:.2g}' if np.isfinite(std_s) else ''
    if not hold_s:
        return f'delay {1e3 * delay_s:.4g}{sd} ms ({how})'
    return (f'time_delay {1e3 * max(delay_s - hold_s, 0.0):.4g}{sd} ms ({how}; the whole delay '
            f"{1e3 * delay_s:.4g} ms less the zero-order hold's {1e3 * hold_s:.4g} ms)")
