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
Campaigns: one application function mapped over many inputs, in parallel, with one summary.

A *task* is any picklable callable ``task(input_path, out_dir, progress) -> dict`` (a
module-level function, or a :func:`functools.partial` of one) that writes its outputs into
``out_dir`` and returns a few scalar columns for the summary table (the same keys for every
input of one command). :func:`run_campaign` runs it once per input:

- ``jobs=1``: in this process, one input after the other (the serial reference);
- ``jobs=N``: on N worker processes of the standard library (:mod:`concurrent.futures`,
  forked while the caller runs one thread, else spawned:
  :func:`~frf_ident.app.campaign_executors.worker_start_method`);
- ``scheduler='local'``: on a Dask ``LocalCluster`` of N single-threaded worker processes
  bound to 127.0.0.1; ``scheduler='tcp://host:8786'``: on that Dask cluster (the inputs and
  ``out`` must be on a file system the workers see under the same paths).

Each input runs alone in a worker with the same code and data, so every route writes the same
files bit for bit. A worker returns only its
:class:`~frf_ident.app.campaign_summary.CampaignRow` (a few numbers), never
arrays, so the caller's memory does not grow with the number of inputs. An input that fails
(bad bag, nothing to estimate, a bug) is reported in its row; the others go on. Each input's
progress lines go to ``out_dir/log.txt`` (parallel workers would interleave on a terminal);
the caller sees one line per finished input and a progress bar.

The parts: :mod:`frf_ident.app.campaign_inputs` (inputs expanded, output folder names),
:mod:`frf_ident.app.campaign_executors` (the routes, one input in a worker) and
:mod:`frf_ident.app.campaign_summary` (rows, result, summary.csv/json); this module runs a
campaign over them.
"""
from __future__ import annotations

import os
from pathlib import Path
import time
from typing import Callable, Sequence

from frf_ident.app.campaign_executors import executor, run_one
from frf_ident.app.campaign_inputs import campaign_dirs
from frf_ident.app.campaign_summary import (CampaignResult, CampaignRow, summary_columns,
                                            summary_record, write_summary)
from frf_ident.app.outdir import check_out
from frf_ident.core.progress import Progress, sink
from frf_ident.errors import FrfIdentInputError

__all__ = ['CAMPAIGN_FILES', 'run_campaign']


#: the files :func:`run_campaign` writes into ``out`` itself (each input has its own folder)
CAMPAIGN_FILES = ('summary.csv', 'summary.json', 'index.html')


def _row_line(r: CampaignRow) -> str:
    if r.ok:
        cols = ', '.join(f'{k} {v}' for k, v in r.columns.items())
        return f'{r.out}: ok in {r.seconds:.1f} s ({cols})'
    return f'{r.out}: {r.status.upper()} in {r.seconds:.1f} s: {r.error}'


def run_campaign(task: Callable[..., dict], inputs: Sequence[Path], out: str | os.PathLike,
                 *, outputs: Sequence[str], root_outputs: Sequence[str] = (),
                 overwrite: bool = False, jobs: int | None = None,
                 scheduler: str | None = None, title: str = 'campaign',
                 progress: Progress | None = None, bar: bool | None = None
                 ) -> CampaignResult:
    """
    Run ``task`` on every input into ``out/<name>/`` and write the summary table.

    Parameters
    ----------
    task : callable
        Picklable ``task(input_path, out_dir, progress) -> dict`` (see the module text).
    inputs : sequence of Path
        The inputs (:func:`~frf_ident.app.campaign_inputs.expand_inputs`).
    out : str or path-like
        The campaign folder: summary.csv, summary.json, index.html and one folder per input
        (:func:`~frf_ident.app.campaign_inputs.campaign_dirs`).
    outputs : sequence of str
        The files ``task`` writes into an input's folder: every folder is checked before any
        work (:func:`~frf_ident.app.outdir.check_out`).
    root_outputs : sequence of str
        Further files the caller writes into ``out`` afterwards (checked with
        :data:`CAMPAIGN_FILES`).
    overwrite : bool
        Replace the outputs of an earlier run (``--overwrite``).
    jobs : int, optional
        Worker processes (>= 1); default all cores (:func:`os.cpu_count`). 1: serial, in
        this process.
    scheduler : str, optional
        ``'local'`` or a Dask scheduler address: run on Dask instead (``jobs`` workers for
        ``'local'``).
    title : str
        Heading of index.html (the command).
    progress : callable
        Called with one line per finished input and the route.
    bar : bool, optional
        Show a tqdm bar over inputs; None: only on a terminal.

    Returns
    -------
    CampaignResult
        One row per input in input order.

    Raises
    ------
    FrfIdentInputError
        ``jobs`` < 1, ``out`` or an input's folder is unusable or holds an earlier run
        without ``overwrite``, Dask missing or its scheduler not answering.

    """
    from tqdm import tqdm

    from frf_ident.report.campaign_page import write_campaign_page
    jobs = (os.cpu_count() or 1) if jobs is None else jobs
    if jobs < 1:
        raise FrfIdentInputError(f'--jobs {jobs}: expected a number of workers >= 1')
    root = check_out(out, outputs=CAMPAIGN_FILES + tuple(root_outputs), overwrite=overwrite)
    names = campaign_dirs(inputs)
    for n in names:
        check_out(root / n, outputs=outputs, overwrite=overwrite)
    progress = sink(progress)
    t0 = time.perf_counter()
    ex = executor(min(jobs, max(len(inputs), 1)) if not scheduler else jobs, scheduler)
    progress(f'{len(inputs)} inputs on {ex.route} into {root}')
    rows: list[CampaignRow | None] = [None] * len(inputs)
    try:
        futs = {ex.submit(run_one, task, str(p), str(root / n), n): k
                for k, (p, n) in enumerate(zip(inputs, names))}
        with tqdm(total=len(inputs), unit='input', disable=None if bar is None else not bar,
                  leave=False) as pb:
            for f in ex.as_completed(list(futs)):
                r = f.result()
                rows[futs[f]] = r
                (progress if pb.disable else pb.write)(_row_line(r))
                pb.update(1)
    finally:
        ex.close()
    res = CampaignResult(rows=[r for r in rows if r is not None], out=root, route=ex.route,
                         seconds=round(time.perf_counter() - t0, 2))
    write_summary(res, title=title)
    write_campaign_page(root / 'index.html', title=title, columns=summary_columns(res.rows),
                        rows=[summary_record(r) for r in res.rows], route=res.route,
                        seconds=res.seconds)
    n_bad = res.n_failed
    progress(f'{len(res.rows) - n_bad} of {len(res.rows)} inputs ok'
             + (f', {n_bad} not (see their rows)' if n_bad else '')
             + f' in {res.seconds:.1f} s; wrote {root / "summary.csv"}, summary.json, index.html')
    return res
