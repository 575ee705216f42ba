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
Early warnings while a multisine run goes on; none of them stops it (the safety limits do).

- ``low_coherence``: an output whose median signal-to-noise ratio over the excited lines
  (gamma^2 / (1 - gamma^2) of its multiple coherence with the references) is
  :data:`FAR_BELOW_DB` below the median of all outputs: a dead or very noisy sensor channel.
- ``low_excitation``: the same for a plant input (the torque's coherence with the
  references): an axis the excitation hardly reaches (a drive in torque limit, a wrong gain).
- ``rising_distortion``: a non-excited detection line whose level rose over each of the last
  :data:`RISE_UPDATES` estimates by :data:`RISE_DB` in all, standing :data:`ABOVE_NOISE_DB`
  above the noise: averaging lowers noise there, so a rising line is a drifting plant (heat,
  wear, a resonance building up).
- ``near_torque_limit``: an axis whose measured torque reached :data:`NEAR_LIMIT` of its
  limit (the run aborts at 0.995, frf_ident/app/excitation_settings.py ``SATURATION``).

Each (kind, channel) is reported once per run.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from frf_ident.core.estimation.live import LiveEstimate
import numpy as np

__all__ = ['ABOVE_NOISE_DB', 'EarlyWarning', 'FAR_BELOW_DB', 'NEAR_LIMIT', 'RISE_DB',
           'RISE_UPDATES', 'WarningMonitor']

#: a channel this far below the median channel's SNR [dB] is reported. On the simulated
#: 3-axis robot with 40 dB SNR output noise the outputs' median SNRs lie within 12 dB of one
#: another (test/core/estimation/test_early_warnings.py measures it); a channel without
#: signal sits 40 dB and more below
FAR_BELOW_DB = 20.0
#: estimates over which a detection line must rise each time
RISE_UPDATES = 3
#: the rise over those estimates [dB]
RISE_DB = 3.0
#: the line must stand this far above its noise level [dB] (|Y|^2 of noise alone reaches
#: 6 dB above its mean in 2 % of lines)
ABOVE_NOISE_DB = 6.0
#: share of the torque limit a measured torque may reach before a warning
NEAR_LIMIT = 0.9


@dataclass(frozen=True)
class EarlyWarning:
    """
    One warning: what, where, the value and the threshold it crossed.

    Parameters
    ----------
    kind : str
        'low_coherence', 'low_excitation', 'rising_distortion' or 'near_torque_limit'.
    channel : str
        The output, input or axis.
    message : str
        One line for a person.
    value, threshold : float
        The measured value and the limit it crossed (units in the message).
    t : float
        Time [s] of the data that raised it.

    """

    kind: str
    channel: str
    message: str
    value: float
    threshold: float
    t: float

    def to_dict(self) -> dict[str, Any]:
        """Return the warning as a JSON-ready dict."""
        return asdict(self)


def _snr_db(coh: np.ndarray) -> np.ndarray:
    """Median over lines of gamma^2 / (1 - gamma^2) [dB], per channel (nan when undefined)."""
    c = np.clip(np.asarray(coh, float), 0.0, 1.0 - 1e-12)
    with np.errstate(invalid='ignore'):
        return np.median(10 * np.log10(np.maximum(c / (1 - c), 1e-30)), axis=1)


class WarningMonitor:
    """
    Judge every live estimate and the measured torque; return the new warnings.

    Parameters
    ----------
    axes : list of str
        Joint names (torque warnings).
    torque_limit : ndarray, shape (n,)
        Torque limit per axis [N m].

    """

    def __init__(self, axes: list[str], torque_limit: np.ndarray) -> None:
        self.axes = list(axes)
        self.limit = np.asarray(torque_limit, float)
        self.seen: set[tuple[str, str]] = set()
        self.history: list[np.ndarray] = []      # detection-line levels per estimate

    def _new(self, w: EarlyWarning) -> list[EarlyWarning]:
        key = (w.kind, w.channel)
        if key in self.seen:
            return []
        self.seen.add(key)
        return [w]

    def torque(self, peak: np.ndarray, t: float) -> list[EarlyWarning]:
        """
        Judge the peak measured torque of the newest samples.

        Parameters
        ----------
        peak : ndarray, shape (n,)
            Largest |torque| per axis [N m].
        t : float
            Time [s].

        Returns
        -------
        list of EarlyWarning

        """
        out = []
        for i in np.flatnonzero(np.abs(peak) >= NEAR_LIMIT * self.limit):
            out += self._new(EarlyWarning(
                'near_torque_limit', self.axes[i],
                f'{self.axes[i]}: measured torque {abs(peak[i]):.1f} N m is '
                f'{abs(peak[i]) / self.limit[i]:.0%} of its limit {self.limit[i]:g} N m '
                f'(the run aborts at 99.5 %)', float(abs(peak[i])),
                float(NEAR_LIMIT * self.limit[i]), t))
        return out

    def estimate(self, est: LiveEstimate) -> list[EarlyWarning]:
        """
        Judge a live estimate: coherence, excitation level, distortion trend.

        Parameters
        ----------
        est : LiveEstimate
            The newest estimate.

        Returns
        -------
        list of EarlyWarning
            The warnings not reported before in this run.

        """
        out = []
        for kind, coh, names, what in (
                ('low_coherence', est.coherence, est.frf.outputs, 'output'),
                ('low_excitation', est.input_coherence, est.frf.inputs, 'plant input')):
            snr = _snr_db(coh)
            if not np.all(np.isfinite(snr)) or snr.size < 2:
                continue
            ref = float(np.median(snr))
            for i in np.flatnonzero(snr < ref - FAR_BELOW_DB):
                out += self._new(EarlyWarning(
                    kind, names[i], f'{what} {names[i]}: median SNR {snr[i]:.1f} dB over the '
                    f'excited lines, {ref - snr[i]:.0f} dB below the median channel '
                    f'({ref:.1f} dB)', float(snr[i]), ref - FAR_BELOW_DB, est.t))
        return out + self._distortion(est)

    def _distortion(self, est: LiveEstimate) -> list[EarlyWarning]:
        d = est.frf.meta.get('distortion')
        if not d or d.get('noise') is None:
            return []
        kind = np.asarray(d['kind'])
        power = np.asarray(d['power'], float)
        noise = np.asarray(d['noise'], float)
        level = 10 * np.log10(np.maximum(power, 1e-300))
        above = level - 10 * np.log10(np.maximum(noise, 1e-300))
        self.history.append(level)
        if len(self.history) <= RISE_UPDATES:
            return []
        h = np.stack(self.history[-RISE_UPDATES - 1:])          # (updates, n_out, lines)
        rising = (np.all(np.diff(h, axis=0) > 0, axis=0) & (h[-1] - h[0] >= RISE_DB)
                  & (above >= ABOVE_NOISE_DB) & (kind != 'excited')[None, :])
        out = []
        freq = np.asarray(d['freq_hz'], float)
        for o, line in zip(*np.nonzero(rising)):
            name = d['outputs'][o]
            out += self._new(EarlyWarning(
                'rising_distortion', name,
                f'{name}: {kind[line]} line {freq[line]:.2f} Hz rose '
                f'{h[-1, o, line] - h[0, o, line]:.1f} dB over the last {RISE_UPDATES} '
                f'estimates, {above[o, line]:.0f} dB above the noise: the plant drifts '
                f'(heat, wear) or a resonance builds up',
                float(h[-1, o, line] - h[0, o, line]), RISE_DB, est.t))
        return out
