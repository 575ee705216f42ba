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
The signal an excitation is detected on, readied for the detectors.

- :func:`excitation_source` — which signal of a recording carries the excitation (the
  commanded velocity reference when there is one, else the torque); the estimators and the
  importer both use it.
- :func:`prepare_signal` — validate, pick the strongest channel of a ``(N, n)`` array (all
  channels of a MIMO experiment share the design), bridge NaN gaps linearly, remove the median.

``MIN_FINITE`` is the share of finite samples a signal needs for either.
"""
from __future__ import annotations

from frf_ident.errors import EstimationError
import numpy as np

__all__ = ['MIN_FINITE', 'excitation_source', 'prepare_signal']


#: share of finite samples a signal needs: a reference that is commanded less often than
#: this is not the excitation source, and detection refuses sparser signals
MIN_FINITE = 0.5


def excitation_source(reference: np.ndarray | None, effort: np.ndarray
                      ) -> tuple[np.ndarray, str]:
    """
    Return the signal to detect the excitation on and its name.

    The velocity reference r when it was commanded (finite in at least ``MIN_FINITE`` of the
    samples; NaN where no command was held, e.g. before the first one or in a gap) and moves
    on some joint, else the torque u (the plant input, which carries the excitation too).

    Parameters
    ----------
    reference
        (N, n) velocity reference or None.
    effort
        (N, n) motor torque.

    Returns
    -------
    tuple
        ((N, n) array, 'velocity reference' | 'torque').

    """
    if reference is not None:
        r = np.asarray(reference, dtype=float)
        finite = np.isfinite(r)
        if r.size and np.mean(finite) >= MIN_FINITE:
            spread = [np.std(r[finite[:, j], j]) if np.any(finite[:, j]) else 0.0
                      for j in range(r.shape[1])]
            if max(spread, default=0.0) > 0:
                return r, 'velocity reference'
    return np.asarray(effort, dtype=float), 'torque'


def _bridge(x: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """``x`` with the invalid samples linearly interpolated (held at the ends)."""
    if np.all(valid):
        return x
    idx = np.arange(x.size)
    return np.interp(idx, idx[valid], x[valid])


def prepare_signal(x: np.ndarray, fs: float, min_samples: int = 16
                   ) -> tuple[np.ndarray, int, np.ndarray]:
    """
    Validate, pick the strongest channel, bridge NaN gaps, remove the median.

    Returns (x, channel, valid): ``valid`` marks the samples that were finite.
    """
    if not (np.isfinite(fs) and fs > 0):
        raise EstimationError(f'{fs=} must be a positive sample rate in Hz')
    x = np.asarray(x, dtype=float)
    if x.ndim not in (1, 2):
        raise EstimationError(f'signal must be (N,) or (N, n_channels), got {x.shape=}')
    if x.shape[0] < min_samples:
        raise EstimationError(f'signal has {x.shape[0]} samples; need at least {min_samples}')
    if np.any(np.isinf(x)):
        raise EstimationError(f'signal has {int(np.sum(np.isinf(x)))} infinite samples')
    channel = 0
    if x.ndim == 2:
        centred = x - np.nanmedian(x, axis=0) if np.any(np.isfinite(x)) else x
        with np.errstate(invalid='ignore'):
            rms = np.array([np.sqrt(np.mean(c[np.isfinite(c)] ** 2)) if np.any(np.isfinite(c))
                            else 0.0 for c in centred.T])
        channel = int(np.argmax(rms))
        x = x[:, channel]
    valid = np.isfinite(x)
    if np.mean(valid) < MIN_FINITE:
        raise EstimationError(f'signal has {int(np.sum(~valid))} non-finite (missing) of {x.size} '
                              f'samples; expected at least {100 * MIN_FINITE:.0f} % present')
    x = _bridge(x, valid)
    return x - np.median(x), channel, valid
