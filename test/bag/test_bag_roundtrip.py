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
"""write_recording -> read_recording is bit-exact, and other tools read our bags."""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from bag_synth import JOINTS, make_recording
from frf_ident.bag import bag_info, BagTopics, read_recording, write_recording
from frf_ident.core.recording import Recording
from frf_ident.errors import BagError
import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.typesys import get_typestore, Stores
import yaml

ARRAYS = ('t', 'position', 'velocity', 'effort', 'reference', 'excitation')


def assert_same(a: Recording, b: Recording) -> None:
    for name in ARRAYS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype == np.float64, name
        assert x.shape == y.shape, name
        # bit-exact: the sign of a zero and every NaN payload survive
        assert np.array_equal(x.view(np.int64), y.view(np.int64)), name
    assert a.joint_names == b.joint_names
    assert a.segments == b.segments
    assert a.meta == b.meta


def test_round_trip_bit_exact(clean_rec: Recording, clean_bag: Path) -> None:
    rec, report = read_recording(clean_bag)
    assert_same(clean_rec, rec)
    assert not report.resampled and report.grid == 'exact'
    assert report.topics['/joint_states'].stamp_source == 'header'
    assert report.n_samples == clean_rec.t.size
    assert json.dumps(report.to_dict())
    assert report.summary()[0].startswith(f'{clean_rec.t.size} samples at 1000.000 Hz')


def test_round_trip_offset_time_and_custom_topics(tmp_path: Path) -> None:
    src = make_recording(seconds=2.0, fs=500.0, t0=1234.5)
    # 2 s leave no room for the chirp segment (it would end before it starts): a segment
    # outside the record is left out by the reader
    src = dataclasses.replace(src, segments=src.segments[:1])
    # signed zeros and a NaN with a payload must come back bit for bit
    src.effort[3, 0] = src.position[4, 1] = -0.0
    src.excitation[7, 0] = np.array([0x7FF8_0000_DEAD_BEEF], np.int64).view(np.float64)[0]
    topics = BagTopics(joint_states='/robot/joint_states', experiment='/robot/experiment',
                       velocity_commands='/fwd/commands', excitation='/robot/exc')
    path = write_recording(src, tmp_path / 'b', topics=topics)
    rec, _ = read_recording(path, topics=topics)
    assert_same(src, rec)
    with pytest.raises(BagError, match='no messages on /joint_states'):
        read_recording(path)


def test_select_joints_by_name(clean_rec: Recording, clean_bag: Path) -> None:
    rec, _ = read_recording(clean_bag, joints=['joint_3', 'joint_1'])
    assert rec.joint_names == ['joint_3', 'joint_1']
    for name in ('position', 'velocity', 'effort', 'reference', 'excitation'):
        np.testing.assert_array_equal(getattr(rec, name), getattr(clean_rec, name)[:, [2, 0]])


def test_t_range(clean_rec: Recording, clean_bag: Path) -> None:
    rec, report = read_recording(clean_bag, t_range=(1.0, 2.5))
    sl = (clean_rec.t >= 1.0 - 1e-12) & (clean_rec.t <= 2.5 + 1e-12)
    np.testing.assert_array_equal(rec.t, clean_rec.t[sl])
    np.testing.assert_array_equal(rec.velocity, clean_rec.velocity[sl])
    # both segments reach outside the range: left out and named (issue 44), never estimated
    # from a part
    assert rec.segments == []
    assert rec.meta['segments_left_out'] == [[0.5, 2.0], [2.1, 4.5]]
    assert sum('only partly in the record' in w for w in report.warnings) == 2


def test_refuses_to_overwrite(clean_bag: Path, clean_rec: Recording, tmp_path: Path) -> None:
    before = sorted(p.stat().st_mtime_ns for p in clean_bag.iterdir())
    with pytest.raises(BagError, match='exists; refusing to overwrite') as exc:
        write_recording(clean_rec, clean_bag)
    assert str(clean_bag) in str(exc.value) and '\n' not in str(exc.value)
    assert sorted(p.stat().st_mtime_ns for p in clean_bag.iterdir()) == before
    # overwrite=True replaces atomically and leaves no temporary directories behind
    path = write_recording(clean_rec, tmp_path / 'x')
    small = make_recording(seconds=1.0)
    write_recording(small, path, overwrite=True)
    assert read_recording(path)[0].t.size == small.t.size
    assert sorted(p.name for p in tmp_path.iterdir()) == ['x']


