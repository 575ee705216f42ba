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

Used by ``frf-ident diagnose`` and ``frf-ident demo``. Numbers carry 3-4 significant digits
(the report's JSON keeps 6); parameters are written ``name value`` instead of dict reprs
(:func:`frf_ident.report.text.plain`, as in the HTML report).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from frf_ident.report.text import plain

__all__ = ['diagnosis_summary']


def _band(signature: Mapping[str, Any]) -> str:
    band = signature.get('band_hz')
    if band:
        return f', strongest misfit {band[0]:.3g}-{band[1]:.3g} Hz'
    return ''


def diagnosis_summary(report: Mapping[str, Any], out: Path) -> list[str]:
    """
    Return the summary lines of a diagnosis report.

    Parameters
    ----------
    report : mapping
        The content of report.json.
    out : Path
        The output directory (named in the last line).

    Returns
    -------
    list of str
        One line per effect and per unexplained axis, the held-out error before and after,
        one per validation record, and where the report was written.

    """
    lines = []
    for k, e in enumerate(report['effects']):
        se = e.get('standard_error')
        se = f' (standard error {plain(se)})' if se else ''
        lines.append(f"{k + 1}. {e['name']} on {e['axis']}: {plain(e['parameters'])}{se}; "
                     f"score {e['score']:.2f}")
    if not report['effects']:
        lines.append('no effects: none of the candidates improves the held-out data')
    band = report.get('analysis_band')
    if band:
        lines.append(f"analysis band 0-{band['fc_hz']:.3g} Hz (set by the {band['set_by']}); "
                     'residual above it scanned for resonances')
    for u in report['unexplained']:
        if 'misfit_share' not in u:
            s = u['signature']
            lines.append(f"unexplained on {u['axis']}: {u['kind']}, {s['band_hz'][0]:.3g}-"
                         f"{s['band_hz'][1]:.3g} Hz (peak {s['peak_hz']:.3g} Hz, "
                         f"{s['peak_over_floor']:.3g}x the local noise floor)")
            continue
        lines.append(f"unexplained on {u['axis']}: {100 * u['misfit_share']:.0f} % of the "
                     f"nominal misfit left{_band(u.get('signature', {}))}")
    m = report['metrics']

    def err(side: Mapping[str, Any]) -> str:
        db = side.get('frf_error_db')
        nrmse = side.get('time_nrmse')
        parts = ([f'FRF {db:.3g} dB'] if isinstance(db, (int, float)) else []) + \
            ([f'time NRMSE {nrmse:.3g}'] if isinstance(nrmse, (int, float)) else [])
        return ', '.join(parts) or 'n/a'
    lines.append(f"held-out error: nominal {err(m['baseline'])} -> extended "
                 f"{err(m['extended'])} ({m.get('validation', 'held-out part')})")
    for v in m.get('validation_records', []):
        lines.append(f"on {v['record']}: nominal {err(v['baseline'])} -> extended "
                     f"{err(v['extended'])}")
    lines.append(f'wrote {out / "report.json"}, {out / "extended_model.yaml"}, '
                 f'{out / "report.html"}')
    return lines
