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
Spectra of a detected segment: a multisine's periods (missing samples filled) and chirp lines.

The period spectra of a detected multisine (:func:`multisine_periods`): whole periods inside
the data, those an earlier block used skipped, missing samples (NaN rows of a recording read
with ``gaps='mark'``) estimated from the other periods
(:mod:`frf_ident.core.estimation.missing_periodic`) or, where they cannot be, the periods
they touch dropped; and the Sec. 5.1 spectra of a detected chirp at its analysis frequencies
(:func:`chirp_lines`).
"""
from __future__ import annotations

from frf_ident.core.estimation.checks import missing_rows
from frf_ident.core.estimation.missing_periodic import fill_steady_periods
from frf_ident.core.estimation.spectra import periodic_spectra
from frf_ident.core.estimation.transient import steady_periods
from frf_ident.core.excitation.chirp import ChirpDesign
from frf_ident.core.excitation.chirp_dft import chirp_analysis_frequencies, chirp_spectra
from frf_ident.core.excitation.multisine import reference_frequency_set
from frf_ident.core.recording import Recording, Segment
import numpy as np

__all__ = ['chirp_lines', 'multisine_periods', 'output_columns']


def multisine_periods(rec: Recording, seg: Segment, *, used_until: float | None = None
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int,
                                 list[tuple[float, float]]]:
    """
    Compute the period spectra of a detected multisine.

    Excited bins, the period spectra U, Y (n_q, F, n) of a detected multisine's periods
    without missing samples, the periods skipped, the (t_start, t_end) of the periods
    dropped for missing samples, Y at every detection line (n_q, L, n) and the input at the
    lines up to the band (n_q, B) (for the estimator's transient test).

    When the excitation was already running (``used_until``: the end [s] of the periods an
    earlier block used) the periods starting before it are skipped, so overlapping blocks
    never count a period twice, and the whole periods between it and this block's first are
    taken. Only whole periods inside the data are used; the start-up transient is left out
    later, on all periods of the excitation (by the estimator,
    :mod:`frf_ident.core.estimation.detected_estimator`).
    """
    info = seg.info
    i0 = int(info.get('start', rec.index_of(seg.t_start)))
    n_per = int(info['period_samples'])
    n_q = max(0, min(int(info['periods']), (rec.t.size - i0) // n_per))
    if used_until is not None:
        # the excitation goes on: the whole periods between the earlier block's last one and
        # this block's (flush with its end) are periods of the same run, not a transient
        back = min(i0 // n_per, max(0, int(np.floor(
            (rec.t[0] + i0 / rec.fs - used_until) * rec.fs / n_per + 1e-6))))
        i0, n_q = i0 - back * n_per, n_q + back
    starts = rec.t[0] + (i0 + np.arange(n_q) * n_per) / rec.fs
    skip = 0 if used_until is None else int(np.count_nonzero(
        starts < used_until - 0.5 / rec.fs))
    bins = np.asarray(info['harmonics'])
    j = int(info['input'])
    gone = missing_rows(rec.effort[:, j], rec.velocity)
    # detection lines: every line up to three times the band (a cubic's products); the
    # transient test looks at the input's lines up to the band
    lines = np.arange(1, min(3 * int(np.max(bins)), (n_per - 1) // 2) + 1)
    band = np.arange(1, min(int(np.max(bins)), (n_per - 1) // 2) + 1)
    idx = (i0 + np.arange(skip, n_q) * n_per)[:, None] + np.arange(n_per)   # (n_b, n_per)
    miss = gone[idx]
    u, y = rec.effort[idx], rec.velocity[idx]
    keep, filled = ~miss.any(axis=1), None
    if miss.any():
        u, y, keep, filled = _filled_block(rec, u, y, miss, j, band, used_until is None)
    dropped = [(float(starts[q]), float(starts[q] + n_per / rec.fs))
               for q, k in zip(range(skip, n_q), keep) if not k]
    if not np.any(keep):
        empty = np.empty((0, bins.size, rec.velocity.shape[1]), dtype=complex)
        return bins, empty, empty, skip, dropped, empty[:, :0], empty[:, :0, 0], None
    u, y = u[keep], y[keep]
    U = periodic_spectra(u, bins, axis=1)
    Y = periodic_spectra(y, bins, axis=1)
    return (bins, U, Y, skip, dropped, periodic_spectra(y, lines, axis=1),
            periodic_spectra(u[:, :, j], band, axis=1), filled)


def _filled_block(rec: Recording, u: np.ndarray, y: np.ndarray, miss: np.ndarray, j: int,
                  band: np.ndarray, new_run: bool) -> tuple:
    """
    Estimate the missing samples of a block's periods from its other periods.

    ``u``, ``y`` (n_b, n_per, n) the efforts and velocities of the block's periods, ``miss``
    (n_b, n_per) their missing samples (:mod:`frf_ident.core.estimation.missing_periodic`). A
    new run is filled from its steady periods (the transient test on the input's and outputs'
    lines up to the band). Returns u, y, the periods kept (all, unless a sample is missing in
    every period: then those a gap touches are dropped) and (FilledPeriods, account) or None.
    """
    n_u = u.shape[2]

    def first_steady(v: np.ndarray) -> int:
        return steady_periods(np.concatenate([periodic_spectra(v[:, :, j], band, axis=1)[
            :, :, None], periodic_spectra(v[:, :, n_u:], band, axis=1)], axis=2)).first
    fill = fill_steady_periods(np.concatenate([u, y], axis=2), miss,
                               first_steady if new_run else None)
    if not fill.complete:
        return u, y, ~miss.any(axis=1), None
    names = rec.joint_names
    outs = set(output_columns(rec))
    channels = [f'tau_m/{m}' for m in names] + [f'dq_m/{m}' for m in names]
    keep = np.array([k == j for k in range(n_u)] + [k in outs for k in range(y.shape[2])])
    accounts = [fill.account(channels, keep=keep, periods=np.arange(len(miss)) == q)
                for q in range(len(miss))]
    return (np.ascontiguousarray(fill.values[:, :, :n_u]),
            np.ascontiguousarray(fill.values[:, :, n_u:]), np.ones(len(miss), bool),
            (fill.periods(), accounts))


def output_columns(rec: Recording) -> list[int]:
    """Columns that are outputs: all joints, or the outputs of an import layout."""
    return rec.output_columns()


def chirp_lines(rec: Recording, seg: Segment) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Analysis frequencies and the Sec. 5.1 spectra U, Y (F, n) of a detected chirp."""
    info = seg.info
    design = ChirpDesign(info['f_low'], info['f_high'], info['t1'] - info['t0'],
                         np.ones((1, 1)), t0=info['t0'])
    freqs = chirp_analysis_frequencies(reference_frequency_set(info['f_low'], info['f_high']),
                                       design.time_at, info['t0'], info['t1'])
    tc = design.time_at(freqs)            # detection times count from the first sample
    return (freqs, chirp_spectra(rec.effort, rec.fs, freqs, tc),
            chirp_spectra(rec.velocity, rec.fs, freqs, tc))
