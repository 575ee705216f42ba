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
Why a target is missed, in one sentence with the numbers: the loop's phase budget there.

At the frequency where a :class:`~frf_ident.core.loop.shaping.Limit` binds, the phase of
L = P PI F splits into the plant's (of which an input delay tau takes -360 f tau deg), the
PI's and the filters'; the sentence names the largest share and whether the frequency lies
in a resonance band.
"""
from __future__ import annotations

from frf_ident.core.loop.check import pi_response
from frf_ident.core.loop.modes import ResonanceBand
from frf_ident.core.loop.shaping import AxisSetting, Limit
import numpy as np

__all__ = ['explain_limit', 'phase_budget']

_WHAT = {'phase_margin_deg': ('phase margin', 'deg'), 'gain_margin_db': ('gain margin', 'dB'),
         'modulus_margin': ('modulus margin min |1 + L|', ''),
         'robust': ('max |W T| (robust stability)', ''), 'crossover_hz': ('crossover', 'Hz')}


def phase_budget(freq_hz: np.ndarray, response: np.ndarray, setting: AxisSetting, dt: float,
                 at_hz: float, delay_s: float | None = None) -> dict[str, float]:
    """
    Return the phase of the loop's parts at one frequency [deg].

    Parameters
    ----------
    freq_hz : ndarray
        The measured lines [Hz].
    response : ndarray of complex
        The plant P_ii at those lines.
    setting : AxisSetting
        The controller.
    dt : float
        Controller sample time [s].
    at_hz : float
        Where [Hz] (interpolated between the lines).
    delay_s : float, optional
        A fitted input delay [s]: its share -360 f tau is reported.

    Returns
    -------
    dict
        ``plant``, ``delay`` (NaN without one), ``pi``, ``filters``, ``magnitude`` (|L|).

    """
    f = np.asarray(freq_hz, dtype=float)
    ph = np.unwrap(np.angle(response))
    plant = float(np.degrees(np.interp(at_hz, f, ph)))
    plant = (plant + 180.0) % 360.0 - 180.0
    mag = float(np.exp(np.interp(at_hz, f, np.log(np.abs(response)))))
    pi = complex(pi_response(np.array([at_hz]), setting.kp, setting.ki, dt)[0])
    filt = complex(setting.filter_response(np.array([at_hz]))[0])
    return {'plant': plant, 'delay': -360.0 * at_hz * delay_s if delay_s else float('nan'),
            'pi': float(np.degrees(np.angle(pi))), 'filters': float(np.degrees(np.angle(filt))),
            'magnitude': mag * abs(pi) * abs(filt)}


def _band(at_hz: float, bands: list[ResonanceBand]) -> str:
    for b in bands:
        if 0.9 * b.low_hz <= at_hz <= 1.1 * b.high_hz:
            return f', at the resonance (band {b.low_hz:.4g}-{b.high_hz:.4g} Hz)'
    return ''


def explain_limit(limit: Limit, freq_hz: np.ndarray, response: np.ndarray,
                  setting: AxisSetting, dt: float, *, pose: str = '',
                  delay_s: float | None = None, bands: list[ResonanceBand] = ()) -> str:
    """
    Return one sentence: which target binds, where, and the phase budget there.

    Parameters
    ----------
    limit : Limit
        What binds (from :func:`~frf_ident.core.loop.shaping.shape_axis`).
    freq_hz, response : ndarray
        The lines and P_ii of the pose where it binds.
    setting : AxisSetting
        The chosen controller.
    dt : float
        Controller sample time [s].
    pose : str, optional
        The pose's name.
    delay_s : float, optional
        The pose's fitted input delay [s].
    bands : list of ResonanceBand, optional
        The axis' resonance bands.

    Returns
    -------
    str
        The sentence.

    """
    at = f' at pose {pose}' if pose else ''
    if limit.target == 'judge':
        return (f'the {int(limit.value)} best settings on the measured lines all miss a target '
                f'as reported (python-control between the lines, or the MIMO loop with the axes '
                f'tuned before closed); the last is kept: see its margins')
    if limit.target == 'band':
        return ("no setting keeps the loop's crossover inside the measured band "
                f'{freq_hz[0]:.4g}-{freq_hz[-1]:.4g} Hz{at} (|L| must exceed 1 at its lowest line '
                f'and fall below 1 at its highest; best: {limit.value:.3g} dB below 1 at the '
                f'highest): measure a wider band, or ask for a crossover inside it')
    if limit.target == 'stability':
        return (f'no setting keeps the loop stable with its crossover inside the measured band'
                f'{at} (best: {int(limit.value)} encirclements of -1; sensitivity peak at '
                f'{limit.frequency_hz:.4g} Hz)')
    name, unit = _WHAT[limit.target]
    if limit.target == 'crossover_hz':
        head = (f'crossover: {limit.value:.3g} Hz reached{at}, {limit.wanted:.3g} Hz asked')
        if limit.because is None:
            return head + ': no candidate setting crosses that high'
        sub = explain_limit(limit.because, freq_hz, response, setting, dt, pose='',
                            delay_s=delay_s, bands=bands)
        return f'{head}; the best setting that crosses there misses its {sub}'
    if limit.target == 'gain_margin_db' and np.isinf(limit.frequency_hz):
        return (f'gain margin: |L| at the highest measured line ({freq_hz[-1]:.4g} Hz) is '
                f'{limit.value:.3g} dB below 1, less than the {limit.wanted:g} dB asked{at}; '
                f'beyond the band the phase is unknown (measure a wider band)')
    if not np.isfinite(limit.frequency_hz):
        return f'{name} {limit.value:.3g} {unit} (target {limit.wanted:g} {unit}){at}'.strip()
    b = phase_budget(freq_hz, response, setting, dt, limit.frequency_hz, delay_s)
    delay = '' if not np.isfinite(b['delay']) else \
        f' ({b["delay"]:.0f} deg of it the {1e3 * delay_s:.3g} ms delay)'
    cmp = '>' if limit.target == 'robust' else '<'
    return (f'{name} {limit.value:.3g}{" " + unit if unit else ""} {cmp} {limit.wanted:g}'
            f'{" " + unit if unit else ""} at {limit.frequency_hz:.4g} Hz{at}'
            f'{_band(limit.frequency_hz, list(bands))}: |L| {b["magnitude"]:.3g}, the plant\'s '
            f'phase {b["plant"]:.0f} deg{delay}, the PI\'s {b["pi"]:.0f} deg, the filters\' '
            f'{b["filters"]:.0f} deg')
