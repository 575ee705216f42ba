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
Detect the excitation in a measured signal: periodic multisine or exponential chirp.

For data recorded by other tools (a robot's own bag, a CSV/MAT import) the experiment
descriptors of ``/frf/experiment`` are missing; these detectors recover the design from the
signal itself (pure numpy/scipy, no bag or ROS imports). This module holds
:func:`detect_excitation`, which tries both and returns whichever was found; the pieces live
in a module each:

- :mod:`frf_ident.core.excitation.multisine_detect` — :func:`detect_multisine` (period, block
  of whole periods, excited lines; Saupe & Knoblach 2015, Sec. 4), ``multisine_at_period``,
  ``period_drift``; the block of whole periods in
  :mod:`frf_ident.core.excitation.periodic_block`.
- :mod:`frf_ident.core.excitation.chirp_detect` — :func:`detect_chirp` (eq. 16 from zero
  crossings and a robust log-linear fit; band and active interval from an on-/offset fit).
- :mod:`frf_ident.core.excitation.detection_results` — :class:`MultisineDetection`,
  :class:`ChirpDetection`.
- :mod:`frf_ident.core.excitation.detect_input` — ``excitation_source`` (the commanded
  velocity reference when there is one, else the torque) and the input checks.

Signals are ``(N,)`` arrays sampled uniformly at ``fs``; ``(N, n)`` arrays are reduced to the
channel with the largest RMS. NaN marks missing samples (gaps in a recording): they are
bridged linearly for the search and never count against the periodicity of the data around
them.

``detect_multisine``, ``detect_chirp``, ``MultisineDetection`` and ``ChirpDetection`` stay
importable from here: docs/import_maps.md names them by this module's path.
"""
from __future__ import annotations

from typing import Any

from frf_ident.core.excitation.chirp_detect import detect_chirp
from frf_ident.core.excitation.detection_results import ChirpDetection, MultisineDetection
from frf_ident.core.excitation.multisine_detect import detect_multisine
from frf_ident.errors import EstimationError
import numpy as np

__all__ = ['ChirpDetection', 'MultisineDetection', 'detect_chirp', 'detect_excitation',
           'detect_multisine']


def detect_excitation(x: np.ndarray, fs: float, **kwargs: Any
                      ) -> MultisineDetection | ChirpDetection:
    """
    Detect a periodic multisine, else an exponential chirp, in ``x`` sampled at ``fs``.

    The result's ``kind`` ('multisine' or 'chirp') says which was found and ``describe()``
    says what. ``kwargs`` may hold ``min_periods`` for the multisine detector. Raises
    :class:`EstimationError` with one line giving both reasons if neither is found.

    Parameters
    ----------
    x : ndarray, shape (N,) or (N, n)
        The signal; of a 2-D signal the channel with the largest RMS is analysed. NaN marks
        missing samples.
    fs : float
        Sample rate [Hz].
    **kwargs
        ``min_periods`` (int, default 2) for :func:`detect_multisine`; other keys are ignored.

    Returns
    -------
    MultisineDetection or ChirpDetection
        The multisine if one is found, else the chirp.

    """
    try:
        return detect_multisine(x, fs, min_periods=kwargs.get('min_periods', 2))
    except EstimationError as exc:
        why_ms = str(exc)
    try:
        return detect_chirp(x, fs)
    except EstimationError as exc:
        why_chirp = str(exc)
    n = np.asarray(x).shape[0] if np.ndim(x) else 0
    raise EstimationError(f'no multisine or exponential chirp found in {n} samples at '
                          f'{fs=:g} Hz: {why_ms}; {why_chirp}')
