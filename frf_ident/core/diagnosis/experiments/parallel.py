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
starting simplex of a joint refit and a Nelder-Mead step's trial points do not depend on each
other. :class:`WorkerPool` runs such models on worker processes of the standard library
(:mod:`concurrent.futures`), forked once per diagnosis so they inherit the recording instead of
receiving it: a batch (the evaluator's models of a round, a Nelder-Mead step's reflection and
guess) costs the models sent and the results returned, not a fork of the whole diagnosing
process. Its results' large arrays (a simulation's signals, 25 MB on the demo bag) come back
through memory the workers share with the caller instead of a pipe, where pickling and
copying them cost about as much as simulating. The simulation is deterministic
(fixed seed, noise-free model), so the results are those of running the parts one after the
other.
"""
from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
import mmap
import multiprocessing
from typing import Any, Callable, Sequence, TypeVar

import numpy as np

__all__ = ['can_fork', 'WorkerPool']

T = TypeVar('T')

#: the function a :class:`WorkerPool`'s worker runs and the memory it shares with the caller
#: (set in the worker when it starts)
_POOL_FN: Callable[[Any], Any] | None = None
_POOL_SHARED: tuple[mmap.mmap, int] | None = None
#: arrays smaller than this travel pickled (the copy through shared memory is not worth it)
_SHARED_MIN_BYTES = 1 << 16


def can_fork() -> bool:
    """Return whether worker processes can be forked here (POSIX; not on Windows)."""
    return 'fork' in multiprocessing.get_all_start_methods()


@dataclass(frozen=True)
class _InShared:
    """Where a worker left an array of its result in the shared memory."""

    offset: int
    shape: tuple[int, ...]
    dtype: str


def _set_pool_fn(fn: Callable[[Any], Any], shared: tuple[mmap.mmap, int] | None) -> None:
    """Keep the pool's function in a worker (forked: the closure is inherited, not pickled)."""
    global _POOL_FN, _POOL_SHARED
    _POOL_FN, _POOL_SHARED = fn, shared


def _run_pooled(job: tuple[int, Any]) -> Any:
    """Run the pool's function on item ``job[1]``, its large arrays left in slot ``job[0]``."""
    assert _POOL_FN is not None, 'the worker initialiser sets the function'
    k, item = job
    out = _POOL_FN(item)
    if _POOL_SHARED is None or k < 0 or not isinstance(out, tuple):
        return out
    buf, size = _POOL_SHARED
    pos, end = k * size, (k + 1) * size
    placed = []
    for x in out:
        if (isinstance(x, np.ndarray) and x.nbytes >= _SHARED_MIN_BYTES
                and pos + x.nbytes <= end):
            np.frombuffer(buf, x.dtype, x.size, pos).reshape(x.shape)[...] = x
            placed.append(_InShared(pos, x.shape, x.dtype.str))
            pos += -(-x.nbytes // 64) * 64
        else:
            placed.append(x)
    return tuple(placed)


class WorkerPool:
    """
    Worker processes, forked once, that apply one function to the items sent to them.

    ``fn`` may be a closure over large state: the workers inherit it when they are forked
    (at the first :meth:`run` of two or more items); items and results travel pickled. What
    the caller changes after that is not seen by the workers, so ``fn`` must depend only on
    its item and on state that stays fixed. Close the pool with :meth:`close` (or use it as a
    context manager).

    Where ``fn`` returns a tuple, its large arrays come back through memory shared with the
    workers when ``shared_bytes`` is given: each item of a :meth:`run` has that many bytes of
    it (an array that does not fit travels pickled), and the caller gets copies.

    Parameters
    ----------
    fn : callable
        The function of one item.
    jobs : int
        Worker processes; 1 or no fork here: :meth:`run` runs in this process.
    shared_bytes : int
        Bytes of shared memory per item for the arrays of a result (0: none).
    max_items : int
        Most items of one :meth:`run` whose arrays come back through the shared memory (the
        rest are pickled).

    """

    def __init__(self, fn: Callable[[Any], T], jobs: int, *, shared_bytes: int = 0,
                 max_items: int = 0) -> None:
        self.fn, self.jobs = fn, jobs
        self._pool: ProcessPoolExecutor | None = None
        self._size = -(-shared_bytes // mmap.PAGESIZE) * mmap.PAGESIZE
        self._slots = max_items if self._size else 0
        self._shared: mmap.mmap | None = None

    def run(self, items: Sequence[Any]) -> list[Any]:
        """Return ``[fn(x) for x in items]``, on the workers where there are two or more."""
        if self.jobs < 2 or len(items) < 2 or not can_fork():
            return [self.fn(x) for x in items]
        if self._pool is None:
            if self._slots and self._shared is None:
                # anonymous and shared: the workers forked below write into the caller's pages
                self._shared = mmap.mmap(-1, self._size * self._slots)
            shared = (self._shared, self._size) if self._shared is not None else None
            self._pool = ProcessPoolExecutor(self.jobs,
                                             mp_context=multiprocessing.get_context('fork'),
                                             initializer=_set_pool_fn,
                                             initargs=(self.fn, shared))
        jobs = [(k if k < self._slots else -1, x) for k, x in enumerate(items)]
        return [self._collect(r) for r in self._pool.map(_run_pooled, jobs)]

    def _collect(self, out: Any) -> Any:
        """Return a result with its arrays copied out of the shared memory."""
        if not isinstance(out, tuple) or self._shared is None:
            return out
        return tuple(np.frombuffer(self._shared, np.dtype(x.dtype), int(np.prod(x.shape)),
                                   x.offset).reshape(x.shape).copy()
                     if isinstance(x, _InShared) else x for x in out)

    def close(self) -> None:
        """Stop the workers (a later :meth:`run` forks new ones)."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None
        if self._shared is not None:
            self._shared.close()
            self._shared = None

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
