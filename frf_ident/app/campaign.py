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
  forked while the caller runs one thread, else spawned: :func:`worker_start_method`);
- ``scheduler='local'``: on a Dask ``LocalCluster`` of N single-threaded worker processes
  bound to 127.0.0.1; ``scheduler='tcp://host:8786'``: on that Dask cluster (the inputs and
  ``out`` must be on a file system the workers see under the same paths).

Each input runs alone in a worker with the same code and data, so every route writes the same
files bit for bit. A worker returns only its :class:`CampaignRow` (a few numbers), never
arrays, so the caller's memory does not grow with the number of inputs. An input that fails
(bad bag, nothing to estimate, a bug) is reported in its row; the others go on. Each input's
progress lines go to ``out_dir/log.txt`` (parallel workers would interleave on a terminal);
the caller sees one line per finished input and a progress bar.
"""
from __future__ import annotations

from concurrent.futures import as_completed, Future, ProcessPoolExecutor
import csv
from dataclasses import asdict, dataclass, field
import glob
import json
import multiprocessing
import os
from pathlib import Path
import resource
import socket
import threading
import time
import traceback
from typing import Any, Callable, Sequence

from frf_ident.app.outdir import check_out
from frf_ident.core.progress import Progress, sink
from frf_ident.errors import FrfIdentInputError

__all__ = ['CAMPAIGN_FILES', 'CampaignResult', 'CampaignRow', 'LOCAL_SCHEDULER',
           'campaign_dirs', 'expand_inputs', 'is_bag_dir', 'is_campaign', 'run_campaign',
           'worker_start_method']

#: the files :func:`run_campaign` writes into ``out`` itself (each input has its own folder)
CAMPAIGN_FILES = ('summary.csv', 'summary.json', 'index.html')

#: ``--scheduler`` value that starts a Dask LocalCluster on loopback instead of connecting
LOCAL_SCHEDULER = 'local'

#: name of each input's progress log inside its output folder
LOG_NAME = 'log.txt'

#: row status of an input whose task returned / raised an input error / raised anything else
OK, REFUSED, FAILED = 'ok', 'refused', 'failed'

#: suffixes of single-file inputs a folder is searched for (besides bag directories)
FILE_SUFFIXES = ('.mcap', '.csv', '.mat')


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


def is_campaign(specs: Sequence[str | os.PathLike[str]],
                member: Callable[[Path], bool] | None = None) -> bool:
    """
    Return whether the inputs name a campaign rather than one input.

    Several inputs, an ``@list.txt``, a glob pattern or a folder holding bags (but not a bag
    itself) is a campaign. Anything else alone (a bag, a file, a path that does not exist
    or a folder without bags) is one input: the command keeps its single-input behaviour
    and its messages (outputs directly in ``--out``).

    Parameters
    ----------
    specs : sequence of str or path-like
        The positional inputs as given.
    member : callable, optional
        For inputs that are folders of another kind (``fit``: estimate output folders):
        whether a path is one input. A folder that is one is one input; a folder holding
        some is a campaign. Default: bags and data files as above.

    Returns
    -------
    bool
        True for a campaign.

    """
    if len(specs) != 1:
        return True
    text = os.fspath(specs[0])
    if text.startswith('@') or glob.has_magic(text):
        return True
    p = Path(text)
    if member is not None:
        return p.is_dir() and not member(p) and any(member(q) for q in p.iterdir())
    return p.is_dir() and not is_bag_dir(p) and any(_is_input(q) for q in p.iterdir())


def is_bag_dir(p: Path) -> bool:
    """
    Return whether the folder ``p`` is one bag: it has metadata.yaml or MCAP files of its own.

    A rosbag2 folder whose metadata.yaml was lost (a recorder killed) still holds its split
    .mcap files, and the bag reader reads them in order as one bag: such a folder is one
    input, never a campaign of its files.
    """
    return (p / 'metadata.yaml').is_file() or any(p.glob('*.mcap'))


def _is_input(p: Path) -> bool:
    return (p / 'metadata.yaml').is_file() or (p.is_file() and p.suffix in FILE_SUFFIXES)


def _expand_one(spec: str, member: Callable[[Path], bool] | None = None) -> list[Path]:
    if spec.startswith('@'):
        lst = Path(spec[1:])
        try:
            lines = lst.read_text().splitlines()
        except OSError as err:
            raise FrfIdentInputError(f'{spec}: cannot read the list file ({err.strerror}); '
                                     f'expected one input path per line') from err
        # relative entries are relative to the list file, so a list travels with its bags
        return [q for s in lines if s.strip() and not s.lstrip().startswith('#')
                for q in _expand_one(str(lst.parent / s.strip()), member)]
    if glob.has_magic(spec):
        hits = sorted(Path(h) for h in glob.glob(spec))
        if not hits:
            raise FrfIdentInputError(f'{spec}: the pattern matches nothing; expected bags')
        return hits
    p = Path(spec)
    if not p.exists():
        raise FrfIdentInputError(f'{spec}: no such bag, file or folder')
    if member is not None and p.is_dir():
        if member(p):
            return [p]
        found = sorted(q for q in p.iterdir() if member(q))
        if not found:
            what = (member.__doc__ or member.__name__).strip().splitlines()[0]
            raise FrfIdentInputError(f'{spec}: a folder without inputs (none of its entries '
                                     f'passes {member.__name__}: {what})')
        return found
    if p.is_dir() and not (p / 'metadata.yaml').is_file():
        found = sorted(q for q in p.iterdir() if _is_input(q))
        if not found:
            raise FrfIdentInputError(f'{spec}: a folder without bags (expected bag folders '
                                     f'with metadata.yaml or {", ".join(FILE_SUFFIXES)} files)')
        return found
    return [p]


def expand_inputs(specs: Sequence[str | os.PathLike[str]],
                  member: Callable[[Path], bool] | None = None) -> list[Path]:
    """
    Expand paths, folders of bags, globs and ``@list.txt`` files into input paths.

    Parameters
    ----------
    specs : sequence of str or path-like
        Each a bag or file, a folder holding bags (bag folders and .mcap/.csv/.mat files,
        sorted by name), a glob pattern (sorted), or ``@FILE``: a text file with one such
        entry per line (blank lines and ``#`` comments skipped; relative entries are taken
        relative to the list file).
    member : callable, optional
        Inputs of another kind (see :func:`is_campaign`): a folder is one input when
        ``member`` says so, else its entries that are; its docstring names them in errors.

    Returns
    -------
    list of Path
        The inputs in the order given, each once.

    Raises
    ------
    FrfIdentInputError
        An entry that does not exist, a pattern or folder that holds nothing, an unreadable
        list file (one line naming it).

    """
    seen: dict[Path, None] = {}
    for s in specs:
        for p in _expand_one(os.fspath(s), member):
            seen.setdefault(p, None)
    return list(seen)


def campaign_dirs(inputs: Sequence[Path]) -> list[str]:
    """
    Return one output folder name per input: its name without suffix, made unique.

    Parameters
    ----------
    inputs : sequence of Path
        The expanded inputs.

    Returns
    -------
    list of str
        ``bag_a``, ``bag_b``...; a name that repeats (bags of the same name in different
        folders) gets ``_2``, ``_3``... in input order.

    """
    names: list[str] = []
    used: set[str] = set()
    for p in inputs:
        base = p.name[:-len(p.suffix)] if p.suffix in FILE_SUFFIXES else p.name
        name, k = base or 'input', 1
        while name in used:
            k += 1
            name = f'{base}_{k}'
        used.add(name)
        names.append(name)
    return names


def _peak_rss_mb() -> float:
    # ru_maxrss is in KiB on Linux
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def run_one(task: Callable[..., dict], inp: str, out_dir: str, name: str) -> CampaignRow:
    """
    Run ``task`` on one input, catch what it raises, return its row (runs in the worker).

    Parameters
    ----------
    task : callable
        ``task(input_path, out_dir, progress) -> dict`` of scalar summary columns.
    inp : str
        The input path.
    out_dir : str
        Its output folder (created).
    name : str
        The folder's name relative to the campaign folder (for the row).

    Returns
    -------
    CampaignRow
        Status, time, memory, error line and the task's columns.

    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0, c0 = time.perf_counter(), time.process_time()
    with open(out / LOG_NAME, 'w') as log:
        def progress(line: str) -> None:
            log.write(line + '\n')
        try:
            cols = task(Path(inp), out, progress)
            status, error = OK, ''
        except FrfIdentInputError as exc:
            status, error, cols = REFUSED, str(exc), {}
        except Exception as exc:  # a failure of one input must not stop the others
            log.write(traceback.format_exc())
            status, error, cols = FAILED, f'{type(exc).__name__}: {exc}', {}
        log.write(f'{status} after {time.perf_counter() - t0:.2f} s\n')
    error = ' '.join(error.split())
    return CampaignRow(source=inp, out=name, status=status,
                       seconds=round(time.perf_counter() - t0, 3),
                       cpu_seconds=round(time.process_time() - c0, 3),
                       worker=f'{socket.gethostname()}:{os.getpid()}',
                       peak_rss_mb=round(_peak_rss_mb(), 1), error=error,
                       columns=dict(cols or {}))


