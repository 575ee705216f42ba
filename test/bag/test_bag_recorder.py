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
"""BagRecorder: incremental recording that survives SIGKILL and closes cleanly on SIGTERM."""
from __future__ import annotations

import os
from pathlib import Path
import signal
import subprocess
import sys
import textwrap
import time

from frf_ident.bag import bag_info, BagRecorder, read_recording, reindex
from frf_ident.bag.cdr import JointStateEncoder
from frf_ident.errors import BagError
import numpy as np
import pytest
import yaml

CHILD = textwrap.dedent("""
    import signal, sys, time
    import numpy as np
    from frf_ident.bag import BagRecorder
    from frf_ident.bag.cdr import JointStateEncoder

    path, mode = sys.argv[1], sys.argv[2]
    auto = mode == 'auto'
    rec = BagRecorder(chunk_bytes=(4096 if auto else 1 << 30),
                      flush_period_s=(0.05 if auto else 1e9))
    rec.open(path)
    if mode == 'term':
        def stop(signum, frame):
            rec.close()
        signal.signal(signal.SIGTERM, stop)
    enc = JointStateEncoder(['a', 'b'])
    k = 0
    while rec.is_open:
        ns = 10**9 + k * 10**6
        rec.write('/joint_states', 'sensor_msgs/msg/JointState', ns,
                  enc.encode(ns, [k, -k], [1.0, 2.0], [0.5, 0.5]))
        if k % 7 == 0:
            rec.write('/frf/experiment', 'std_msgs/msg/String', ns, {'data': '{"event": "x"}'})
        k += 1
        if k % 100 == 0:
            if not auto:
                rec.flush()
            print(k, flush=True)
            time.sleep(0.01)
    print('closed', k, flush=True)
""")


def _spawn(path: Path, mode: str) -> subprocess.Popen[str]:
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))
    return subprocess.Popen([sys.executable, '-c', CHILD, str(path), mode], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_for(proc: subprocess.Popen[str], n_lines: int) -> int:
    last = 0
    assert proc.stdout is not None
    for _ in range(n_lines):
        line = proc.stdout.readline()
        assert line, proc.stderr.read() if proc.stderr else 'child died'
        last = int(line.split()[0])
    return last


def test_sigkill_keeps_everything_flushed(tmp_path: Path) -> None:
    bag = tmp_path / 'killed'
    proc = _spawn(bag, 'manual')
    flushed = _wait_for(proc, 5)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=10)
    assert not (bag / 'metadata.yaml').exists()  # close() never ran
    rec, rep = read_recording(bag)
    # everything up to the last flush() the child reported, possibly the next flush too
    n = rec.t.size
    assert n >= flushed and n % 100 == 0
    np.testing.assert_array_equal(rec.position[:, 0], np.arange(n, dtype=float))
    np.testing.assert_allclose(rec.t, 1.0 + np.arange(n) * 1e-3, rtol=0, atol=1e-12)
    assert not rep.recovery['complete']
    assert rep.recovery['messages_lost'].startswith('unknown')
    # reindex turns it into a complete bag with metadata.yaml
    fixed = reindex(bag, tmp_path / 'fixed')
    info = yaml.safe_load((fixed / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert info['version'] == 9 and info['storage_identifier'] == 'mcap'
    rec2, rep2 = read_recording(fixed)
    assert rep2.recovery['complete'] and rec2.t.size == n


def test_sigkill_with_automatic_chunks(tmp_path: Path) -> None:
    bag = tmp_path / 'auto'
    proc = _spawn(bag, 'auto')
    reported = _wait_for(proc, 4)
    time.sleep(0.1)  # > flush_period_s: the chunk holding `reported` is closed
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=10)
    rec, _ = read_recording(bag)
    assert rec.t.size >= reported
    assert bag_info(bag)['complete'] is False


def test_sigterm_handler_close_writes_complete_bag(tmp_path: Path) -> None:
    bag = tmp_path / 'term'
    proc = _spawn(bag, 'term')
    _wait_for(proc, 3)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=20)
    assert proc.returncode == 0, err
    total = int(out.strip().splitlines()[-1].split()[1])
    assert (bag / 'metadata.yaml').exists()
    info = bag_info(bag)
    assert info['version'] == 9
    counts = {t['name']: t['count'] for t in info['topics']}
    assert counts['/joint_states'] == total
    rec, rep = read_recording(bag)
    assert rep.recovery['complete'] and rec.t.size == total


