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
"""A campaign's index.html: one table row per input, linking to its folder's outputs."""
from __future__ import annotations

import html
from pathlib import Path
from typing import Any, Mapping, Sequence

__all__ = ['write_campaign_page']

#: the pages an input's folder may hold, linked from its row when present (first found)
REPORT_PAGES = ('report.html', 'bode.png', 'frf.json')

_STYLE = ('body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1300px;padding:0 1em}'
          'table{border-collapse:collapse;font-size:.9em}'
          'th,td{border:1px solid #ccc;padding:.25em .6em;text-align:left}'
          'th{background:#eef3f8}td.num{text-align:right}'
          '.ok{color:#272}.refused,.failed{color:#a33;font-weight:bold}')


def _cell(col: str, v: Any) -> str:
    if isinstance(v, float):
        return f'<td class="num">{v:.4g}</td>'
    if col == 'status':
        return f'<td class="{html.escape(str(v))}">{html.escape(str(v))}</td>'
    return f'<td>{html.escape("" if v is None else str(v))}</td>'


def write_campaign_page(path: Path, *, title: str, columns: Sequence[str],
                        rows: Sequence[Mapping[str, Any]], route: str, seconds: float) -> Path:
    """
    Write a self-contained HTML table of a campaign (no scripts, relative links).

    Parameters
    ----------
    path : Path
        The page to write (the campaign folder's index.html).
    title : str
        The command that ran.
    columns : sequence of str
        Table columns; ``out`` becomes a link to the input's report when it has one.
    rows : sequence of mapping
        One record per input.
    route : str
        Where it ran (serial, processes, Dask).
    seconds : float
        Wall time of the campaign [s].

    Returns
    -------
    Path
        ``path``.

    """
    body = []
    for r in rows:
        cells = []
        for c in columns:
            v = r.get(c, '')
            page = next((p for p in REPORT_PAGES if (path.parent / str(r['out']) / p).exists()),
                        None) if c == 'out' else None
            if page:
                href = html.escape(f'{r["out"]}/{page}', quote=True)
                cells.append(f'<td><a href="{href}">{html.escape(str(v))}</a></td>')
            else:
                cells.append(_cell(c, v))
        body.append('<tr>' + ''.join(cells) + '</tr>')
    bad = sum(r.get('status') != 'ok' for r in rows)
    head = ''.join(f'<th>{html.escape(c)}</th>' for c in columns)
    path.write_text(
        f'<!DOCTYPE html><html><head><meta charset="utf-8"><title>frf-ident {html.escape(title)}'
        f' campaign</title><style>{_STYLE}</style></head><body>'
        f'<h1>frf-ident {html.escape(title)}: {len(rows)} inputs, {bad} not ok</h1>'
        f'<p>ran on {html.escape(route)} in {seconds:.1f} s; the outputs and log.txt of each '
        f'input are in its folder.</p><table><tr>{head}</tr>{"".join(body)}</table>'
        f'</body></html>\n')
    return path
