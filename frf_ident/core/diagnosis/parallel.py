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
Run independent parts of the diagnosis in parallel processes.

The diagnosis simulates many models on one recording; the candidates of one round, the
starting simplex of a joint refit and the FRF-shape candidates of different axes do not depend
on each other. :func:`fork_map` runs such parts on worker processes of the standard library
(:mod:`concurrent.futures`), forked so they inherit the recording and the search state instead
of receiving them: only an index goes out and the part's result comes back.
:class:`WorkerPool` keeps its workers for the many small batches of one search (the
evaluator's models of a round, a Nelder-Mead step's reflection and guess): forked once, so a
batch costs the models sent and the results returned, not a fork of the whole diagnosing
process. The simulation is deterministic (fixed seed, noise-free model), so the results are
those of running the parts one after the other.
"""
from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
import multiprocessing
from typing import Any, Callable, Sequence, TypeVar

__all__ = ['can_fork', 'fork_map', 'WorkerPool']

T = TypeVar('T')

#: (function, items) the forked workers run; set only while a pool runs
_JOB: tuple[Callable[[Any], Any], Sequence[Any]] | None = None
#: the function a :class:`WorkerPool`'s worker runs (set in the worker when it starts)
_POOL_FN: Callable[[Any], Any] | None = None


def can_fork() -> bool:
    """Return whether worker processes can be forked here (POSIX; not on Windows)."""
    return 'fork' in multiprocessing.get_all_start_methods()


def _run_item(k: int) -> Any:
    """Run the inherited function on the inherited item k (in a forked worker)."""
    assert _JOB is not None, 'fork_map sets the job before the workers fork'
    return _JOB[0](_JOB[1][k])


def fork_map(fn: Callable[[Any], T], items: Sequence[Any], jobs: int) -> list[T]:
    """
    Return ``[fn(x) for x in items]``, computed on ``jobs`` forked worker processes.

    ``fn`` may be a closure over large state (the workers inherit it); its results travel
    back pickled, and what it changes in its own process stays there.

    Parameters
    ----------
    fn : callable
        The part, a function of one item.
    items : sequence
        The items.
    jobs : int
        Worker processes; 1, one item, or no fork here: one after the other in this process.

    Returns
    -------
    list
        The results, in the order of ``items``.

    """
    global _JOB
    if jobs < 2 or len(items) < 2 or not can_fork():
        return [fn(x) for x in items]
    _JOB = (fn, items)
    try:
        with ProcessPoolExecutor(min(jobs, len(items)),
                                 mp_context=multiprocessing.get_context('fork')) as pool:
            return list(pool.map(_run_item, range(len(items))))
    finally:
        _JOB = None


def _set_pool_fn(fn: Callable[[Any], Any]) -> None:
    """Keep the pool's function in a worker (forked: the closure is inherited, not pickled)."""
    global _POOL_FN
    _POOL_FN = fn


def _run_pooled(item: Any) -> Any:
    assert _POOL_FN is not None, 'the worker initialiser sets the function'
    return _POOL_FN(item)


class WorkerPool:
    """
    Worker processes, forked once, that apply one function to the items sent to them.

    ``fn`` may be a closure over large state: the workers inherit it when they are forked
    (at the first :meth:`run` of two or more items); items and results travel pickled. What
    the caller changes after that is not seen by the workers, so ``fn`` must depend only on
    its item and on state that stays fixed. Close the pool with :meth:`close` (or use it as a
    context manager).

    Parameters
    ----------
    fn : callable
        The function of one item.
    jobs : int
        Worker processes; 1 or no fork here: :meth:`run` runs in this process.

    """

    def __init__(self, fn: Callable[[Any], T], jobs: int) -> None:
        self.fn, self.jobs = fn, jobs
        self._pool: ProcessPoolExecutor | None = None

    def run(self, items: Sequence[Any]) -> list[Any]:
        """Return ``[fn(x) for x in items]``, on the workers where there are two or more."""
        if self.jobs < 2 or len(items) < 2 or not can_fork():
            return [self.fn(x) for x in items]
        if self._pool is None:
            self._pool = ProcessPoolExecutor(self.jobs,
                                             mp_context=multiprocessing.get_context('fork'),
                                             initializer=_set_pool_fn, initargs=(self.fn,))
        return list(self._pool.map(_run_pooled, items))

    def close(self) -> None:
        """Stop the workers (a later :meth:`run` forks new ones)."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