class _Serial:
    """An executor that runs each call at once in this process (the serial reference)."""

    route = 'serial'

    def submit(self, fn, *args) -> Future:
        f: Future = Future()
        f.set_result(fn(*args))
        return f

    @staticmethod
    def as_completed(futures):
        return iter(futures)

    def close(self) -> None:
        pass


class _Processes:
    """Worker processes of the standard library (see :func:`worker_start_method`)."""

    def __init__(self, jobs: int) -> None:
        method = worker_start_method()
        self.route = f'processes={jobs} ({method})'
        self.pool = ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context(method))
        self.as_completed = as_completed

    def submit(self, fn, *args) -> Future:
        return self.pool.submit(fn, *args)

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


def worker_start_method() -> str:
    """
    Return how worker processes start: ``fork`` where it is safe, else ``spawn``.

    A forked worker inherits the modules the command already imported (numpy, scipy,
    matplotlib, frf_ident), which a spawned one imports again before its first input: on 2
    cores that start-up kept ``--jobs 2`` well below twice the serial speed (``python -m
    benchmarks campaign`` measures it beside the CPU-time bound). It is safe only while this
    process runs one
    thread (ProcessPoolExecutor forks every worker before it starts its own manager thread,
    and the progress bar starts later): a lock held by another thread would be copied
    locked. Where ``fork`` does not exist (Windows, macOS default) or other threads run, the
    workers are spawned. Either way they run the same code on the same data, so the outputs
    are the same bit for bit.

    Returns
    -------
    str
        'fork' or 'spawn'.

    """
    if 'fork' in multiprocessing.get_all_start_methods() and threading.active_count() == 1:
        return 'fork'
    return 'spawn'


