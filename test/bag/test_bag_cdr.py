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
"""The hand-rolled CDR codecs agree byte for byte with rosbags; bench and progress work."""
from __future__ import annotations

import json
from pathlib import Path

from benchmarks.bag_read import bench_read
from frf_ident.bag import cdr, read_recording
from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest
from rosbags.typesys import get_typestore, Stores

STORE = get_typestore(Stores.ROS2_JAZZY)
JS = STORE.types['sensor_msgs/msg/JointState']
HDR = STORE.types['std_msgs/msg/Header']
TIME = STORE.types['builtin_interfaces/msg/Time']
F64 = STORE.types['std_msgs/msg/Float64MultiArray']
LAYOUT = STORE.types['std_msgs/msg/MultiArrayLayout']
DIM = STORE.types['std_msgs/msg/MultiArrayDimension']

names_st = st.lists(st.text(min_size=0, max_size=12), max_size=5)
floats_st = st.floats(allow_nan=False, width=64)


@settings(max_examples=60, deadline=None)
@given(names=names_st, frame=st.text(max_size=10), sec=st.integers(0, 2**31 - 1),
       nsec=st.integers(0, 10**9 - 1), data=st.data())
def test_joint_state_codec_matches_rosbags(names: list[str], frame: str, sec: int, nsec: int,
                                           data: st.DataObject) -> None:
    n = len(names)
    arrays = [np.array(data.draw(st.lists(floats_st, min_size=k, max_size=k)))
              for k in (n, data.draw(st.sampled_from([0, n])), data.draw(st.sampled_from([0, n])))]
    msg = JS(header=HDR(stamp=TIME(sec=sec, nanosec=nsec), frame_id=frame), name=names,
             position=arrays[0], velocity=arrays[1], effort=arrays[2])
    ref = bytes(STORE.serialize_cdr(msg, JS.__msgtype__))
    stamp_ns = sec * 10**9 + nsec
    assert cdr.JointStateEncoder(names, frame).encode(stamp_ns, *arrays) == ref
    stamp, got_names, got = cdr.JointStateDecoder().decode(ref)
    assert stamp == stamp_ns and list(got_names) == names
    for a, b in zip(got, arrays):
        np.testing.assert_array_equal(np.array(a), b)
    batch = cdr.decode_joint_state_batch(ref * 10, [i * len(ref) for i in range(10)],
                                         [(i + 1) * len(ref) for i in range(10)])
    assert batch is not None
    assert np.all(batch[0] == stamp_ns) and list(batch[1]) == names
    for a, b in zip(batch[2], arrays):
        np.testing.assert_array_equal(a, np.tile(b, (10, 1)).reshape(10, len(b)))


@settings(max_examples=40, deadline=None)
@given(values=st.lists(floats_st, max_size=7), labels=st.lists(st.text(max_size=5), max_size=2))
def test_float64_array_codec_matches_rosbags(values: list[float], labels: list[str]) -> None:
    dims = [DIM(label=lab, size=3, stride=3) for lab in labels]
    msg = F64(layout=LAYOUT(dim=dims, data_offset=0), data=np.array(values, dtype=float))
    ref = bytes(STORE.serialize_cdr(msg, F64.__msgtype__))
    if not labels:
        assert cdr.encode_float64_array(values) == ref
    assert list(cdr.decode_float64_array(ref)) == values
    out = cdr.decode_float64_array_batch(ref * 3, [0, len(ref), 2 * len(ref)],
                                         [len(ref), 2 * len(ref), 3 * len(ref)])
    assert out is not None and out.shape == (3, len(values))
    np.testing.assert_array_equal(out, np.tile(values, (3, 1)).reshape(3, len(values)))


def test_string_codec_and_errors() -> None:
    s = STORE.types['std_msgs/msg/String']
    ref = bytes(STORE.serialize_cdr(s(data='{"ä": 1}'), s.__msgtype__))
    assert cdr.encode_string('{"ä": 1}') == ref and cdr.decode_string(ref) == '{"ä": 1}'
    with pytest.raises(cdr.CdrError, match='not little-endian'):
        cdr.decode_string(b'\x00\x00\x00\x00' + ref[4:])
    with pytest.raises(cdr.CdrError):
        cdr.JointStateDecoder().decode(ref[:10])
    hetero = [cdr.JointStateEncoder(['a']).encode(1, [1.0], [], []),
              cdr.JointStateEncoder(['b']).encode(2, [2.0], [], [])]
    buf = b''.join(hetero)
    assert cdr.decode_joint_state_batch(buf, [0, len(hetero[0])],
                                        [len(hetero[0]), len(buf)]) is None


def test_bench_and_progress(clean_bag: Path, capsys: pytest.CaptureFixture[str]) -> None:
    result = bench_read(clean_bag)
    assert result['joint_state_messages'] == 5000
    assert result['frf_ident']['joint_states_per_s'] > 0
    assert result['rosbags_anyreader']['peak_bytes'] > 0
    assert json.dumps(result)
    lines: list[str] = []
    read_recording(clean_bag, progress=lines.append)
    size_mb = sum(f.stat().st_size for f in clean_bag.glob('*.mcap')) / 1e6
    assert len(lines) == 1 and lines[0].startswith(f'{clean_bag}: read {size_mb:.1f} MB in 1 '
                                                   f'file(s), ')
    assert capsys.readouterr().err == ''      # the bar is drawn on a terminal only
    with pytest.raises(TypeError, match='progress=True: expected a callable'):
        read_recording(clean_bag, progress=True)     # the bool it once took
