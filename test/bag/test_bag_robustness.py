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
"""Bad input always ends in one BagError line; damaged bags are recovered where possible."""
from __future__ import annotations

import os
from pathlib import Path
import shutil
import tempfile

from bag_synth import make_recording
from frf_ident.bag import bag_info, BagRecorder, read_recording, write_recording
from frf_ident.bag.repair import iter_raw
from frf_ident.bag.topics import QOS_DEFAULT
from frf_ident.core.recording import Recording
from frf_ident.errors import BagError
from hypothesis import given, HealthCheck, settings
from hypothesis import strategies as st
import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

# module fixtures shared by the tests here: they run on one worker (make test, pytest-xdist)
pytestmark = pytest.mark.xdist_group('test_bag_robustness')

STORE = get_typestore(Stores.ROS2_JAZZY)


def one_line_error(path: Path | str, match: str, **kw: object) -> str:
    with pytest.raises(BagError) as exc:
        read_recording(path, **kw)  # type: ignore[arg-type]
    msg = str(exc.value)
    assert '\n' not in msg and 'Traceback' not in msg
    assert match in msg, msg
    return msg


@pytest.fixture(scope='module')
def small_rec() -> Recording:
    return make_recording(seconds=2.0)


@pytest.fixture(scope='module')
def small_bag(tmp_path_factory: pytest.TempPathFactory, small_rec: Recording) -> Path:
    return write_recording(small_rec, tmp_path_factory.mktemp('rb') / 'small')


@pytest.fixture(scope='module')
def chunky_bag(tmp_path_factory: pytest.TempPathFactory, small_bag: Path) -> Path:
    """small_bag re-recorded with BagRecorder in 16 KiB chunks (many chunks to damage)."""
    out = tmp_path_factory.mktemp('rb') / 'chunky'
    with BagRecorder(chunk_bytes=16 * 1024).open(out) as rec:
        for topic, msgtype, log, raw in iter_raw(small_bag):
            rec.write(topic, msgtype, log, raw)
    return out


def _copy(bag: Path, dst: Path) -> Path:
    shutil.copytree(bag, dst)
    return dst


def _mcap(bag: Path) -> Path:
    return next(bag.glob('*.mcap'))


# --------------------------------------------------------------------------- recovery

def test_truncated_bag_recovers_complete_chunks(clean_bag: Path, clean_rec: Recording,
                                                tmp_path: Path) -> None:
    small_rec = clean_rec
    bag = _copy(clean_bag, tmp_path / 'cut')
    data = _mcap(bag).read_bytes()
    _mcap(bag).write_bytes(data[: int(len(data) * 0.6)])
    rec, rep = read_recording(bag)
    n = rec.t.size
    assert 0 < n < small_rec.t.size
    np.testing.assert_array_equal(rec.t, small_rec.t[:n])  # still the exact grid
    np.testing.assert_array_equal(rec.velocity, small_rec.velocity[:n])
    r = rep.recovery
    assert not r['complete'] and r['bytes_lost'] > 0
    assert r['messages_lost_per_topic']['/joint_states'] == small_rec.t.size - n
    assert any('recovered' in line for line in rep.summary())
    info = bag_info(bag)  # metadata.yaml is intact, so it still describes the full bag
    assert info['message_count'] > 0


def _damage(bag: Path, at: float = 0.5) -> None:
    data = bytearray(_mcap(bag).read_bytes())
    k = int(len(data) * at)
    data[k:k + 2000] = b'\xff' * 2000
    _mcap(bag).write_bytes(bytes(data))


