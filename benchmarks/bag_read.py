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
Read benchmark: frf_ident's streaming reader vs a plain rosbags AnyReader loop.

``bench_read(path)`` reads the same bag twice each way: once timed (no tracing), once under
``tracemalloc`` for the peak Python heap. The rosbags baseline deserialises every JointState
on the joint-state topic and keeps nothing, so it is a lower bound for any rosbags-based
reader (which would still have to copy the values somewhere).

``python -m benchmarks.bag_read [BAG]`` prints the result as JSON (without BAG a synthetic
60 s, 6-joint, 1 kHz bag is written to a temporary directory first).
"""
from __future__ import annotations

import json
from pathlib import Path
import sys
import tempfile
import time
import tracemalloc
from typing import Any, Callable

from frf_ident.bag import bag_info, read_recording
from frf_ident.bag.topics import BagTopics
import numpy as np


def _rosbags_loop(path: Path, topic: str) -> int:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import get_typestore, Stores

    n = 0
    paths = [path if path.is_dir() else path]
    with AnyReader(paths, default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        for conn, _, raw in reader.messages(connections=conns):
            reader.deserialize(raw, conn.msgtype)
            n += 1
    return n


def measure(fn: Callable[[], Any]) -> tuple[float, int]:
    """(seconds, peak traced bytes) of fn(), timed and traced in separate runs."""
    t0 = time.perf_counter()
    fn()
    seconds = time.perf_counter() - t0
    tracemalloc.start()
    try:
        fn()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return seconds, peak


def bench_read(path: str | Path, *, topics: BagTopics | None = None) -> dict[str, Any]:
    """Measure JointState msgs/s and peak memory: ``read_recording`` vs rosbags ``AnyReader``."""
    topics = topics or BagTopics()
    path = Path(path)
    counts = {t['name']: t['count'] for t in bag_info(path)['topics']}
    n_js = int(counts.get(topics.joint_states, 0))
    ours_s, ours_peak = measure(lambda: read_recording(path, topics=topics))
    rb_s, rb_peak = measure(lambda: _rosbags_loop(path, topics.joint_states))
    size = sum(f.stat().st_size for f in ([path] if path.is_file() else path.glob('*.mcap')))
    return {
        'bag': str(path), 'bag_bytes': int(size), 'joint_state_messages': n_js,
        'messages_total': int(sum(counts.values())),
        'frf_ident': {'seconds': ours_s, 'joint_states_per_s': n_js / ours_s,
                      'peak_bytes': int(ours_peak)},
        'rosbags_anyreader': {'seconds': rb_s, 'joint_states_per_s': n_js / rb_s,
                              'peak_bytes': int(rb_peak)},
        'speedup': rb_s / ours_s,
    }


def synthetic_bag(path: Path, seconds: float = 60.0, n_joints: int = 6,
                  fs: float = 1000.0) -> Path:
    """Write a simulated run (sines on every topic) for benchmarking."""
    from frf_ident.bag.writer import write_recording
    from frf_ident.core.recording import Recording, Segment

    t = np.arange(int(seconds * fs)) / fs
    w = 2 * np.pi * np.linspace(0.5, 3.0, n_joints)
    vel = np.cos(np.outer(t, w))
    rec = Recording(t, [f'joint_{i + 1}' for i in range(n_joints)], np.sin(np.outer(t, w)),
                    vel, 2 * vel, vel, 0.1 * vel, [Segment(1.0, seconds - 1.0, {'design': 'x'})])
    return write_recording(rec, path)


def main(argv: list[str] | None = None) -> int:
    """CLI: print bench_read of BAG (or of a synthetic bag) as JSON."""
    argv = sys.argv[1:] if argv is None else argv
    if argv:
        print(json.dumps(bench_read(argv[0]), indent=2))
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        bag = synthetic_bag(Path(tmp) / 'bench')
        print(json.dumps(bench_read(bag), indent=2))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
