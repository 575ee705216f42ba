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
Where a campaign's inputs run: serially, on worker processes or on Dask, one row per input.

:func:`run_one` runs the task on one input in the worker and returns its
:class:`~frf_ident.app.campaign_summary.CampaignRow`; :func:`executor` picks the route:
this process one input after the other (``jobs=1``), the standard library's worker processes
(forked while the caller runs one thread, else spawned: :func:`worker_start_method`), or a
Dask ``LocalCluster`` on 127.0.0.1 (``scheduler='local'``) or a Dask scheduler's address.
"""
from __future__ import annotations

from concurrent.futures import as_completed, Future, ProcessPoolExecutor
import multiprocessing
import os
from pathlib import Path
import resource
import socket
import threading
import time
import traceback
from typing import Callable

from frf_ident.app.campaign_summary import CampaignRow, FAILED, OK, REFUSED
from frf_ident.errors import FrfIdentInputError

__all__ = ['executor', 'LOCAL_SCHEDULER', 'LOG_NAME', 'run_one', 'worker_start_method']

#: ``--scheduler`` value that starts a Dask LocalCluster on loopback instead of connecting
LOCAL_SCHEDULER = 'local'

#: name of each input's progress log inside its output folder
LOG_NAME = 'log.txt'


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


def executor(jobs: int, scheduler: str | None):
    """
    Return the executor of a campaign's route.

    Parameters
    ----------
    jobs : int
        Worker processes (1: serially in this process); Dask ``'local'``: its workers.
    scheduler : str or None
        ``'local'`` or a Dask scheduler address; None: this machine's processes.

    Returns
    -------
    object
        With ``route`` (how it runs), ``submit(fn, *args)``, ``as_completed(futures)`` and
        ``close()``.

    """
    if scheduler:
        return _Dask(scheduler, jobs)
    return _Serial() if jobs == 1 else _Processes(jobs)