def test_corrupt_chunk_costs_that_chunk_only(chunky_bag: Path, small_rec: Recording,
                                             tmp_path: Path) -> None:
    """
    2000 bad bytes inside a bag of 16 KiB chunks: one chunk is lost, nothing else.

    Inside a chunk's data its CRC fails (the writer fills in the chunk CRCs that rosbags
    leaves at 0, as ros2 bag record's writer does); on a record frame the scan resumes at the
    next chunk the summary indexes. Every other message is read as written; a stretch of lost
    joint states is marked as missing (``gaps='mark'``, the default). At four places in
    the file: both kinds of damage occur and at least one hits the joint states. The summary
    says the bag was damaged, naming the problem (a CRC mismatch reads every byte).
    """
    hit = crc = frame = False
    for at in (0.3, 0.4, 0.5, 0.6):
        bag = _copy(chunky_bag, tmp_path / f'bad{at}')
        _damage(bag, at)
        rec, rep = read_recording(bag)
        r = rep.recovery
        assert r['chunks_lost'] == 1 and r['complete'] and r['problems'], r
        # every byte read, yet damaged: the summary says so (it printed only the gap before)
        line, = [x for x in rep.summary() if x.startswith('recovered a damaged')]
        assert r['damaged'] and '1 chunks lost' in line and r['problems'][0] in line, line
        crc |= any('CRC mismatch' in p for p in r['problems'])
        frame |= any('resumed at the next chunk' in p for p in r['problems'])
        # what survived is what was written, at its own times; the lost stretch is marked
        np.testing.assert_allclose(rec.t, small_rec.t, rtol=0, atol=1e-9)
        keep = ~np.isnan(rec.velocity).any(axis=1)
        lost = r['messages_lost_per_topic'].get('/joint_states', 0)
        assert keep.sum() == small_rec.t.size - lost
        # (marked gaps put the samples on the grid by interpolation: equal to rounding)
        np.testing.assert_allclose(rec.velocity[keep], small_rec.velocity[keep], rtol=1e-9,
                                   atol=1e-12)
        np.testing.assert_allclose(rec.effort[keep], small_rec.effort[keep], rtol=1e-9,
                                   atol=1e-12)
        hit |= lost > 0
    assert hit and crc and frame


def test_corrupt_chunk_holding_the_channels_is_one_line(small_bag: Path, tmp_path: Path
                                                        ) -> None:
    """A bag of few large chunks loses its channel records with the chunk: one-line BagError."""
    bag = _copy(small_bag, tmp_path / 'bad')
    _damage(bag)
    with pytest.raises(BagError) as exc:
        read_recording(bag)
    assert '\n' not in str(exc.value) and str(bag) in str(exc.value)


def test_metadata_missing_dir_and_bare_file(small_bag: Path, small_rec: Recording,
                                            tmp_path: Path) -> None:
    bag = _copy(small_bag, tmp_path / 'nometa')
    (bag / 'metadata.yaml').unlink()
    rec, rep = read_recording(bag)
    assert rec.t.size == small_rec.t.size and rep.recovery['messages_lost'] == 0
    assert bag_info(bag)['message_count'] == bag_info(small_bag)['message_count']


# --------------------------------------------------------------------------- bad input

def test_nonexistent_and_not_a_bag(tmp_path: Path) -> None:
    one_line_error(tmp_path / 'nope', 'does not exist')
    (tmp_path / 'empty.mcap').write_bytes(b'')
    one_line_error(tmp_path / 'empty.mcap', 'not a readable MCAP file')
    (tmp_path / 'text.mcap').write_text('hello world, not a bag\n' * 10)
    one_line_error(tmp_path / 'text.mcap', 'not a readable MCAP file')
    (tmp_path / 'dir').mkdir()
    one_line_error(tmp_path / 'dir', 'neither metadata.yaml nor an .mcap')


def test_broken_metadata_yaml(small_bag: Path, tmp_path: Path) -> None:
    bag = _copy(small_bag, tmp_path / 'm')
    (bag / 'metadata.yaml').write_text('just: [a, list\n')
    one_line_error(bag, 'not a rosbag2 metadata.yaml')
    (bag / 'metadata.yaml').write_text('rosbag2_bagfile_information:\n  storage_identifier: '
                                       'sqlite3\n')
    one_line_error(bag, "storage_identifier 'sqlite3' is not supported; expected mcap")


