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
Longer run of the bag-imperfection property (test/bag/test_replay_properties.py).

``make bench`` section 'replay': ``EXAMPLES`` random examples (jitter, drops, bursts,
duplicates, reordering, partial periods, a period that is not a whole number of samples,
truncated last chunk, in memory or streamed). Every example must exit 0 with the driven
channel's FRF within the test's TOL_DB (0.05 dB) median of the exact FRF, or exit 2 with one
line, and a whole-sample period in an intact file without bursts must be estimated; the rows
give how many did which and the most frequent refusals.

``python -m benchmarks.replay_properties [N]`` runs N examples on its own.
"""
from __future__ import annotations

import collections
from pathlib import Path
import sys
import time

__all__ = ['EXAMPLES', 'bench_replay', 'run_examples']

EXAMPLES = 100


def run_examples(n: int = EXAMPLES) -> dict:
    """Run ``n`` hypothesis examples of the property; returns counts, worst error, time."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'test' / 'bag'))
    from hypothesis import given, HealthCheck, settings
    from hypothesis import strategies as st
    import test_replay_properties as prop  # noqa: I100 (test module, path set above)

    counts: collections.Counter = collections.Counter()
    refusals: collections.Counter = collections.Counter()

    @settings(max_examples=n, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(imp=prop.imperfections(), kind=st.sampled_from(['whole', 'fractional']),
           truncate=st.sampled_from([0, 0, 3000, 20000]), stream=st.booleans(),
           seed=st.integers(0, 2 ** 16))
    def examples(imp, kind, truncate, stream, seed):
        result = prop.check_one(imp, kind, truncate, stream, seed)
        if kind == 'whole' and not truncate and not imp.bursts:
            assert result == 'ok', (result, imp)
        counts[(kind, 'ok' if result == 'ok' else 'refused')] += 1
        if result != 'ok':
            reason = result.split('/bag: ', 1)[-1]
            for tag in ('not a whole number', 'without missing samples remain',
                        'no multisine or chirp found', 'whole steady-state period'):
                if tag in reason:
                    reason = tag
                    break
            refusals[f'{kind}: {reason[:60]}'] += 1

    t0 = time.perf_counter()
    examples()
    n = sum(counts.values())
    return {'n': n, 'counts': dict(counts), 'refusals': refusals.most_common(4),
            'ok': sum(v for (_, r), v in counts.items() if r == 'ok'),
            'refused': sum(v for (_, r), v in counts.items() if r == 'refused'),
            'seconds': time.perf_counter() - t0}


def bench_replay() -> list[tuple[str, str, str, str]]:
    """Rows for ``python -m benchmarks``."""
    r = run_examples()
    c = r['counts']
    rows = [(f"bag imperfections ({r['n']} hypothesis examples)",
             f"{r['ok']} estimated, {r['refused']} refused", 'never exit 1 / traceback',
             f"{r['seconds'] / max(r['n'], 1):.1f} s/example")]
    for kind in ('whole', 'fractional'):
        rows.append((f'  {kind}-sample period: estimated / refused',
                     f"{c.get((kind, 'ok'), 0)} / {c.get((kind, 'refused'), 0)}", '', ''))
    rows += [(f'  refused: {why[:44]}', f'{k}x', '', '') for why, k in r['refusals']]
    return rows


if __name__ == '__main__':
    res = run_examples(int(sys.argv[1]) if len(sys.argv) > 1 else EXAMPLES)
    print(res)
