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
One BLAS thread per process, for commands that fork simulation workers.

The diagnosis' matrices are small; a multi-threaded OpenBLAS in the diagnosing process and in
each worker it forks spins on the cores the others simulate on, and even a single process
then burns a second core: `python -m benchmarks diagnosis_demo` prints the CPU time beside the
wall time of a one-process diagnosis, equal with one thread.
"""
from __future__ import annotations

import contextlib
from typing import Iterator

from threadpoolctl import threadpool_limits

__all__ = ['one_blas_thread']


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """
    Limit every BLAS library to one thread while the block (or decorated function) runs.

    threadpoolctl changes the libraries loaded when the block starts, so numpy's and scipy's
    (two separate OpenBLAS builds in the wheels) are loaded first.
    """
    import numpy  # noqa: F401
    import scipy.linalg  # noqa: F401
    with threadpool_limits(limits=1, user_api='blas'):
        yield
