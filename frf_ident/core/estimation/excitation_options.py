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
What is known about the excitation of a recording without descriptors: ExcitationOptions.

The options of `frf-ident estimate` (the excited joint, a multisine period and the band of its
lines, a chirp's band and sweep times, or the LPM as the method): the given parts replace the
respective detection (:mod:`frf_ident.core.estimation.detected_segments`). Checked against
the recording (:meth:`ExcitationOptions.check`) before anything is detected.
"""
from __future__ import annotations

from dataclasses import dataclass

from frf_ident.core.estimation.checks import check_band, check_periods
from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError

__all__ = ['LPM_METHODS', 'ExcitationOptions']

#: the methods that force the LPM without detecting (ExcitationOptions.method): the indirect
#: estimate through r where r is recorded, or the direct one of y on u
LPM_METHODS = ('lpm', 'lpm-direct')


@dataclass(frozen=True)
class ExcitationOptions:
    """
    What is known about the excitation of a recording without descriptors; None: detect.

    Parameters
    ----------
    input : str, optional
        Name of the excited joint (the only input analysed).
    multisine_period : float, optional
        Multisine period [s]; the periodic block and lines are found in the data.
    band : tuple of float, optional
        (f_low, f_high) [Hz]; only multisine lines inside are analysed.
    chirp : tuple of float, optional
        (f_low, f_high) [Hz] of an exponential chirp (eq. 16); needs ``chirp_time``.
    chirp_time : tuple of float, optional
        (t0, t1) [s] of the sweep, counted from the first analysed sample (as the
        detection reports them).
    method : str, optional
        'lpm': the excitation is not periodic, estimate with the Local Polynomial Method
        (:mod:`frf_ident.core.estimation.nonperiodic`) without detecting; 'lpm-direct': the
        same, the direct estimate of y on u even where the reference r is recorded (biased
        towards -1/C where noise is fed back; for a reference that does not excite the band);
        None: detect, and use the LPM only where no multisine or chirp is found.

    """

    input: str | None = None  # noqa: A003
    multisine_period: float | None = None
    band: tuple[float, float] | None = None
    chirp: tuple[float, float] | None = None
    chirp_time: tuple[float, float] | None = None
    method: str | None = None

    def given(self) -> bool:
        """
        Return true when any option is set.

        Returns
        -------
        bool
            False when every option is None (detect everything).

        """
        return any(v is not None for v in (self.input, self.multisine_period, self.band,
                                           self.chirp, self.chirp_time, self.method))

    def text(self) -> str:
        """
        Return the given options as 'name=value' pairs.

        Returns
        -------
        str
            Comma-separated ``name=value`` of the options that are not None (for messages).

        """
        return ', '.join(f'{k}={v!r}' for k, v in vars(self).items() if v is not None)

    def check(self, rec: Recording) -> None:
        """
        Refuse options that contradict each other or the recording (one line each).

        Parameters
        ----------
        rec : Recording
            The recording the options are for (joint names, sample rate, duration).

        Raises
        ------
        EstimationError
            An unknown input joint, both a chirp and a multisine period, a chirp without
            sweep times (or the reverse), a band with a chirp, a band or chirp frequency at
            or above Nyquist, fewer than two periods in the recording, or sweep times outside
            it.

        """
        if self.method not in (None, *LPM_METHODS):
            raise EstimationError(f'method={self.method!r}: expected one of {LPM_METHODS} '
                                  f'(or none: detect)')
        if self.method in LPM_METHODS and (self.chirp is not None
                                           or self.multisine_period is not None):
            raise EstimationError(f'method={self.method!r} with {self.text()}: the LPM is for '
                                  f'excitation that is neither a multisine nor a chirp')
        if self.input is not None and self.input not in rec.joint_names:
            raise EstimationError(f'input={self.input!r} is not a joint of the recording; '
                                  f'expected one of {rec.joint_names}')
        if self.chirp is not None and self.multisine_period is not None:
            raise EstimationError('chirp and multisine_period both given; expected one '
                                  'excitation')
        if (self.chirp is None) != (self.chirp_time is None):
            raise EstimationError(f'chirp={self.chirp} and chirp_time={self.chirp_time}: '
                                  f'expected both (band and sweep times) or neither')
        if self.band is not None:
            if self.chirp is not None:
                raise EstimationError(f'band={self.band} restricts multisine lines; for a chirp '
                                      f'give its band as chirp=(f_low, f_high)')
            lo, hi = self.band
            if not lo < hi:
                raise EstimationError(f'band={self.band}: expected f_low < f_high [Hz]')
            check_band([lo, hi], rec.fs, where=f'band={self.band}')
        duration = float(rec.t[-1] - rec.t[0]) + rec.dt
        if self.multisine_period is not None:
            if not self.multisine_period > 0:
                raise EstimationError(f'multisine_period={self.multisine_period}: expected a '
                                      f'positive period in seconds')
            check_periods(int(duration // self.multisine_period), need=2,
                          where=f'multisine_period={self.multisine_period:g} s in a recording '
                                f'of {duration:.4g} s', hint='a shorter period or more data')
        if self.chirp is not None:
            lo, hi = self.chirp
            if not (lo > 0 and hi > 0 and lo != hi):
                raise EstimationError(f'chirp={self.chirp}: expected two different positive '
                                      f'frequencies [Hz]')
            check_band([lo, hi], rec.fs, where=f'chirp={self.chirp}')
            t0, t1 = self.chirp_time
            if not 0 <= t0 < t1 <= duration:
                raise EstimationError(f'chirp_time={self.chirp_time}: expected 0 <= t0 < t1 <= '
                                      f'{duration:.4g} s (seconds from the first analysed '
                                      f'sample)')
