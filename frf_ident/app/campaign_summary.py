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
What a campaign gives: its rows, its result, and the summary table written from them.

One :class:`CampaignRow` per input, the :class:`CampaignResult` holding them, summary.csv and
summary.json (:func:`write_summary`).
"""
from __future__ import annotations

import csv
from dataclasses import asdict, dataclass, field
import json
from pathlib import Path
from typing import Any, Sequence

__all__ = ['CampaignResult', 'CampaignRow', 'FAILED', 'OK', 'REFUSED', 'summary_columns',
           'summary_record', 'write_summary']

#: row status of an input whose task returned / raised an input error / raised anything else
OK, REFUSED, FAILED = 'ok', 'refused', 'failed'


@dataclass(frozen=True)
class CampaignRow:
    """
    What one input of a campaign gave: its status and a few columns, never arrays.

    Attributes
    ----------
    source : str
        The input path as expanded.
    out : str
        Its output folder, relative to the campaign's ``out``.
    status : str
        ``ok``, ``refused`` (an input error: the message says what to fix) or ``failed``.
    seconds : float
        Wall time of the task [s].
    cpu_seconds : float
        CPU time of the task in its process [s] (wall time on a loaded machine says little).
    worker : str
        ``host:pid`` of the process that ran it.
    peak_rss_mb : float
        Peak resident memory of the process that ran it [MiB] (the whole worker, so the
        largest input it has run so far).
    error : str
        One line (empty when ok).
    columns : dict
        The task's summary columns (scalars; empty when not ok).

    """

    source: str
    out: str
    status: str
    seconds: float
    cpu_seconds: float
    worker: str
    peak_rss_mb: float
    error: str = ''
    columns: dict[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Whether the task succeeded."""
        return self.status == OK


@dataclass(frozen=True)
class CampaignResult:
    """
    Rows of a campaign in input order, and where the summary went.

    Attributes
    ----------
    rows : list of CampaignRow
        One per input, in the order of the inputs.
    out : Path
        The campaign folder holding summary.csv, summary.json, index.html.
    route : str
        How it ran: ``serial``, ``processes=N``, ``dask local=N`` or ``dask ADDRESS``.
    seconds : float
        Wall time of the whole campaign [s].

    """

    rows: list[CampaignRow]
    out: Path
    route: str
    seconds: float

    @property
    def n_failed(self) -> int:
        """Return the number of inputs that did not succeed."""
        return sum(not r.ok for r in self.rows)


def summary_columns(rows: Sequence[CampaignRow]) -> list[str]:
    """
    Return the summary table's columns: the fixed ones, then the tasks' columns in order.

    Parameters
    ----------
    rows : sequence of CampaignRow
        The campaign's rows.

    Returns
    -------
    list of str
        source, out, status, seconds, cpu_seconds, worker, peak_rss_mb, error, then every
        task column once.

    """
    cols = ['source', 'out', 'status', 'seconds', 'cpu_seconds', 'worker', 'peak_rss_mb',
            'error']
    for r in rows:
        cols += [c for c in r.columns if c not in cols]
    return cols


def summary_record(r: CampaignRow) -> dict[str, Any]:
    """
    Return one row as a flat record (fixed fields, then the task's columns).

    Parameters
    ----------
    r : CampaignRow
        The row.

    Returns
    -------
    dict
        Column -> value.

    """
    d = asdict(r)
    cols = d.pop('columns')
    return {**d, **cols}


def write_summary(res: CampaignResult, *, title: str) -> None:
    """
    Write ``summary.csv`` and ``summary.json`` of a campaign into its folder.

    Parameters
    ----------
    res : CampaignResult
        The campaign.
    title : str
        The command, recorded in summary.json.

    """
    cols = summary_columns(res.rows)
    with open(res.out / 'summary.csv', 'w', newline='') as fh:
        w = csv.DictWriter(fh, fieldnames=cols, restval='')
        w.writeheader()
        for r in res.rows:
            w.writerow(summary_record(r))
    doc = {'command': title, 'route': res.route, 'seconds': res.seconds,
           'n_inputs': len(res.rows), 'n_failed': res.n_failed,
           'rows': [summary_record(r) for r in res.rows]}
    (res.out / 'summary.json').write_text(json.dumps(doc, indent=1))