def _bag_with(path: Path, topic: str, msgtype: str, msgs: list) -> Path:
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        c = w.add_connection(topic, msgtype, typestore=STORE, offered_qos_profiles=[QOS_DEFAULT])
        for stamp, msg in msgs:
            w.write(c, stamp, STORE.serialize_cdr(msg, msgtype))
    return path


def _js(k: int, names: list[str], pos: list[float]) -> object:
    js = STORE.types['sensor_msgs/msg/JointState']
    hdr = STORE.types['std_msgs/msg/Header']
    tm = STORE.types['builtin_interfaces/msg/Time']
    return js(header=hdr(stamp=tm(sec=1, nanosec=k * 1_000_000), frame_id=''), name=names,
              position=np.array(pos), velocity=np.zeros(len(names)),
              effort=np.zeros(len(names)))


def test_empty_bag(tmp_path: Path) -> None:
    _bag_with(tmp_path / 'e', '/joint_states', 'sensor_msgs/msg/JointState', [])
    one_line_error(tmp_path / 'e', 'no messages on /joint_states')


def test_missing_topic(tmp_path: Path) -> None:
    clock = STORE.types['rosgraph_msgs/msg/Clock']
    tm = STORE.types['builtin_interfaces/msg/Time']
    _bag_with(tmp_path / 'c', '/clock', clock.__msgtype__,
              [(k, clock(clock=tm(sec=0, nanosec=k))) for k in range(1, 5)])
    msg = one_line_error(tmp_path / 'c', 'no messages on /joint_states')
    assert "topics present: ['/clock']" in msg


def test_wrong_type(tmp_path: Path) -> None:
    f64 = STORE.types['std_msgs/msg/Float64MultiArray']
    lay = STORE.types['std_msgs/msg/MultiArrayLayout']
    _bag_with(tmp_path / 'w', '/joint_states', f64.__msgtype__,
              [(1, f64(layout=lay(dim=[], data_offset=0), data=np.ones(3)))])
    one_line_error(tmp_path / 'w', 'topic /joint_states has type std_msgs/msg/Float64MultiArray;'
                   ' expected sensor_msgs/msg/JointState')


def test_missing_joint(tmp_path: Path) -> None:
    msgs = [(10**9 + k * 10**6, _js(k, ['a', 'b'], [k, k])) for k in range(20)]
    _bag_with(tmp_path / 'j', '/joint_states', 'sensor_msgs/msg/JointState', msgs)
    one_line_error(tmp_path / 'j', "joint 'zz' not found in /joint_states (joints present: "
                   "['a', 'b'])", joints=['a', 'zz'])


@pytest.mark.parametrize('bad', [np.nan, np.inf, -np.inf])
def test_non_finite_values(tmp_path: Path, bad: float) -> None:
    msgs = [(10**9 + k * 10**6, _js(k, ['a', 'b'], [k, bad if k == 7 else k]))
            for k in range(20)]
    _bag_with(tmp_path / 'n', '/joint_states', 'sensor_msgs/msg/JointState', msgs)
    msg = one_line_error(tmp_path / 'n', '/joint_states position[b] is ')
    assert 'at t=1.007000 s' in msg and 'expected finite values' in msg


def test_bad_arguments(small_bag: Path) -> None:
    one_line_error(small_bag, 'expected a non-empty list', joints=[])
    one_line_error(small_bag, 't_start < t_end', t_range=(2.0, 1.0))
    one_line_error(small_bag, 'no /joint_states samples in', t_range=(50.0, 60.0))


# --------------------------------------------------------------------------- fuzz

FUZZ_EXAMPLES = int(os.environ.get('FRF_FUZZ_EXAMPLES', '50'))


