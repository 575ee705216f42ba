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
The report page of ``frf-ident tune`` (tune.html), in the layout of the fit and loop pages.

Sections: the verdict per axis and target, the filters, the figure (tune.png), the margins
of the tuned and of the model file's controller at the nominal pose (the tables of
``loop``), every pose, the uncertainty weights, the files written. The caller passes the
rows; this module only renders them.
"""
from __future__ import annotations

import html
from pathlib import Path
from typing import Any, Sequence

from frf_ident.core.loop.check import LoopCheck
from frf_ident.report.html import fit_sections, write_fit_report

__all__ = ['table', 'write_tune_page']


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return f'<td class="num">{v:.4g}</td>'
    if isinstance(v, int) and not isinstance(v, bool):
        return f'<td class="num">{v}</td>'
    return f'<td>{html.escape("" if v is None else str(v))}</td>'


def table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    """Return header and rows as an HTML table, floats with 4 significant digits."""
    head = ''.join(f'<th>{html.escape(h)}</th>' for h in header)
    body = ''.join('<tr>' + ''.join(_cell(v) for v in r) + '</tr>' for r in rows)
    return f'<table><tr>{head}</tr>{body}</table>'


def write_tune_page(path: str | Path, *, title: str, intro: str,
                    verdicts: tuple[Sequence[str], Sequence[Sequence[Any]]],
                    filters: tuple[Sequence[str], Sequence[Sequence[Any]]],
                    poses: tuple[Sequence[str], Sequence[Sequence[Any]]],
                    weights: tuple[Sequence[str], Sequence[Sequence[Any]]],
                    after: LoopCheck, before: LoopCheck | None, figure: str,
                    files: Sequence[str], reasons: Sequence[str]) -> Path:
    """
    Write tune.html.

    Parameters
    ----------
    path : str or Path
        The page.
    title : str
        Its title.
    intro : str
        One paragraph (plain text): sources, nominal pose, rate, targets.
    verdicts, filters, poses, weights : tuple
        (header, rows) of each table.
    after, before : LoopCheck
        The tuned and the model file's controller at the nominal pose (``before`` None
        without a model file).
    figure : str
        File name of tune.png next to the page.
    files : sequence of str
        The files written.
    reasons : sequence of str
        One sentence per axis on what binds ('' when nothing does).

    Returns
    -------
    Path
        ``path``.

    """
    why = ''.join(f'<li>{html.escape(r)}</li>' for r in reasons if r)
    sections = [('verdict', 'Targets per axis, worst pose',
                 f'<p>{html.escape(intro)}</p>' + table(*verdicts)
                 + (f'<p>What binds:</p><ul>{why}</ul>' if why else '')),
                ('filters', 'Filters (on the measured velocity, in front of the PI)',
                 table(*filters)),
                ('figure', 'Loops before and after', (
                    f'<figure><a href="{html.escape(figure)}"><img src="{html.escape(figure)}" '
                    'alt="loop Bode and Nyquist before and after"></a><figcaption>Bode and '
                    'Nyquist of L = C P-hat per axis: tuned at the nominal pose (thick) with '
                    'the band |L0| (1 &plusmn; |W|) and the discs |W L0| the uncertainty '
                    "weight covers, at the other poses (thin), and with the model file's "
                    'controller (dashed); the circle around &minus;1 is the modulus margin '
                    'target.</figcaption></figure>'))]
    tuned = fit_sections(check=after)[0][2]
    sections.append(('tuned', 'Margins of the tuned controller, nominal pose', tuned))
    if before is not None:
        sections.append(('before', "Margins of the model file's controller, nominal pose",
                         fit_sections(check=before)[0][2]))
    sections += [('poses', 'Every pose', table(*poses)),
                 ('weights', 'Uncertainty weights W(s) and robust stability', table(*weights)),
                 ('files', 'Files', '<ul>' + ''.join(f'<li>{html.escape(f)}</li>'
                                                     for f in files) + '</ul>')]
    return write_fit_report(path, title=title, sections=sections)
