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
The analysis band and the residual scan above it on the real records (issue #41 item 4).

``frf-ident diagnose`` (the app function) on EMPS and on KUKA A axes 1-3: the band the record
chose, what the scan above it reports (``unexplained`` resonances and lines), the effects, and
the wall time of the scan beside the whole diagnosis. Writes the EMPS figure the docs show,
docs/img/emps_residual_spectrum.png (:func:`frf_ident.report.residual_spectrum`).

Run: ``python -m benchmarks band``.
"""
from __future__ import annotations

from pathlib import Path
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / 'shared' / 'data'
RECORDS = [
    ('EMPS', DATA / 'EMPS' / 'DATA_EMPS.mat', 'map_emps.yaml', 'model_emps.yaml',
     ROOT / 'docs' / 'img' / 'emps_residual_spectrum.png'),
    ('KUKA A', DATA / 'KUKA_KR300_Weigand2021' / 'recorded_FF_A_2020-10-21.mat',
     'map_kuka_kr300.yaml', 'model_kuka_kr300_axes123.yaml', None)]


def _peaks(unexplained: list) -> str:
    """Return the scan's entries (:class:`Unexplained` records) as one short text."""
    found = [f'{u.axis}: {u.kind.split()[0]} {u.signature.peak_hz:.0f} Hz '
             f'({u.signature.band_hz[0]:.0f}-{u.signature.band_hz[1]:.0f} Hz, '
             f'{u.signature.peak_over_floor:.0f}x floor)'
             for u in unexplained if u.signature.peak_hz is not None]
    return '; '.join(found) or 'none'


def rows() -> list[tuple[str, str, str, str]]:
    """Diagnose each record present; return the band, the scan and the effects per record."""
    from frf_ident.app.diagnose import diagnose
    from frf_ident.core.diagnosis.regressors import model_residual
    from frf_ident.core.diagnosis.timeseries.resonance import resonances_above
    from frf_ident.report.residual_spectrum import residual_spectrum_figure
    out: list[tuple[str, str, str, str]] = []
    for name, data, mp, model, fig in RECORDS:
        if not data.exists():
            out.append((f'{name}: record', 'missing', str(data), '-'))
            continue
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            r = diagnose(data, ROOT / 'config' / model, Path(tmp), map_path=ROOT / 'config' / mp,
                         progress=lambda _line: None)
            wall = time.perf_counter() - t0
        res, rec = r.result, r.recording
        t0 = time.perf_counter()
        resonances_above(model_residual(rec, res.extended)[0], rec.fs, res.band.fc_hz,
                         res.extended.joint_names)
        scan = time.perf_counter() - t0
        b = res.band
        out += [(f'{name}: analysis band', f'0-{b.fc_hz:.3g} Hz (set by the {b.reason})',
                 'motion to ' + ', '.join(f'{x:.3g}' for x in b.motion_hz) + ' Hz',
                 f'limit {b.limit_hz:.3g} Hz'),
                (f'{name}: above the band', _peaks(res.unexplained),
                 'not scanned with the fixed 20 Hz low-pass', '-'),
                (f'{name}: effects', ', '.join(f'{e.name}@{e.axis}' for e in res.effects)
                 or 'none', '-', '-'),
                (f'{name}: scan wall time', f'{1e3 * scan:.0f} ms', f'diagnose {wall:.1f} s',
                 f'{scan / wall:.1%}')]
        if fig is not None:
            residual_spectrum_figure(res, rec, fig, title=f'{name} ({data.name}): residual '
                                     'of the extended model, analysis band and scan above it')
            out.append((f'{name}: figure', str(fig.relative_to(ROOT)), '-', '-'))
    return out
