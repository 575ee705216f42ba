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
Recordings without periodic excitation (PRBS, noise, normal motion): the LPM, block by block.

:class:`LpmBlocks` takes the blocks of a recording (in memory or a streamed bag's windows,
:func:`frf_ident.core.estimation.detected.estimate_in_blocks`), cuts them into frames of one
length (:data:`~frf_ident.core.estimation.lpm_frames.DEFAULT_FRAME_SAMPLES`, or the first
block when it is shorter) and adds every frame whose regressor is complete to an
:class:`~frf_ident.core.estimation.lpm_frames.LpmAccumulator` (missing output samples are
estimated with the FRF, :mod:`frf_ident.core.estimation.missing_lpm`). The inputs are the
torques of the joints whose excitation source moves (the velocity reference when the bag has
one, else the torque, as detection chooses), the outputs the velocities of every joint. With
the reference the estimate is the indirect one, P = G_yr G_ur^-1; without it the direct one,
with a warning.
"""
from __future__ import annotations

from typing import Any

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.lpm_frames import (DEFAULT_FRAME_SAMPLES, DIRECT_WARNING,
                                                  EXCITED_FRACTION, LpmAccumulator)
from frf_ident.core.excitation.detect_input import excitation_source
from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError
import numpy as np

__all__ = ['LpmBlocks', 'MIN_LEVEL']

#: a joint whose excitation source has less than this fraction of the strongest joint's rms
#: is not an input (it only follows through coupling); the rule detection applies
MIN_LEVEL = 1e-3


class LpmBlocks:
    """
    LPM estimate of a recording without periodic excitation, gathered block by block.

    Parameters
    ----------
    frame_samples : int
        LPM frame length (resolution fs / frame_samples); a shorter first block sets it.
    input : str, optional
        The only input joint; default: every joint whose excitation source moves.
    band : tuple of float, optional
        (f_low, f_high) [Hz]: only these lines are kept in the result.

    """

    def __init__(self, frame_samples: int = DEFAULT_FRAME_SAMPLES, *,
                 input: str | None = None,  # noqa: A002
                 band: tuple[float, float] | None = None, direct: bool = False) -> None:
        self.frame_samples = int(frame_samples)
        self.direct = direct
        self.input = input
        self.band = band
        self.acc: LpmAccumulator | None = None
        self.inputs: list[int] = []
        self.units: dict[str, Any] = {}
        self.source = ''
        self.layout = False                 # an import layout: inputs and sensors, no robot
        self.dropped = 0
        self.why: dict[str, int] = {}
        self.used_until: float | None = None

    def _drop(self, why: str) -> None:
        """Count a frame dropped for gaps, and why."""
        self.dropped += 1
        self.why[why] = self.why.get(why, 0) + 1

    def _dropped_text(self) -> str:
        """Say how many frames gaps dropped and why ('' for none)."""
        if not self.dropped:
            return ''
        x = 'reference r' if self.source == 'velocity reference' else 'torque u'
        reasons = [f'{k} frame(s): their {x} (the regressor) is missing there; the missing-'
                   f'data LPM estimates missing outputs only' if why == 'regressor'
                   else f'{k} frame(s): {why}' for why, k in self.why.items()]
        return f', {self.dropped} frame(s) dropped for gaps ({"; ".join(reasons)})'

    @property
    def frames(self) -> int:
        """Return the number of frames added so far."""
        return 0 if self.acc is None else self.acc.frames

    def _start(self, rec: Recording, n_rows: int) -> None:
        """Choose inputs and frame length from the first block."""
        x = rec.reference if self.source == 'velocity reference' else rec.effort
        source = self.source
        self.layout = rec.is_layout
        names = rec.joint_names
        if self.input is not None:
            if self.input not in names:
                raise EstimationError(f'input={self.input!r} is not a joint of the recording; '
                                      f'expected one of {names}')
            self.inputs = [names.index(self.input)]
        else:
            level = np.array([np.nanstd(x[:, j]) if np.any(np.isfinite(x[:, j])) else 0.0
                              for j in range(x.shape[1])])
            if not np.any(level > 0):
                raise EstimationError(f'no joint moves: the {source} is constant in every '
                                      f'joint; expected an excited input')
            self.inputs = [j for j in range(len(names)) if level[j] >= MIN_LEVEL * level.max()]
        n = min(n_rows, self.frame_samples)
        outs = [names[k] for k in rec.output_columns()]
        self.acc = LpmAccumulator(rec.fs, n, inputs=[f'tau_m/{names[j]}' for j in self.inputs],
                                  outputs=[f'dq_m/{m}' for m in outs])
        # one input unit where the inputs share it ('' where they differ: no common unit)
        ins = {rec.unit(names[j], 'effort') for j in self.inputs}
        self.units = {'input': ins.pop() if len(ins) == 1 else '',
                      'outputs': [rec.unit(m, 'velocity') for m in outs]}

    def add(self, rec: Recording) -> float | None:
        """
        Add the whole frames of a block; return where the data used end [s], None if none.

        Leading samples without a value in some channel (a reference not yet commanded) are
        skipped; a frame whose outputs miss samples later is estimated with them as unknowns,
        one whose regressor (r, else u) misses one is dropped (counted, with the reason).

        Parameters
        ----------
        rec : Recording
            One block of the recording, in time order after the blocks before.

        Returns
        -------
        float or None
            End time [s] of the last frame used (a next block may start there).

        Raises
        ------
        EstimationError
            No joint moves, or an unknown ``input`` joint.

        """
        y = rec.velocity[:, rec.output_columns()]      # a layout's sensors only
        u = rec.effort
        if self.acc is None:
            self.source = ('torque' if self.direct
                           else excitation_source(rec.reference, rec.effort)[1])
        ref = rec.reference if self.source == 'velocity reference' else None
        cols = [y, u] if ref is None else [y, u, ref]
        ok = np.all(np.concatenate([np.isfinite(c) for c in cols], axis=1), axis=1)
        if not np.any(ok):
            return None
        a = int(np.argmax(ok))
        if self.acc is None:
            self._start(rec, ok.size - a)
        n = self.acc.n
        j = self.inputs
        # a frame whose regressor (r, else u) is complete keeps missing outputs: they are
        # estimated with it (missing_lpm.py); one missing a regressor sample is dropped
        x = u[:, j] if ref is None else ref[:, j]
        whole = np.all(np.isfinite(x), axis=1)
        end = None
        for s in range(a, ok.size - n + 1, n):
            sl = slice(s, s + n)
            if not np.all(ok[sl]) and not np.all(whole[sl]):
                self._drop('regressor')
                continue
            try:
                self.acc.add(y[sl], u[sl, j], None if ref is None else ref[sl, j])
            except EstimationError as why:
                self._drop(str(why))
                continue
            end = float(rec.t[0] + (s + n) / rec.fs)
        if end is not None:
            self.used_until = end
        return end

    def results(self, notes: list[str]) -> dict[str, FrequencyResponse]:
        """
        Return 'lpm' and its baseline 'lpm_h1' (Welch H1 with coherence in its meta).

        Parameters
        ----------
        notes : list of str
            Why the blocks had no periodic excitation (kept in meta['detected']).

        Returns
        -------
        dict of str to FrequencyResponse
            'lpm': P with its noise variance; 'lpm_h1': the Welch H1 of the same frames,
            ``meta['coherence']`` (n_out, n_freq). ``meta['detected']`` of both holds the
            notes and the one-line summary of the estimator.

        Raises
        ------
        EstimationError
            No whole frame left to estimate (gaps in the regressor drop a frame).

        """
        if self.acc is None or not self.acc.frames:
            n = 0 if self.acc is None else self.acc.n
            raise EstimationError(f'no whole LPM frame of {n} samples left to estimate'
                                  f'{self._dropped_text() or " (none dropped for gaps)"}; '
                                  f'expected a longer record, or the regressor recorded '
                                  f'without gaps')
        res = self.acc.result()
        frf, h1 = res.frf, res.h1
        if not frf.freq_hz.size:
            raise EstimationError(self._no_line_text(frf))
        if self.band is not None:
            lo, hi = self.band
            frf = frf.select((frf.freq_hz >= lo) & (frf.freq_hz <= hi))
            h1 = h1.select((h1.freq_hz >= lo) & (h1.freq_hz <= hi))
        ins = ', '.join(n.split('/', 1)[1] for n in frf.inputs)
        band, singular = frf.meta['excitation_band_hz'], frf.meta['singular_lines']
        unexcited = frf.meta['unexcited_lines']
        how = (f'indirect through the velocity reference r of {ins} (P = G_yr G_ur^-1)'
               if res.method == 'indirect' else f'direct, input {ins}' if self.layout
               else f'direct, torque of {ins} as input')
        line = (f'Local Polynomial Method, {how}: '
                f'{frf.noutputs}x{frf.ninputs} channels, {frf.freq_hz.size} lines '
                f'{frf.freq_hz[0]:.4g}-{frf.freq_hz[-1]:.4g} Hz, {res.frames} frame(s) of '
                f'{self.acc.n / self.acc.fs:.4g} s, {res.dof} dof per window; 99 % of the '
                f'{"r" if res.method == "indirect" else "u"} power in '
                f'{band[0]:.4g}-{band[1]:.4g} Hz'
                + (f', {singular} line(s) without excitation of every input dropped'
                   if singular else '')
                + (f', {unexcited} line(s) with less than {EXCITED_FRACTION:g} of the largest '
                   f'line excitation dropped' if unexcited else '')
                + self._dropped_text())
        ex = h1.meta['excited']
        coh = np.median(h1.meta['coherence'][:, ex], axis=1)
        f_ex = h1.freq_hz[ex]
        base = (f'Welch H1 baseline (lpm_h1): median coherence over the excited '
                f'{f_ex[0]:.4g}-{f_ex[-1]:.4g} Hz: '
                + ', '.join(f'{n.split("/", 1)[1]} {c:.2f}' for n, c in zip(h1.outputs, coh)))
        warning = ([] if res.method != 'direct' else [DIRECT_WARNING] if not self.direct else
                   [DIRECT_WARNING.replace('no reference recorded', "method='lpm-direct'")])
        detected = list(notes) + [line] + warning + [base]
        for v in (frf, h1):
            v.meta['detected'] = detected
            v.meta['units'] = self.units
        frf.meta['dropped'] = {'frames': self.dropped} if self.dropped else {}
        if self.acc.missing is not None:
            frf.meta['missing'] = self.acc.missing.to_dict()
        return {'lpm': frf, 'lpm_h1': h1}

    def _no_line_text(self, frf: FrequencyResponse) -> str:
        """Say why no line of the LPM is determined (every line unexcited or singular)."""
        lo, hi = frf.meta['excitation_band_hz']
        x = 'the velocity reference r' if self.source == 'velocity reference' else 'the torque u'
        text = (f'no line of the LPM is determined: 99 % of the power of {x} lies in '
                f'{lo:.4g}-{hi:.4g} Hz, {frf.meta["unexcited_lines"]} line(s) hold less than '
                f'{EXCITED_FRACTION:g} of the largest line excitation and '
                f'{frf.meta["singular_lines"]} do not excite every input; expected {x} '
                f'exciting every input over the band of interest')
        if self.source == 'velocity reference':
            text += (" (method='lpm-direct' estimates y on u directly, biased towards -1/C "
                     'where noise is fed back)')
        return text
