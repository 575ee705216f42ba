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
Records taken at different excitation levels side by side.

A linear system gives the same FRF at every level; a nonlinear one does not: its modes move
(a hardening spring stiffens with amplitude) and its distortion grows faster than the
excitation. :func:`compare_levels` lines up estimates of the same channels: the FRF change
per line against the first record, the mode frequencies (peaks of |P|) and their shift, and
the odd / even distortion over the noise per record.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

from frf_ident.core.estimation.distortion import DistortionLines
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.errors import EstimationError
import numpy as np
from scipy import signal

__all__ = ['MODE_PROMINENCE_DB', 'LevelComparison', 'compare_levels', 'mode_frequencies']

#: a peak of |P| is a mode when it stands this far [dB] above the valleys around it: 6 dB
#: passes the resonances of lightly damped drives (10-40 dB) and not the scatter of noisy
#: lines (a line at 40 dB SNR scatters by about 0.1 dB)
MODE_PROMINENCE_DB = 6.0


def mode_frequencies(freq_hz: np.ndarray, response: np.ndarray,
                     prominence_db: float = MODE_PROMINENCE_DB) -> np.ndarray:
    """
    Frequencies of the resonance peaks of one FRF channel.

    Parameters
    ----------
    freq_hz : ndarray
        Line frequencies [Hz], ascending.
    response : ndarray of complex
        The channel's FRF at those lines.
    prominence_db : float, optional
        How far a peak must stand above its surroundings [dB].

    Returns
    -------
    ndarray
        Peak frequencies [Hz], refined by a parabola through the peak line and its
        neighbours (in dB over the line index).

    """
    mag = 20 * np.log10(np.maximum(np.abs(response), 1e-300))
    peaks, _ = signal.find_peaks(mag, prominence=prominence_db)
    out = []
    for k in peaks:
        a, b, c = mag[k - 1], mag[k], mag[k + 1]
        d = 0.5 * (a - c) / (a - 2 * b + c) if (a - 2 * b + c) != 0 else 0.0
        step = freq_hz[k + 1] - freq_hz[k] if d > 0 else freq_hz[k] - freq_hz[k - 1]
        out.append(freq_hz[k] + d * step)
    return np.asarray(out, float)


