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
The HTML report in a real browser: headless Chromium at desktop and phone widths.

Chromium is Debian's ``chromium`` package; the tests skip where it is not installed.

A probe script added to a copy of the page measures what a reader would see: the page must fit
its window without horizontal scrolling and no figure may be wider than the window. Headless
Chromium keeps a window at least 500 px wide, so the page is shown in a frame of the width
under test (as a phone shows it) and the probe reports to the frame's parent. Before the
report's tables scrolled inside themselves, this report's estimates table widened a 390 px page
to 646 px.
"""
import html
import json
from pathlib import Path
import re
import shutil
import subprocess

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.report import write_report
import numpy as np
import pytest

CHROMIUM = next((p for p in map(shutil.which, ('chromium', 'chromium-browser', 'google-chrome'))
                 if p), None)
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason='headless Chromium not installed')

PROBE = """<script>
window.addEventListener('load', () => {
  const imgs = [...document.images];
  const out = {};
  out.textContent = JSON.stringify({
    scroll_width: document.documentElement.scrollWidth, inner_width: window.innerWidth,
    images: imgs.length, loaded: imgs.every(i => i.complete && i.naturalWidth > 0),
    widest_image: Math.max(0, ...imgs.map(i => i.getBoundingClientRect().width)),
    rightmost_image: Math.max(0, ...imgs.map(i => i.getBoundingClientRect().right))});
  parent.postMessage(out.textContent, '*');
});
</script>"""
FRAME = ('<!DOCTYPE html><html><body style="margin:0">'
         '<iframe src="{src}" width="{width}" height="900" style="border:0"></iframe>'
         '<script>window.addEventListener("message", e => {{'
         'const out = document.createElement("pre"); out.id = "probe"; '
         'out.textContent = e.data; document.body.appendChild(out); }});</script>'
         '</body></html>')


def _chromium(tmp: Path, width: int, *args: str) -> str:
    cmd = [CHROMIUM, '--headless', '--no-sandbox', '--disable-gpu', '--hide-scrollbars',
           f'--user-data-dir={tmp / "profile"}', f'--window-size={max(width, 500)},900',
           '--allow-file-access-from-files',
           '--virtual-time-budget=5000', *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=True).stdout


@pytest.fixture(scope='module')
def report(tmp_path_factory) -> Path:
    """Write a report of two 2x2 estimates with variances (two figures)."""
    f = np.geomspace(1, 60, 40)
    s = 2j * np.pi * f
    p = 1 / (s * (35 + 150 * 1.5e5 / (150 * s ** 2 + 400 * s + 1.5e5)))
    resp = np.array([[p, 0.2 * p], [0.2 * p, p]])
    var = (0.05 * np.abs(resp)) ** 2
    names = (['tau_1', 'tau_2'], ['dq_1', 'dq_2'])
    frfs = {'multisine': FrequencyResponse(f, 1.02 * resp, *names, var / 4, var),
            'chirp': FrequencyResponse(f, 0.98 * resp, *names, noise_variance=var)}
    return write_report(tmp_path_factory.mktemp('browser') / 'rep', frfs=frfs,
                        title='frf_ident report in a browser')


@pytest.mark.parametrize('width', [1280, 390])
def test_page_fits_the_window_and_figures_fit_the_page(report, tmp_path, width):
    probe = report.with_name('probe.html')
    probe.write_text(report.read_text().replace('</body>', PROBE + '</body>'))
    frame = report.with_name(f'frame_{width}.html')
    frame.write_text(FRAME.format(src=probe.name, width=width))
    dom = _chromium(tmp_path, width, '--dump-dom', frame.as_uri())
    m = re.search(r'<pre id="probe">(.*?)</pre>', dom, re.S)
    assert m, dom[-2000:]
    seen = json.loads(html.unescape(m.group(1)))
    assert seen['inner_width'] == width and seen['images'] >= 2 and seen['loaded'], seen
    assert seen['scroll_width'] <= width, seen                 # no horizontal scrolling
    assert seen['rightmost_image'] <= width and seen['widest_image'] <= width, seen


def test_screenshot_is_taken(report, tmp_path, width=390):
    """Screenshots as a reader sees the page (the narrow one: the frame at the left)."""
    frame = report.with_name(f'shot_{width}.html')
    frame.write_text(FRAME.format(src=report.name, width=width))
    png = tmp_path / f'report_{width}.png'
    _chromium(tmp_path, width, f'--screenshot={png}', frame.as_uri())
    head = png.read_bytes()[:24]
    assert head[:8] == b'\x89PNG\r\n\x1a\n'
    assert int.from_bytes(head[16:20], 'big') == max(width, 500)