def test_recorder_api(tmp_path: Path) -> None:
    path = tmp_path / 'r'
    rec = BagRecorder()
    rec.open(path)
    with pytest.raises(BagError, match='exists; refusing'):
        BagRecorder().open(path)
    enc = JointStateEncoder(['j'])
    rec.write('/joint_states', 'sensor_msgs/msg/JointState', 5, enc.encode(5, [1.0], [], []))
    rec.write('/joint_states', 'sensor_msgs/msg/JointState', 6,
              {'header': {'stamp': {'sec': 0, 'nanosec': 6}}, 'name': ['j'], 'position': [2.0]})
    with pytest.raises(BagError, match='recorded as sensor_msgs/msg/JointState'):
        rec.write('/joint_states', 'std_msgs/msg/String', 7, {'data': 'x'})
    with pytest.raises(BagError, match='no field'):
        rec.write('/frf/experiment', 'std_msgs/msg/String', 7, {'text': 'x'})
    size0 = next(path.glob('*.mcap')).stat().st_size
    rec.flush()
    assert next(path.glob('*.mcap')).stat().st_size > size0
    rec.close()
    rec.close()  # idempotent
    with pytest.raises(BagError, match='closed recorder'):
        rec.write('/joint_states', 'sensor_msgs/msg/JointState', 8, b'')
    raw = bag_info(path)
    assert {t['name']: t['count'] for t in raw['topics']}['/joint_states'] == 2


def test_a_bag_path_that_cannot_be_created_is_one_line(tmp_path: Path) -> None:
    """A file on the way gave estimator_node a FileExistsError traceback (exit 1)."""
    (tmp_path / 'afile').write_text('x')
    with pytest.raises(BagError, match=r"bag path '.*afile/run1' cannot be created: .*afile is "
                                       r'a file, not a directory'):
        BagRecorder().open(tmp_path / 'afile' / 'run1')
    ro = tmp_path / 'ro'
    ro.mkdir()
    ro.chmod(0o500)
    try:
        if not os.access(ro, os.W_OK):          # root writes anyway
            with pytest.raises(BagError, match='cannot be created: Permission denied'):
                BagRecorder().open(ro / 'run1')
    finally:
        ro.chmod(0o700)


def test_split_closes_the_file_and_records_on(tmp_path: Path) -> None:
    """
    ``split()`` (the estimator's at an abort): the bag is complete up to there, recording goes on.

    After the split metadata.yaml names the closed file, which has its MCAP summary (an
    independent reader, rosbags, reads it); at close every file is listed, the counts add up
    and the samples of all files read back in order. No empty file for a split with nothing
    recorded since the last one; a topic first seen after a split is recorded too.
    """
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader
    path = tmp_path / 'r'
    rec = BagRecorder()
    rec.open(path)
    enc = JointStateEncoder(['j'])

    def run(k0: int, n: int) -> None:
        for k in range(k0, k0 + n):
            ns = 10**9 + k * 10**6
            rec.write('/joint_states', 'sensor_msgs/msg/JointState', ns,
                      enc.encode(ns, [float(k)], [0.0], [0.0]))

    run(0, 300)
    rec.split()
    rec.split()                      # nothing since: no empty file
    meta = yaml.safe_load((path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['relative_file_paths'] == ['r_0.mcap'] and meta['message_count'] == 300
    with open(path / 'r_0.mcap', 'rb') as f:
        assert make_reader(f).get_summary() is not None       # footer and summary written
    with AnyReader([path]) as reader:
        assert sum(1 for _ in reader.messages()) == 300
    run(300, 200)
    rec.write('/frf/experiment', 'std_msgs/msg/String', 10**9 + 499 * 10**6,
              {'data': '{"event": "aborted"}'})
    rec.close()
    meta = yaml.safe_load((path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['relative_file_paths'] == ['r_0.mcap', 'r_1.mcap']
    assert sorted(p.name for p in path.glob('*.mcap')) == ['r_0.mcap', 'r_1.mcap']
    counts = {t['topic_metadata']['name']: t['message_count']
              for t in meta['topics_with_message_count']}
    assert counts == {'/joint_states': 500, '/frf/experiment': 1}
    assert meta['duration']['nanoseconds'] == 499 * 10**6
    got, _ = read_recording(path)
    assert np.array_equal(got.position[:, 0], np.arange(500.0))
