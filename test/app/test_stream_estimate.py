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
Bags longer than memory: windowed reading and estimation in bounded memory (issue 6.7).

The streamed estimate must equal the in-memory one (own bags: bit for bit; bags without
descriptors: every period of every block in the H1 sums), and the memory held must not grow
with the length of the bag while the in-memory reader's does.
"""
import json
import tracemalloc

from benchmarks.__main__ import periodic_multisine_run
from frf_ident.app.stream_estimate import stream_estimate
from frf_ident.bag import read_recording, write_recording
from frf_ident.bag.windows import read_experiment, segment_windows, WindowReader
from frf_ident.cli import main
from frf_ident.core.estimation.described import estimate_recording
import numpy as np
import pytest


@pytest.fixture(scope='module')
def foreign_bags(tmp_path_factory):
    root = tmp_path_factory.mktemp('stream')
    out = {}
    for dur in (60.0, 240.0):
        path = root / f'foreign_{int(dur)}s'
        write_recording(periodic_multisine_run(dur), path)
        out[dur] = path
    return out


def _peak_bytes(fn):
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_windows_equal_the_in_memory_recording(foreign_bags):
    bag = foreign_bags[60.0]
    full, _ = read_recording(bag)
    reader = WindowReader(bag, window_s=7.0, drain_rows=5000)
    n = 0
    for rec, report in reader:
        i0 = full.index_of(rec.t[0])
        sl = slice(i0, i0 + rec.t.size)
        np.testing.assert_array_equal(rec.t, full.t[sl])
        np.testing.assert_array_equal(rec.velocity, full.velocity[sl])
        np.testing.assert_array_equal(rec.reference, full.reference[sl])
        assert report.grid == 'exact'
        n += rec.t.size
    assert n == full.t.size                      # consecutive blocks: every sample once
    assert reader.stats.windows == int(np.ceil(full.t.size / 7000))
    assert reader.stats.recovery['messages_lost'] == 0
    # rows held at once: one block plus what arrives between drains, not the bag
    assert reader.stats.peak_rows < 3 * (7000 + 5000)


def test_blocks_of_a_foreign_bag_give_the_in_memory_estimate(foreign_bags):
    bag = foreign_bags[60.0]
    rec, _ = read_recording(bag)
    ref = estimate_recording(rec)['detected/joint_2']
    got = stream_estimate(bag, window_s=12.0).estimates['detected/joint_2']
    np.testing.assert_allclose(got.freq_hz, ref.freq_hz, rtol=1e-9)   # f0 from each fs
    # the next block starts where the last whole period ended and skips no transient: all
    # steady-state periods are used as in memory (19 periods, the first three transient by
    # the transient test on either path) except a last block holding a single period, which
    # detection (>= 2 periods) cannot confirm
    assert got.meta['blocks'] == 6          # 3 whole periods (9.2 s) per 12 s block
    assert ref.meta['periods'] == 16 and got.meta['periods'] == 15
    assert got.meta['transient_periods'] == ref.meta['transient_periods'] == 3
    z = np.abs(got.response - ref.response) / np.sqrt(ref.noise_variance)
    assert np.max(z) < 1.0 and np.median(z) < 0.3
    drive = 20 * np.log10(np.abs(got.response[1] / ref.response[1]))
    print(f'driven channel: max |diff| {np.max(np.abs(drive)):.3f} dB')


def test_streamed_estimate_of_an_own_bag_equals_the_in_memory_one(tmp_path, capsys):
    from frf_ident.app.identify import run_identify
    from frf_ident.cli.identify import identification_config
    from frf_ident.cli.main import build_parser
    bag = tmp_path / 'own'
    cfg = identification_config(build_parser().parse_args(
        ['identify', '--out', str(bag), '--realisations', '2', '--periods', '2',
         '--resolution', '0.5', '--chirp-duration', '6', '--max-iterations', '1']))
    run_identify(None, None, cfg, bag, progress=lambda _m: None)
    exp = read_experiment(bag)
    assert len(segment_windows(exp.segments)) == 1 + 2 * 3 + 3
    assert main(['estimate', str(bag), '--out', str(tmp_path / 'mem')]) == 0
    assert main(['estimate', str(bag), '--out', str(tmp_path / 'str'), '--stream']) == 0
    a = json.loads((tmp_path / 'mem' / 'estimates.json').read_text())
    b = json.loads((tmp_path / 'str' / 'estimates.json').read_text())
    assert sorted(a) == sorted(b) == ['chirp', 'chirp_reference', 'multisine',
                                      'multisine_plain', 'multisine_uncompensated']
    for k in a:
        za, zb = (np.array(d[k]['re']) + 1j * np.array(d[k]['im']) for d in (a, b))
        if k.startswith('multisine'):         # whole periods, same samples: bit for bit
            np.testing.assert_array_equal(za, zb)
        else:   # the chirp excerpt DFT uses fs = 1/median(dt) of its window: last-bit change
            np.testing.assert_allclose(za, zb, rtol=1e-9, atol=0)
    s = json.loads((tmp_path / 'str' / 'summary.json').read_text())
    assert s['streaming']['windows'] == 10
    assert json.loads((tmp_path / 'mem' / 'summary.json').read_text())['streaming'] is None


def test_memory_does_not_grow_with_the_bag(foreign_bags):
    """4x the bag: the streamed estimate holds the same memory, the in-memory one 4x."""
    def streamed(d):
        return _peak_bytes(lambda: stream_estimate(foreign_bags[d], window_s=12.0))

    def in_memory(d):
        return _peak_bytes(lambda: estimate_recording(read_recording(foreign_bags[d])[0]))
    s1, s4 = streamed(60.0), streamed(240.0)
    m1, m4 = in_memory(60.0), in_memory(240.0)
    print(f'peak traced memory: streamed {s1 / 2**20:.1f} -> {s4 / 2**20:.1f} MB, '
          f'in memory {m1 / 2**20:.1f} -> {m4 / 2**20:.1f} MB for 60 s -> 240 s')
    assert s4 < 1.25 * s1
    assert m4 > 3.0 * m1
    assert s4 < m4 / 2


def test_bag_over_the_memory_budget_streams_automatically(foreign_bags, tmp_path, capsys):
    out = tmp_path / 'auto'
    assert main(['estimate', str(foreign_bags[60.0]), '--out', str(out), '--max-memory', '1',
                 '--window', '12']) == 0
    assert 'streamed' in capsys.readouterr().out
    s = json.loads((out / 'summary.json').read_text())
    assert s['streaming']['windows'] == 7 and s['estimates'] == ['detected/joint_2']


@pytest.mark.parametrize('args, expect', [
    (['--window', '0'], '--window 0.0: expected a block length in s > 0'),
    (['--max-memory', '-5'], '--max-memory -5.0: expected a size in MB > 0'),
    # a window too short for the multisine and its given period (without the period the
    # blocks hold no multisine, and the LPM estimates them instead)
    (['--stream', '--window', '0.5', '--multisine-period', '2.0'],
     'no multisine or chirp found in any 0.5 s block'),
])
def test_bad_streaming_options_one_line(foreign_bags, tmp_path, capsys, args, expect):
    assert main(['estimate', str(foreign_bags[60.0]), '--out', str(tmp_path / 'o')]
                + args) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and expect in err and 'Traceback' not in err
    assert not (tmp_path / 'o' / 'frf.json').exists()
