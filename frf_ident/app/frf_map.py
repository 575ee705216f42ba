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
The FRF map of an estimate campaign: resonance and antiresonance per axis against the pose.

Each bag's row of an ``frf-ident estimate`` campaign carries its pose (bags of ``identify
--poses``) and the resonance and antiresonance of each excited axis
(:func:`frf_ident.app.estimate.estimate_columns`). :func:`write_frf_map` collects them into
``frf_map.csv`` (one row per bag that succeeded) and ``frf_map.png`` (per axis, both
frequencies over the bags, each labelled with its pose) in the campaign folder. A global
pose-dependent model fitted to these maps is not made here: it needs the physical fit.
"""
from __future__ import annotations

import csv
from pathlib import Path

from frf_ident.app.campaign_summary import CampaignResult

__all__ = ['MAP_FILES', 'write_frf_map']

#: what :func:`write_frf_map` writes into the campaign folder
MAP_FILES = ('frf_map.csv', 'frf_map.png')

#: the per-axis columns of an estimate row that make up the map, by prefix
PREFIXES = ('pose_rad_', 'resonance_hz_', 'antiresonance_hz_')


def write_frf_map(res: CampaignResult) -> list[Path]:
    """
    Write frf_map.csv and frf_map.png of an estimate campaign; nothing without modes.

    Parameters
    ----------
    res : CampaignResult
        The campaign (rows with ``resonance_hz_J`` columns).

    Returns
    -------
    list of Path
        The files written (empty when no bag gave resonances).

    """
    from frf_ident.report.frf_map_figure import frf_map_figure
    rows = [r for r in res.rows if r.ok and any(k.startswith('resonance_hz_') for k in r.columns)]
    if not rows:
        return []
    cols = []
    for r in rows:
        cols += [k for k in r.columns if k.startswith(PREFIXES) and k not in cols]
    cols.sort(key=lambda k: [k.startswith(p) for p in PREFIXES].index(True))
    with open(res.out / MAP_FILES[0], 'w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(['bag'] + cols)
        for r in rows:
            w.writerow([r.out] + [r.columns.get(k, '') for k in cols])
    joints = [k[len('resonance_hz_'):] for k in cols if k.startswith('resonance_hz_')]
    labels = [r.out + ''.join(f'\n{r.columns[k]:+.2f}' for k in cols
                              if k.startswith('pose_rad_') and k in r.columns) for r in rows]
    freqs = {j: ([r.columns.get(f'resonance_hz_{j}') for r in rows],
                 [r.columns.get(f'antiresonance_hz_{j}') for r in rows]) for j in joints}
    frf_map_figure(labels, freqs, res.out / MAP_FILES[1])
    return [res.out / n for n in MAP_FILES]
