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
The pieces every HTML page of frf_ident is made of: the page, a figure, a table of values.

Self-contained pages (inline CSS, no scripts, no external resources) whose figures are PNG
files beside them, referenced by relative file name.
"""
from __future__ import annotations

import datetime as _dt
import html
import math
from typing import Any, Mapping, Sequence

from frf_ident.core.recording import Recording
from frf_ident.report.text import plain
import numpy as np

__all__ = ['cell', 'CSS', 'figure_tag', 'num', 'page', 'table']

#: the style sheet of every page
CSS = """
body { font-family: system-ui, -apple-system, 'Segoe UI', sans-serif; margin: 2em auto;
       max-width: 1200px; color: #222; line-height: 1.45; padding: 0 1em; }
h1 { border-bottom: 2px solid #3b6ea5; padding-bottom: .2em; }
h2 { color: #3b6ea5; margin-top: 2em; }
body { overflow-wrap: break-word; }
figure { margin: 1em 0; } figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: .9em; color: #555; margin-top: .3em; }
table { border-collapse: collapse; margin: .6em 0; font-size: .9em; display: block;
        max-width: 100%; overflow-x: auto; }
th, td { border: 1px solid #ccc; padding: .25em .6em; text-align: left; overflow-wrap: normal; }
td:last-child { min-width: 14em; }
th { background: #eef3f8; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
.warn { color: #a33; } .ok { color: #272; } .muted { color: #777; font-size: .85em; }
nav a { margin-right: 1em; }
"""


def page(title: str, sections: list[tuple[str, str, str]], rec: Recording | None) -> str:
    """Return a whole page: title, navigation, (anchor, heading, html) sections, the record."""
    nav = ' '.join(f'<a href="#{a}">{html.escape(h)}</a>' for a, h, _ in sections)
    body = '\n'.join(f'<section id="{a}"><h2>{html.escape(h)}</h2>\n{content}\n</section>'
                     for a, h, content in sections)
    stamp = _dt.datetime.now().isoformat(timespec='seconds')
    src = ''
    if rec is not None:
        src = (f' &middot; recording: {rec.t.size} samples at {rec.fs:.6g} Hz, '
               f'{rec.t[-1] - rec.t[0]:.3f} s, joints {html.escape(", ".join(rec.joint_names))}')
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">\n'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            f'<title>{html.escape(title)}</title>\n<style>{CSS}</style></head>\n<body>\n'
            f'<h1>{html.escape(title)}</h1>\n<p class="muted">frf_ident report, {stamp}{src}'
            f'</p>\n<nav>{nav}</nav>\n{body}\n</body></html>\n')


def figure_tag(name: str, caption: str, alt: str) -> str:
    """Return a figure of the PNG file ``name`` beside the page, with its caption."""
    # the image links to itself: on a phone the page shrinks it, a tap shows it full size
    src = html.escape(name)
    return (f'<figure><a href="{src}"><img src="{src}" alt="{html.escape(alt)}"></a>'
            f'<figcaption>{caption}</figcaption></figure>')


def table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    """Return a table of values (:func:`cell` each) under a header row."""
    head = ''.join(f'<th>{html.escape(str(h))}</th>' for h in header)
    body = ''.join('<tr>' + ''.join(cell(v) for v in row) + '</tr>' for row in rows)
    return f'<table><tr>{head}</tr>{body}</table>'


def cell(v: Any) -> str:
    """Return one table cell: numbers right-aligned to 4 digits, structures in words."""
    if isinstance(v, bool) or v is None:
        return f'<td>{html.escape(str(v))}</td>'
    if isinstance(v, (int, np.integer)):
        return f'<td class="num">{int(v)}</td>'
    if isinstance(v, (float, np.floating)):
        return f'<td class="num">{num(float(v))}</td>'
    if isinstance(v, (Mapping, list, tuple)):
        return f'<td>{html.escape(plain(v))}</td>'
    return f'<td>{html.escape(str(v))}</td>'


def num(v: float) -> str:
    """Return a number to 4 significant digits (inf and nan as words)."""
    if not math.isfinite(v):
        return str(v)
    return f'{v:.4g}'
