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
Tell a line above the analysis band locked to position from one locked to time.

A drives engineer's first question about a line in the torque residual: does it move with
speed? A line locked to position (cogging, ripple, gear mesh, a screw's pitch) sits at
f = kappa |v|, kappa cycles per unit of travel; a line locked to time (the mains, PWM, a
structural mode) stays at its frequency. The evidence is the record's own steady speeds
(:func:`steady_speeds`: stretches where the speed holds within LINE_STEADY_SHARE for at least
LINE_MIN_RUN_S). The line's frequency f0 is read at the speed v* where it stands highest;
at every other steady speed v the residual's spectrum is read at the two frequencies the
hypotheses predict, kappa v = f0 v / v* (position) and f0 (time), against the chi-square
threshold of that speed's Welch average (:func:`..timeseries.resonance.peak_threshold`,
false-alarm LINE_LOCK_FALSE_ALARM). A speed where only one of them carries a line votes for
it; the line is locked to position (time) when some speed votes so and none the other way,
else not determined (both frequencies carry lines at every other speed, as on EMPS, whose
two steady speeds are 2 : 3, where a ripple's harmonics land on each other; or the record
holds a single steady speed). Every frequency within a line of a mains multiple is labelled
(:func:`..line_cause.mains_multiple`), whatever locks it.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy import signal
from scipy.ndimage import median_filter

from .resonance import peak_threshold
from ..line_cause import LineAtSpeed, LineCause, mains_multiple
from ..records import Unexplained
from ..residual import lowpass
from ..thresholds import (LINE_LOCK_FALSE_ALARM, LINE_LOCK_MIN_SHIFT_LINES, LINE_MIN_RUN_S,
                          LINE_SPEED_HZ, LINE_STEADY_SHARE, RESONANCE_FLOOR_LINES,
                          RESONANCE_SEGMENT_S, REST_SHARE)

__all__ = ['classify_lines', 'line_cause', 'SpeedSpectrum', 'steady_speeds']


@dataclass(frozen=True)
class SpeedSpectrum:
    """The residual's spectrum over the stretches of one steady speed."""

    speed: float
    duration_s: float
    f: np.ndarray
    #: PSD over its running median (RESONANCE_FLOOR_LINES lines)
    ratio: np.ndarray
    threshold: float

    def at(self, f_hz: float) -> float:
        """Return the largest PSD over floor of the three lines around ``f_hz`` (0 outside)."""
        df = self.f[1] - self.f[0]
        k = int(round(f_hz / df))
        if k < 1 or k >= self.f.size - 1:
            return 0.0
        return float(self.ratio[k - 1:k + 2].max())

    def peak_near(self, f_hz: float) -> float:
        """Return the frequency of the highest of the three lines around ``f_hz`` [Hz]."""
        df = self.f[1] - self.f[0]
        k = int(round(f_hz / df))
        if k < 1 or k >= self.f.size - 1:
            return f_hz
        return float(self.f[k - 1 + int(np.argmax(self.ratio[k - 1:k + 2]))])

    @property
    def line_hz(self) -> float:
        """Return the spacing of its lines [Hz]."""
        return float(self.f[1] - self.f[0])


def steady_speeds(v: np.ndarray, fs: float) -> list[tuple[float, list[tuple[int, int]]]]:
    """
    Return the record's steady speeds: (speed, [(start, stop) sample ranges]).

    Parameters
    ----------
    v : ndarray, shape (N,)
        One axis' velocity.
    fs : float
        Sample rate [Hz].

    Returns
    -------
    list of (float, list of (int, int))
        Per steady speed (slowest first) its mean |v| and its stretches; stretches whose
        speeds agree within LINE_STEADY_SHARE are one speed. Rest is none.

    """
    s = np.abs(lowpass(np.asarray(v, float), fs, LINE_SPEED_HZ))
    step = max(int(fs / (20 * LINE_SPEED_HZ)), 1)      # the low-passed speed, decimated
    d = s[::step]
    least = REST_SHARE * float(np.percentile(s, 95)) if s.size else 0.0
    min_len = int(np.ceil(LINE_MIN_RUN_S * fs / step))
    runs = []
    k = 0
    while k < d.size:
        ref = d[k]
        j = k
        while j < d.size and abs(d[j] - ref) <= LINE_STEADY_SHARE * ref:
            j += 1
        if j - k >= min_len and ref > least:
            runs.append((k * step, min(j * step, s.size), float(s[k * step:j * step].mean())))
            k = j
        else:
            k += 1
    groups: list[tuple[float, list[tuple[int, int]]]] = []
    for a, b, sp in sorted(runs, key=lambda r: r[2]):
        if groups and abs(sp / groups[-1][0] - 1) <= LINE_STEADY_SHARE:
            groups[-1][1].append((a, b))
        else:
            groups.append((sp, [(a, b)]))
    return [(float(np.mean([s[a:b].mean() for a, b in rs])), rs) for _, rs in groups]


