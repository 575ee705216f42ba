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
The abort ramp's wall time on a loaded PC: its paced steps against sleeps one after another.

``python -m benchmarks.abort_ramp [BUSY] [N]`` runs BUSY (default 3) busy processes beside
N (default 300) ramps of 10 steps at 1 kHz (the excitation node's ``abort_ramp_s`` 0.01 s)
and prints the median and 99th percentile of the time from the first step to the last, for
frf_ident.app.excitation_watch.paced and for the baseline of 9 sleeps of 1 ms in a row (the
ramp before stop 65).
"""
from __future__ import annotations

import multiprocessing as mp
import sys
import time

from frf_ident.app.excitation_watch import paced
import numpy as np

STEPS, PERIOD = 10, 0.001


def _busy(until: float) -> None:
    while time.monotonic() < until:
        pass


def _in_a_row() -> float:
    t0 = time.monotonic()
    for s in range(1, STEPS):
        time.sleep(PERIOD)
    return time.monotonic() - t0


def _paced() -> float:
    t0 = time.monotonic()
    for _ in paced(STEPS, PERIOD):
        pass
    return time.monotonic() - t0


def main(argv: list[str]) -> None:
    busy = int(argv[0]) if argv else 3
    n = int(argv[1]) if len(argv) > 1 else 300
    procs = [mp.Process(target=_busy, args=(time.monotonic() + 60.0,)) for _ in range(busy)]
    for p in procs:
        p.start()
    try:
        for name, f in (('paced (frf_ident)', _paced), ('in a row (baseline)', _in_a_row)):
            t = 1e3 * np.array([f() for _ in range(n)])
            print(f'{name}: median {np.median(t):.2f} ms, 99th percentile '
                  f'{np.percentile(t, 99):.2f} ms, max {t.max():.2f} ms ({busy} busy processes)')
    finally:
        for p in procs:
            p.terminate()
            p.join()


if __name__ == '__main__':
    main(sys.argv[1:])
