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
The live estimate as fixed-layout float64 arrays: what /frf/live/* carry (docs/live.md).

Each frame becomes one ``std_msgs/msg/Float64MultiArray``: ``layout.dim`` names the axes
(labels below), ``data`` holds the values row-major, float64 (the exact estimate: a replayed
bag gives it to 1e-12). Every channel's quantity occupies :data:`LINE_SLOTS` slots
(:data:`DETECTION_SLOTS` in the distortion frame), the lines first and NaN after them, so a
viewer addresses a series by a fixed slice whatever the design:
channel c, quantity q is ``data[(c * n_q + q) * LINE_SLOTS : ... + LINE_SLOTS]`` (Foxglove:
``/frf/live/frf.data[a:b]`` with b = a + LINE_SLOTS - 1, its slices include the end).

- /frf/live/frf: dims ``channel`` (label ``channel <out><-<in> ...``), ``quantity`` (label
  ``quantity`` + :data:`FRF_QUANTITIES`), ``line``.
- /frf/live/distortion: dims ``output`` (label ``output <name> ...``), ``quantity``
  (:data:`DISTORTION_QUANTITIES`; kind 1 excited, 2 odd non-excited, 3 even), ``line``.
- /frf/live/summary: one dim ``field`` (label ``field`` + :data:`SUMMARY_FIELDS`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ['ArrayFrame', 'decode_frf', 'DETECTION_SLOTS', 'DISTORTION_QUANTITIES',
           'distortion_frame', 'FRF_QUANTITIES', 'frf_frame', 'LINE_SLOTS', 'SUMMARY_FIELDS',
           'summary_frame']

#: slots per channel and quantity of /frf/live/frf: a design's lines beyond them are left out
#: of the live view (logged once; the estimate at the end has all). The 2-60 Hz designs have
#: 39 (1 Hz resolution) to 76 (the paper's 0.1 Hz) excited lines. Every slot is sent with each
#: estimate: 1024 slots made a 3-axis frame 590 kB (2.4 MB for 6 axes), 93 % NaN, and the graph
#: lost 13 % of its steps/s with the live stream on (docs/BENCHMARKS.md, live_graph); 128 make
#: it 74 kB
LINE_SLOTS = 128
#: slots per output and quantity of /frf/live/distortion: its detection lines are every DFT
#: line up to the band's top (737 at 0.1 Hz)
DETECTION_SLOTS = 1024
#: per channel and line; the band is magnitude -/+ 2 sd, for a viewer that cannot add arrays
FRF_QUANTITIES = ('freq_hz', 'magnitude_db', 'phase_deg', 'magnitude_sd_db', 'phase_sd_deg',
                  'coherence', 'band_low_db', 'band_high_db')
DISTORTION_QUANTITIES = ('freq_hz', 'level_db', 'noise_db', 'kind')
SUMMARY_FIELDS = ('t_s', 'periods', 'realisations', 'worst_sd_db', 'target_sd_db',
                  'periods_left', 'final', 'min_coherence')
KINDS = {'excited': 1.0, 'odd': 2.0, 'even': 3.0}


@dataclass
class ArrayFrame:
    """
    A Float64MultiArray's content: dims (label, size, stride) and the flat data.

    Parameters
    ----------
    dims : list of (str, int, int)
        Label, size and stride of each dimension, outermost first.
    data : ndarray, shape (N,)
        The values, float64.

    """

    dims: list[tuple[str, int, int]]
    data: np.ndarray


def _slots(rows: np.ndarray, slots: int) -> np.ndarray:
    out = np.full(rows.shape[:-1] + (slots,), np.nan)
    n = min(rows.shape[-1], slots)
    out[..., :n] = rows[..., :n]
    return out


def _dims(labels: list[str], shape: tuple[int, ...]) -> list[tuple[str, int, int]]:
    strides = np.cumprod((shape[1:] + (1,))[::-1])[::-1]
    return [(lab, int(n), int(s * n)) for lab, n, s in zip(labels, shape, strides)]


def frf_frame(freq_hz: np.ndarray, response: np.ndarray, sd_db: np.ndarray,
              phase_sd_deg: np.ndarray, coherence: np.ndarray, outputs: list[str],
              inputs: list[str]) -> ArrayFrame:
    """
    Encode an FRF estimate (n_out, n_in, F) with its uncertainty and coherence.

    Parameters
    ----------
    freq_hz : ndarray, shape (F,)
        Frequency of each line [Hz].
    response : ndarray, shape (n_out, n_in, F)
        The complex FRF.
    sd_db, phase_sd_deg : ndarray, shape (n_out, n_in, F)
        1-sigma magnitude [dB] and phase [deg] uncertainty (nan where undefined).
    coherence : ndarray, shape (n_out, F)
        Multiple coherence per output (the same for each of its channels).
    outputs, inputs : list of str
        Channel names.

    Returns
    -------
    ArrayFrame

    """
    n_out, n_in, F = response.shape
    mag = 20 * np.log10(np.maximum(np.abs(response), 1e-300))
    phase = np.degrees(np.unwrap(np.angle(response), axis=-1))
    q = np.stack([np.broadcast_to(freq_hz, response.shape), mag, phase, sd_db, phase_sd_deg,
                  np.broadcast_to(coherence[:, None, :], response.shape),
                  mag - 2 * sd_db, mag + 2 * sd_db], axis=2)       # (n_out, n_in, Q, F)
    data = _slots(q.reshape(n_out * n_in, len(FRF_QUANTITIES), F), LINE_SLOTS)
    names = ' '.join(f'{o}<-{i}' for o in outputs for i in inputs)
    return ArrayFrame(_dims([f'channel {names}', 'quantity ' + ' '.join(FRF_QUANTITIES),
                             'line'], data.shape), data.ravel())


def decode_frf(dims: list[tuple[str, int, int]], data: np.ndarray) -> dict[str, Any]:
    """
    Decode a /frf/live/frf frame (the inverse of :func:`frf_frame`, for tests and tools).

    Parameters
    ----------
    dims : list of (str, int, int)
        The layout's (label, size, stride).
    data : ndarray
        The flat data.

    Returns
    -------
    dict
        ``channels`` (list of str) and every quantity as an (n_channels, n_lines) array
        without the NaN slots.

    """
    n_ch, n_q, slots = (d[1] for d in dims)
    a = np.asarray(data, float).reshape(n_ch, n_q, slots)
    n = int(np.sum(np.isfinite(a[0, 0])))
    out: dict[str, Any] = {'channels': dims[0][0].split()[1:]}
    for k, name in enumerate(dims[1][0].split()[1:]):
        out[name] = a[:, k, :n]
    return out


def distortion_frame(d: dict[str, Any]) -> ArrayFrame:
    """
    Encode the per-line detection levels (``DistortionLines.to_dict()``).

    Parameters
    ----------
    d : dict
        ``freq_hz``, ``kind``, ``power`` (n_out, lines), ``noise`` (or None), ``outputs``.

    Returns
    -------
    ArrayFrame

    """
    power = np.asarray(d['power'], float)
    n_out, n = power.shape
    noise = (np.full_like(power, np.nan) if d.get('noise') is None
             else np.asarray(d['noise'], float))
    kind = np.array([KINDS.get(k, np.nan) for k in d['kind']])
    q = np.stack([np.broadcast_to(np.asarray(d['freq_hz'], float), power.shape),
                  10 * np.log10(np.maximum(power, 1e-300)),
                  10 * np.log10(np.maximum(noise, 1e-300)),
                  np.broadcast_to(kind, power.shape)], axis=1)
    data = _slots(q, DETECTION_SLOTS)
    return ArrayFrame(_dims(['output ' + ' '.join(d['outputs']),
                             'quantity ' + ' '.join(DISTORTION_QUANTITIES), 'line'],
                            data.shape), data.ravel())


def summary_frame(values: dict[str, float]) -> ArrayFrame:
    """
    Encode the summary fields (:data:`SUMMARY_FIELDS`; a missing one is NaN).

    Parameters
    ----------
    values : dict of str to float
        Field name -> value (None or missing: NaN).

    Returns
    -------
    ArrayFrame

    """
    data = np.array([float(values.get(k, np.nan)) if values.get(k) is not None else np.nan
                     for k in SUMMARY_FIELDS])
    return ArrayFrame([('field ' + ' '.join(SUMMARY_FIELDS), data.size, data.size)], data)
