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
Test reading bags written by rosbag2 itself.

Bags written by rosbag2 itself (rosbag2_py, as `ros2 bag record` stores them): MCAP
uncompressed, with zstd and lz4 chunk compression, split into several files, rosbag2's own
file and message compression; receive-time log stamps that disagree with the header stamps.

Needs ROS 2 (skipped cleanly without it). The lz4 chunks come from rosbag2's MCAP storage
config (``compression: Lz4``); a synthetic lz4 MCAP written by the `mcap` package covers it
without ROS as well. Truth: the simulated plant's exact FRF, and the same run written by
rosbags (independent writer).
"""
import json

from frf_ident.bag import read_recording
from frf_ident.cli import main
import numpy as np
import pytest
from replay_synth import Imperfections, multisine_run, truth_frf, write_robot_bag, write_rosbag2

# module fixtures shared by the tests here: they run on one worker (make test, pytest-xdist)
pytestmark = pytest.mark.xdist_group('test_rosbag2_bags')

IMP = Imperfections(jitter=0.01, drop=0.005, log_offset=0.004)


@pytest.fixture(scope='module')
def run():
    return multisine_run(4, period_samples=2048)


@pytest.fixture(scope='module')
def reference(run, tmp_path_factory):
    """Return the same run, imperfections and seed written by rosbags: the estimate to match."""
    bag = tmp_path_factory.mktemp('rosbags') / 'bag'
    write_robot_bag(bag, run, IMP, seed=1)
    out = bag.parent / 'out'
    assert main(['estimate', str(bag), '--out', str(out)]) == 0
    return _frf(out)


def _frf(out):
    d = json.loads((out / 'frf.json').read_text())
    return np.array(d['freq_hz']), (np.array(d['re']) + 1j * np.array(d['im']))[:, 0, :], d


CASES = {
    'split_by_size': {'max_size': 300_000},
    'zstd_chunks_split_by_duration': {'preset': 'zstd_fast', 'max_duration_s': 3},
    'lz4_chunks': {'config': 'lz4'},
    'rosbag2_message_compression': {'compression_mode': 'message'},
    'rosbag2_file_compression': {'compression_mode': 'file'},
}


@pytest.mark.parametrize('case', sorted(CASES))
def test_rosbag2_bag_estimates_like_the_rosbags_one(case, run, reference, tmp_path):
    pytest.importorskip('rosbag2_py')
    pytest.importorskip('rclpy')
    kw = dict(CASES[case])
    if kw.get('config') == 'lz4':
        cfg = tmp_path / 'mcap_lz4.yaml'
        cfg.write_text('compression: "Lz4"\nchunkSize: 262144\n')
        kw['config'] = str(cfg)
    bag = tmp_path / 'bag'
    write_rosbag2(bag, run, IMP, seed=1, **kw)
    files = sorted(p.name for p in bag.iterdir() if p.name != 'metadata.yaml')
    if 'split' in case:
        assert len(files) >= 2, files
    if 'chunks' in case:
        from mcap.reader import make_reader
        with open(bag / files[0], 'rb') as fh:
            chunks = make_reader(fh).get_summary().chunk_indexes
        assert {c.compression for c in chunks} == {'lz4' if 'lz4' in case else 'zstd'}
    rec, timing = read_recording(bag)
    js = timing.topics['/joint_states']
    assert js.stamp_source == 'header'                # not the receive time
    assert js.header_log_offset_mean_s == pytest.approx(4.3e-3, abs=0.1e-3)
    assert rec.t[0] == pytest.approx(100.0, abs=1e-5)
    out = tmp_path / 'out'
    assert main(['estimate', str(bag), '--out', str(out)]) == 0
    f, P, d = _frf(out)
    f_ref, P_ref, _ = reference
    np.testing.assert_allclose(f, f_ref)
    np.testing.assert_allclose(P, P_ref, rtol=1e-9, atol=0)   # same samples, same estimate
    err = np.abs(20 * np.log10(np.abs(P[1] / truth_frf(run, f)[1])))
    assert np.median(err) < 0.1


def test_lz4_chunks_without_ros(run, reference, tmp_path):
    """
    Test reading an MCAP with lz4-compressed chunks without ROS.

    An MCAP with lz4-compressed chunks written by the `mcap` package (the writer rosbag2
    uses is the C++ twin of it): read like the rosbags bag.
    """
    from frf_ident.bag.repair import iter_raw
    from mcap.writer import CompressionType, Writer
    src = tmp_path / 'src'
    write_robot_bag(src, run, IMP, seed=1)
    dst = tmp_path / 'lz4.mcap'
    with open(dst, 'wb') as fh:
        w = Writer(fh, compression=CompressionType.LZ4, chunk_size=64 * 1024)
        w.start(profile='ros2', library='test')
        schemas, chans = {}, {}
        for topic, msgtype, log, data in iter_raw(src):
            if topic not in chans:
                schemas[topic] = w.register_schema(msgtype, 'ros2msg', b'')
                chans[topic] = w.register_channel(topic, 'cdr', schemas[topic])
            w.add_message(chans[topic], log_time=log, data=data, publish_time=log)
        w.finish()
    out = tmp_path / 'out'
    assert main(['estimate', str(dst), '--out', str(out)]) == 0
    f, P, _ = _frf(out)
    np.testing.assert_allclose(P, reference[1], rtol=1e-9, atol=0)