class _Dask:
    """A Dask distributed client: a LocalCluster on 127.0.0.1 or a scheduler address."""

    def __init__(self, scheduler: str, jobs: int) -> None:
        try:
            from distributed import as_completed as dask_completed, Client, LocalCluster
        except ImportError as err:
            raise FrfIdentInputError(f'--scheduler {scheduler}: needs Dask (pip install '
                                     f'"frf_ident[cluster]": dask, distributed)') from err
        self.cluster = None
        if scheduler == LOCAL_SCHEDULER:
            # single-threaded worker processes on loopback, no dashboard: nothing leaves lo
            self.cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True,
                                        host='127.0.0.1', dashboard_address=None)
            self.route = f'dask local={jobs}'
            address = self.cluster.scheduler_address
        else:
            self.route = f'dask {scheduler}'
            address = scheduler
        try:
            self.client = Client(address, timeout='10s')
        except (OSError, TimeoutError) as err:
            self.close_cluster()
            raise FrfIdentInputError(f'--scheduler {scheduler}: no Dask scheduler answers '
                                     f'({err}); expected tcp://HOST:PORT or "local"') from err
        self.as_completed = dask_completed

    def submit(self, fn, *args):
        # pure=False: each input is its own task even when arguments repeat
        return self.client.submit(fn, *args, pure=False)

    def close_cluster(self) -> None:
        if self.cluster is not None:
            self.cluster.close()

    def close(self) -> None:
        self.client.close()
        self.close_cluster()


def _executor(jobs: int, scheduler: str | None):
    if scheduler:
        return _Dask(scheduler, jobs)
    return _Serial() if jobs == 1 else _Processes(jobs)


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
        The inputs (:func:`expand_inputs`).
    out : str or path-like
        The campaign folder: summary.csv, summary.json, index.html and one folder per input
        (:func:`campaign_dirs`).
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
    ex = _executor(min(jobs, max(len(inputs), 1)) if not scheduler else jobs, scheduler)
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