@dataclass
class LevelComparison:
    """
    Estimates of records at different levels, compared with the first.

    Parameters
    ----------
    names : list of str
        The records, in the given order (the first is the reference).
    freq_hz : ndarray
        Lines all records share [Hz].
    change_db : ndarray, shape (n_records, n_out, n_lines)
        20 log10 |P_k / P_0| per line (0 for the first record).
    outputs, inputs : list of str
        Channels (the input is the first of each estimate).
    modes_hz : list of list of ndarray
        Mode frequencies per record and output.
    distortion : list of dict
        Per record: {'odd', 'even'} median dB over the noise per output (nan when unknown).
    responses : list of ndarray
        Each record's FRF at the shared lines, (n_out, n_lines).

    """

    names: list[str]
    freq_hz: np.ndarray
    change_db: np.ndarray
    outputs: list[str]
    inputs: list[str]
    modes_hz: list[list[np.ndarray]]
    distortion: list[dict[str, list[float]]] = field(default_factory=list)
    responses: list[np.ndarray] = field(default_factory=list)

    def mode_shifts(self) -> list[list[list[tuple[float, float]]]]:
        """
        Each mode of the first record and where the nearest mode of each record lies.

        Returns
        -------
        list
            [record][output] -> list of (f_first, f_record) [Hz]; f_record nan where the
            record has no mode.

        """
        out = []
        for modes in self.modes_hz:
            per_out = []
            for o, ref in enumerate(self.modes_hz[0]):
                cand = modes[o]
                per_out.append([(float(f), float(cand[np.argmin(np.abs(cand - f))])
                                 if cand.size else float('nan')) for f in ref])
            out.append(per_out)
        return out

    def summary(self) -> list[str]:
        """
        One line per record and output: FRF change, mode shift, distortion.

        Returns
        -------
        list of str
            e.g. 'rec_b dq_m/j: |P| change median -0.8 dB, max -6.1 dB at 73.2 Hz; modes
            72.9 -> 75.1 Hz (+3.0 %); odd +18.0 dB, even +0.2 dB above noise'.

        """
        lines = []
        shifts = self.mode_shifts()
        for k, name in enumerate(self.names):
            for o, out in enumerate(self.outputs):
                c = self.change_db[k, o]
                i = int(np.argmax(np.abs(c)))
                modes = ', '.join(f'{a:.4g} -> {b:.4g} Hz ({100 * (b / a - 1):+.1f} %)'
                                  for a, b in shifts[k][o]) or 'none'
                d = self.distortion[k] if k < len(self.distortion) else {}
                odd, even = (d.get(x, [np.nan] * len(self.outputs))[o] for x in ('odd', 'even'))
                lines.append(f'{name} {out}: |P| change median {np.median(c):+.2f} dB, largest '
                             f'{c[i]:+.2f} dB at {self.freq_hz[i]:.4g} Hz; modes {modes}; '
                             f'distortion odd {odd:+.1f} dB, even {even:+.1f} dB above noise')
        return lines

    def to_dict(self) -> dict[str, Any]:
        """
        JSON-ready comparison.

        Returns
        -------
        dict
            names, freq_hz, change_db, outputs, inputs, modes_hz, mode_shifts, distortion.

        """
        return {'names': self.names, 'freq_hz': self.freq_hz.tolist(),
                'change_db': self.change_db.tolist(), 'outputs': self.outputs,
                'inputs': self.inputs,
                'modes_hz': [[m.tolist() for m in r] for r in self.modes_hz],
                'mode_shifts': self.mode_shifts(), 'distortion': self.distortion}


def compare_levels(estimates: Sequence[FrequencyResponse], names: Sequence[str]
                   ) -> LevelComparison:
    """
    Compare estimates of the same channels from records at different levels.

    Parameters
    ----------
    estimates : sequence of FrequencyResponse
        One estimate per record, same outputs; the first input column of each is compared.
    names : sequence of str
        A name per record.

    Returns
    -------
    LevelComparison
        FRF change per shared line, modes and distortion per record.

    Raises
    ------
    EstimationError
        Fewer than two estimates, different outputs, or no line in common.

    """
    if len(estimates) < 2:
        raise EstimationError(f'{len(estimates)} record(s); comparing levels needs two or more')
    first = estimates[0]
    for est, name in zip(estimates[1:], names[1:]):
        if list(est.outputs) != list(first.outputs):
            raise EstimationError(f'{name}: outputs {est.outputs}; expected those of '
                                  f'{names[0]}: {first.outputs}')
    keys = [np.round(e.freq_hz, 6) for e in estimates]
    common = keys[0]
    for k in keys[1:]:
        common = np.intersect1d(common, k)
    if common.size == 0:
        raise EstimationError(f'the records {list(names)} share no frequency line; expected '
                              f'the same excitation at different levels')
    resp = [e.response[:, 0, np.searchsorted(k, common)] for e, k in zip(estimates, keys)]
    change = np.array([20 * np.log10(np.abs(r / resp[0])) for r in resp])
    modes = [[mode_frequencies(common, r[o]) for o in range(r.shape[0])] for r in resp]
    dist = []
    for e in estimates:
        d = e.meta.get('distortion')
        if isinstance(d, dict):
            lv = DistortionLines.from_dict(d)
            dist.append({'odd': lv.above_noise_db('odd').tolist(),
                         'even': lv.above_noise_db('even').tolist()})
        else:
            dist.append({})
    return LevelComparison(list(names), common, change, list(first.outputs),
                           [e.inputs[0] for e in estimates], modes, dist, resp)