@settings(max_examples=FUZZ_EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_fuzz_truncation_and_corruption(chunky_bag: Path, data: st.DataObject) -> None:
    raw = bytearray(_mcap(chunky_bag).read_bytes())
    n = len(raw)
    cut = data.draw(st.one_of(st.just(n), st.integers(0, n)), label='cut')
    flips = data.draw(st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, 255)),
                               max_size=8), label='flips')
    for pos, val in flips:
        raw[pos] = val
    tmp = Path(tempfile.mkdtemp())
    try:
        f = tmp / 'fuzz.mcap'
        f.write_bytes(bytes(raw[:cut]))
        try:
            rec, rep = read_recording(f)
            assert rec.t.size >= 1 and rep.summary()
        except BagError as exc:
            assert '\n' not in str(exc)
        try:
            bag_info(f)
        except BagError as exc:
            assert '\n' not in str(exc)
    finally:
        shutil.rmtree(tmp)


def test_our_own_end_and_abort_events_are_no_warnings() -> None:
    """
    procedure_end is ours: no 'ignored' warning; an abort is named with its reason.

    Every bag the package wrote printed "ignored 1 event(s) 'procedure_end'".
    """
    import json
    from types import SimpleNamespace

    from frf_ident.bag.reader import read_descriptors
    from frf_ident.bag.topics import BagTopics
    ev = [(1, json.dumps({'event': 'start', 't_start': 0.0, 't_end': 1.0, 'kind': 'x'})),
          (2, json.dumps({'event': 'end', 't_start': 0.0, 't_end': 1.0, 'kind': 'x'})),
          (3, json.dumps({'event': 'procedure_end', 'procedure': 'multisine'})),
          (4, json.dumps({'event': 'aborted', 'procedure': 'chirp_iteration_2',
                          'reason': 'shutdown', 't_start': 1.0, 't_end': 1.5})),
          (5, json.dumps({'event': 'mystery'}))]
    _meta, segs, warnings = read_descriptors(ev, SimpleNamespace(name='b'), BagTopics())
    assert len(segs) == 1
    assert warnings == ["/frf/experiment: ignored 1 event(s) 'mystery' (not start/end)",
                        'chirp_iteration_2 aborted at 1.500 s: shutdown'], warnings


def test_a_segment_that_never_ended_is_left_out() -> None:
    """An aborted run's last segment had a start only: the estimate failed on its coverage."""
    import json
    from types import SimpleNamespace

    from frf_ident.bag.reader import read_descriptors
    from frf_ident.bag.topics import BagTopics

    def seg(event, r, t0):
        return json.dumps({'event': event, 't_start': t0, 't_end': t0 + 1.0,
                           'design': 'multisine', 'realisation': r})
    done = [(1, seg('start', 0, 0.0)), (2, seg('end', 0, 0.0)), (3, seg('start', 1, 1.0))]
    abort = [(4, json.dumps({'event': 'aborted', 'procedure': 'multisine',
                             'reason': 'shutdown', 't_start': 0.0, 't_end': 1.4}))]
    # ours (end events, or an abort) cut it; a producer writing start descriptors only keeps it
    for events, kept, n_cut in ((done, [0], 1), (done[2:] + abort, [], 1), (done[2:], [1], 0)):
        meta, segs, warnings = read_descriptors(events, SimpleNamespace(name='b'), BagTopics())
        assert [s.info['realisation'] for s in segs] == kept, events
        cut = [w for w in warnings if 'never ended' in w]
        assert len(cut) == n_cut and len(meta.get('segments_left_out', [])) == n_cut, warnings


def test_a_recording_whose_every_run_was_cut_short_says_so(small_rec: Recording) -> None:
    """It fell through to excitation detection and a line about autocorrelations."""
    from frf_ident.core.estimation.described import estimate_recording
    from frf_ident.errors import EstimationError
    rec = Recording(small_rec.t, small_rec.joint_names, small_rec.position, small_rec.velocity,
                    small_rec.effort, meta={'segments_left_out': [[0.0, 1.0]] * 3})
    with pytest.raises(EstimationError, match=r'every experiment of the recording was cut '
                                              r'short: its 3 started segment\(s\) never ended'):
        estimate_recording(rec)