def test_metadata_yaml_v9(clean_bag: Path) -> None:
    info = yaml.safe_load((clean_bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert info['version'] == 9 and info['storage_identifier'] == 'mcap'
    topics = {t['topic_metadata']['name']: t for t in info['topics_with_message_count']}
    exp = topics['/frf/experiment']['topic_metadata']['offered_qos_profiles'][0]
    assert exp['durability'] == 'transient_local' and exp['reliability'] == 'reliable'
    for t in topics.values():
        assert t['topic_metadata']['offered_qos_profiles']
        assert t['topic_metadata']['type_description_hash'].startswith('RIHS01_')
    js = topics['/joint_states']['topic_metadata']['type_description_hash']
    assert js == ('RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e')


def test_readable_by_rosbags_anyreader(clean_rec: Recording, clean_bag: Path) -> None:
    store = get_typestore(Stores.ROS2_JAZZY)
    with AnyReader([clean_bag], default_typestore=store) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        conns = [c for c in reader.connections if c.topic == '/joint_states']
        vel = [reader.deserialize(raw, c.msgtype).velocity
               for c, _, raw in reader.messages(connections=conns)]
    n = clean_rec.t.size
    assert counts['/joint_states'] == n and counts['/effort_controller/commands'] == n
    assert counts['/velocity_controller/commands'] == np.all(
        np.isfinite(clean_rec.reference), axis=1).sum()
    assert counts['/frf/experiment'] == 1 + 2 * len(clean_rec.segments)
    np.testing.assert_array_equal(np.array(vel), clean_rec.velocity)


def test_readable_by_mcap_ros2(clean_rec: Recording, clean_bag: Path) -> None:
    from mcap_ros2.reader import read_ros2_messages

    mcap = next(clean_bag.glob('*.mcap'))
    stamps, texts = [], []
    for m in read_ros2_messages(str(mcap), topics=['/joint_states', '/frf/experiment']):
        if m.channel.topic == '/joint_states':
            assert list(m.ros_msg.name) == JOINTS
            stamps.append(m.ros_msg.header.stamp.sec * 10**9 + m.ros_msg.header.stamp.nanosec)
        else:
            texts.append(json.loads(m.ros_msg.data))
    np.testing.assert_array_equal(stamps, np.round(clean_rec.t * 1e9).astype(np.int64))
    assert texts[0]['event'] == 'recording_meta' and texts[0]['seed'] == 7
    assert [t['event'] for t in texts[1:]] == ['start', 'end', 'start', 'end']


def test_bag_info(clean_rec: Recording, clean_bag: Path) -> None:
    info = bag_info(clean_bag)
    assert info['version'] == 9 and info['storage'] == 'mcap'
    topics = {t['name']: t for t in info['topics']}
    assert topics['/joint_states']['count'] == clean_rec.t.size
    assert topics['/joint_states']['type'] == 'sensor_msgs/msg/JointState'
    assert info['duration_s'] == pytest.approx(clean_rec.t[-1] - clean_rec.t[0])
    # the same from the MCAP summary alone, and from a bare .mcap
    bare = bag_info(next(clean_bag.glob('*.mcap')))
    assert {t['name']: t['count'] for t in bare['topics']} == \
        {t['name']: t['count'] for t in info['topics']}


def test_bare_mcap_and_dir_without_metadata(clean_rec: Recording, clean_bag: Path,
                                            tmp_path: Path) -> None:
    mcap = next(clean_bag.glob('*.mcap'))
    assert_same(clean_rec, read_recording(mcap)[0])
    d = tmp_path / 'nometa'
    d.mkdir()
    (d / 'data.mcap').write_bytes(mcap.read_bytes())
    assert_same(clean_rec, read_recording(d)[0])
