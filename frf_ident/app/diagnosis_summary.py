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
The few lines a person reads after a diagnosis: effects found, what is unexplained, the gain.

Used by ``frf-ident diagnose`` and ``frf-ident demo``, from the typed
:class:`frf_ident.core.diagnosis.Diagnosis` (report.json is written from the same object).
Numbers carry 3-4 significant digits (the report's JSON keeps 6) and their units; parameters
are written ``name value unit`` (:func:`frf_ident.report.text.parameters_text`, as in the HTML
report).
"""
from __future__ import annotations

from pathlib import Path
import textwrap
from typing import TYPE_CHECKING

from frf_ident.report.effect_names import effect_phrase
from frf_ident.report.text import not_determined_text, parameters_text

if TYPE_CHECKING:
    from frf_ident.core.diagnosis import Diagnosis
    from frf_ident.core.diagnosis.crosscheck.least_squares import LeastSquaresCheck
    from frf_ident.core.diagnosis.records import Scores, Unexplained

__all__ = ['CONTINUED', 'diagnosis_summary']

#: a summary line's width [characters]: a terminal's 160 less a log line's prefix
WIDTH = 150
#: the indent of an effect line's continuation (not-determined lines are indented by 3)
CONTINUED = ' ' * 6


def diagnosis_summary(diag: Diagnosis, out: Path) -> list[str]:
    """
    Return the summary lines of a diagnosis.

    Parameters
    ----------
    diag : Diagnosis
        The diagnosis.
    out : Path
        The output directory (named in the last line).

    Returns
    -------
    list of str
        One line per effect (its values with units and standard errors; below it two per
        value the record does not determine: its range and the experiment that would
        determine it) and per unexplained axis, the held-out error before and after,
        one per validation record, and where the report was written.

    """
    res = diag.result
    lines = []
    for k, e in enumerate(res.effects):
        lines += _effect_lines(f'{k + 1}. {effect_phrase(e.name)} on {e.axis}: ',
                               parameters_text(e.parameters, e.standard_error),
                               f'score {e.score:.2f}'
                               + (' (not counted as found)' if e.not_determined else ''))
        for n in e.not_determined:
            what, helps = not_determined_text(n)
            lines += [f'   {what}', f'   {helps}']
    if not res.effects:
        lines.append('no effects: none of the candidates improves the held-out data')
    if res.band is not None:
        lines.append(f'analysis band 0-{res.band.fc_hz:.3g} Hz (set by the {res.band.reason}); '
                     'residual above it scanned for resonances')
    lines += [_unexplained(u) for u in res.unexplained]
    m = res.metrics
    # what was held out on a line of its own: it names records and realisations (120 chars)
    lines.append(f'held-out error: nominal {_scores(m.baseline)} -> extended '
                 f'{_scores(m.extended)}')
    lines.append(f'  {m.validation}')
    lines += [f'held-out FRF error in the band of {r.text()}' for r in m.resonance_bands]
    if m.resonance_bands and not m.improved:
        lines.append('not an improvement: the extension is worse in a resonance band')
    lines += [f'on {v.record}: nominal {_scores(v.baseline)} -> extended {_scores(v.extended)}'
              for v in diag.checks.validation_records]
    ls = diag.checks.least_squares
    if ls is not None:
        lines += _against_baseline(ls)
    # the folder once: three full paths made a 230-character line in a deep output folder;
    # extended_model.xml where a model naming an MJCF wrote it (docs/mujoco.md)
    xml = ', extended_model.xml' if (out / 'extended_model.xml').is_file() else ''
    lines.append(f'wrote report.json, extended_model.yaml{xml} and report.html in {out}')
    return lines


def _effect_lines(head: str, values: str, score: str) -> list[str]:
    """
    Write an effect: its head, its values and score, wrapped between values only.

    The cause in words made a ripple's line 170 characters long; a value is never parted
    from its unit or error: continuation lines (indented by ``CONTINUED``) start at a value.
    """
    groups = [g.split(', ') for g in values.split('; ')]
    tokens = [part + (', ' if j < len(group) - 1 else '; ')
              for group in groups for j, part in enumerate(group)]
    lines, line, empty = [], head, True
    for token in tokens + [score]:
        if not empty and len(line) + len(token.rstrip()) > WIDTH:
            lines.append(line.rstrip())
            line = CONTINUED
        line, empty = line + token, False
    return lines + [line]


def _unexplained(u: Unexplained) -> str:
    """Write an unexplained entry: an axis above its floor, or a peak above the band."""
    s = u.signature
    if u.misfit_share is None and s.centre_hz is not None:
        return (f'unexplained on {u.axis}: {u.kind}, {s.band_hz[0]:.3g}-{s.band_hz[1]:.3g} Hz '
                f'(centre {s.centre_hz:.3g} Hz, peak {s.peak_hz:.3g} Hz, '
                f'{s.peak_over_floor:.3g}x the noise)')
    if u.misfit_share is None:
        cause = f'; {u.cause.describe()}' if u.cause is not None else ''
        return (f'unexplained on {u.axis}: {u.kind}, {s.band_hz[0]:.3g}-{s.band_hz[1]:.3g} Hz '
                f'(peak {s.peak_hz:.3g} Hz, {s.peak_over_floor:.3g}x the local noise floor)'
                f'{cause}')
    band = f', strongest misfit {s.band_hz[0]:.3g}-{s.band_hz[1]:.3g} Hz' if s.band_hz else ''
    return (f'unexplained on {u.axis}: {100 * u.misfit_share:.0f} % of the nominal misfit '
            f'left{band}')


def _against_baseline(ls: LeastSquaresCheck) -> list[str]:
    """Write per held-out set whether each axis beats, ties or loses to the baseline."""
    by_set: dict[str, list[str]] = {}
    for v in ls.verdicts:
        by_set.setdefault(v.record, []).append(
            f'{v.axis} {v.verdict} ({v.extended:.3g} / {v.least_squares:.3g})')
    # wrapped: three axes of a long record name made a 170-character line
    return [line for rec, parts in by_set.items()
            for line in textwrap.wrap(f'against the least-squares baseline on {rec} (time NRMSE '
                                      'extended / baseline): ' + ', '.join(parts), 150,
                                      subsequent_indent='  ', break_on_hyphens=False)]


def _scores(s: Scores) -> str:
    """Write a model's held-out numbers ('n/a' where neither is defined)."""
    parts = ([f'FRF {s.frf_error_db:.3g} dB'] if s.frf_error_db == s.frf_error_db else []) + \
        ([f'time NRMSE {s.time_nrmse:.3g}'] if s.time_nrmse == s.time_nrmse else [])
    return ', '.join(parts) or 'n/a'