def speed_spectrum(x: np.ndarray, speed: float, runs: list[tuple[int, int]], fs: float
                   ) -> SpeedSpectrum:
    """Return the Welch spectrum (Hann, half overlap within each stretch) over ``runs``."""
    nper = min(int(round(RESONANCE_SEGMENT_S * fs)), min(b - a for a, b in runs))
    win = signal.get_window('hann', nper)
    acc = np.zeros(nper // 2 + 1)
    count = 0
    for a, b in runs:
        for k in range(a, b - nper + 1, max(nper // 2, 1)):
            seg = x[k:k + nper] - x[k:k + nper].mean()
            acc += np.abs(np.fft.rfft(win * seg)) ** 2
            count += 1
    p = acc / max(count, 1)
    floor = median_filter(p, size=RESONANCE_FLOOR_LINES, mode='nearest')
    return SpeedSpectrum(speed, sum(b - a for a, b in runs) / fs, np.fft.rfftfreq(nper, 1 / fs),
                         p / np.maximum(floor, 1e-300),
                         peak_threshold(count, 3, LINE_LOCK_FALSE_ALARM))


def line_cause(f0: float, spectra: list[SpeedSpectrum]) -> LineCause:
    """
    Return what locks the line at ``f0`` [Hz], from the spectra at the record's steady speeds.

    Parameters
    ----------
    f0 : float
        The line's frequency (the whole record's peak) [Hz].
    spectra : list of SpeedSpectrum
        The residual at each steady speed (:func:`speed_spectrum`).

    Returns
    -------
    LineCause

    """
    tol = max([s.line_hz for s in spectra] + [1.0])
    mains = mains_multiple(f0, tol)
    if not spectra:
        return LineCause('undetermined', f0, 'the record holds no steady speed for '
                         f'{LINE_MIN_RUN_S:g} s', mains_multiple=mains)
    best = max(spectra, key=lambda s: s.at(f0) / s.threshold)
    kappa = best.peak_near(f0) / best.speed
    speeds = [LineAtSpeed(s.speed, s.duration_s, kappa * s.speed, s.at(kappa * s.speed),
                          s.at(f0), s.threshold) for s in spectra]
    if best.at(f0) <= best.threshold:
        return LineCause('undetermined', f0, 'not above the noise at any steady speed',
                         mains_multiple=mains, speeds=speeds)
    votes = {'position': [], 'time': [], 'both': []}
    for s, e in zip(spectra, speeds):
        if s is best or abs(e.position_hz - f0) < LINE_LOCK_MIN_SHIFT_LINES * s.line_hz:
            continue
        pos, tim = e.position_over_floor > s.threshold, e.time_over_floor > s.threshold
        if pos or tim:
            votes['both' if pos and tim else 'position' if pos else 'time'].append(e)
    here = f'{f0:.3g} Hz at speed {best.speed:.3g}'
    if votes['position'] and not votes['time']:
        moved = ', '.join(f'{e.position_hz:.3g} Hz at speed {e.speed:.3g} (not at {f0:.3g} Hz)'
                          for e in votes['position'])
        return LineCause('position', f0, f'{here}, {moved}: {kappa:.4g} cycles per unit of '
                         'travel', cycles_per_unit=kappa, mains_multiple=mains, speeds=speeds)
    if votes['time'] and not votes['position']:
        stays = ', '.join(f'speed {e.speed:.3g} (nothing at {e.position_hz:.3g} Hz)'
                          for e in votes['time'])
        return LineCause('time', f0, f'{here} and at {stays}', mains_multiple=mains,
                         speeds=speeds)
    if votes['both'] and not (votes['position'] or votes['time']):
        why = (f'{here}; at every other steady speed both {f0:.3g} Hz and where a '
               'position-locked line would be carry lines (a harmonic of another line may land '
               'on either)')
    elif votes['position']:
        why = f'{here}; the other steady speeds disagree'
    else:
        why = f'{here}; no other steady speed where the two would differ shows it'
    return LineCause('undetermined', f0, why, mains_multiple=mains, speeds=speeds)


def classify_lines(entries: list[Unexplained], residual: np.ndarray, v: np.ndarray,
                   fs: float, names: list[str]) -> list[Unexplained]:
    """
    Return the peaks above the analysis band with their :class:`..line_cause.LineCause`.

    Parameters
    ----------
    entries : list of Unexplained
        The peaks (:func:`.resonance.resonances_above`); other entries pass unchanged.
    residual : ndarray, shape (N, n)
        The extended model's residual the peaks were found in (not low-passed).
    v : ndarray, shape (N, n)
        The axes' velocities on the same rows.
    fs : float
        Sample rate [Hz].
    names : list of str
        The axes' names.

    Returns
    -------
    list of Unexplained

    """
    spectra: dict[str, list[SpeedSpectrum]] = {}
    out = []
    for u in entries:
        if u.signature.peak_hz is None or u.axis not in names:
            out.append(u)
            continue
        if u.axis not in spectra:
            i = names.index(u.axis)
            x = np.nan_to_num(np.asarray(residual[:, i], float))
            spectra[u.axis] = [speed_spectrum(x, sp, runs, fs)
                               for sp, runs in steady_speeds(v[:, i], fs)
                               if min(b - a for a, b in runs) >= 16]
        out.append(replace(u, cause=line_cause(float(u.signature.peak_hz), spectra[u.axis])))
    return out
