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
Test estimating robot bags with jitter, drops and bursts of lost messages.

Issue 12: robot bags with jitter, drops and bursts of lost messages are estimated; in memory
and streamed give one verdict. Issue 55: a gap costs no period, its samples are estimated from
the other periods (test/cli/test_estimate_missing.py holds the must-show figures).

Truth: the simulated plant's exact sampled FRF (robot_frf_sampled). The bags are written like
a ros2_control robot records them (test/bag/replay_synth.py): /joint_states and
/velocity_controller/commands only, no /frf/experiment.
"""
import json
from pathlib import Path
import sys

from frf_ident.cli import main
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'bag'))
from replay_synth import Imperfections, multisine_run, truth_frf, write_robot_bag  # noqa: E402

#: 6 bursts of 90 ms, drawn once (uniform over the first 80 s of a 10-period run)
BURSTS = [(7.77, 0.09), (8.44, 0.09), (19.71, 0.09), (35.22, 0.09), (46.99, 0.09),
          (64.30, 0.09)]


def _frf(out):
    d = json.loads((out / 'frf.json').read_text())
    P = (np.array(d['re']) + 1j * np.array(d['im']))[:, 0, :]      # outputs x lines
    return np.array(d['freq_hz']), P, d


def _db(a, b):
    return np.abs(20 * np.log10(np.abs(a / b)))


def _estimate(bag, out, *args):
    assert main(['estimate', str(bag), '--out', str(out), *args]) == 0
    return _frf(out)


@pytest.fixture(scope='module')
def run10():
    return multisine_run(10)


@pytest.fixture(scope='module')
def burst_bags(run10, tmp_path_factory):
    root = tmp_path_factory.mktemp('bursts')
    clean, burst = root / 'clean', root / 'burst'
    write_robot_bag(clean, run10, Imperfections(jitter=0.01, drop=0.005), seed=5)
    info = write_robot_bag(burst, run10, Imperfections(jitter=0.01, drop=0.005, bursts=BURSTS),
                           seed=5)
    return clean, burst, info


def test_jittered_ros2_control_bag_within_1_db_of_the_plant(tmp_path, capsys):
    """
    Test that a jittered ros2_control bag is within 1 dB of the plant.

    6 periods x 8192 samples at 1 kHz, 1 % stamp jitter, 0.5 % single drops (it crashed
    with 'cannot reshape array' before).
    """
    rec = multisine_run(6)
    write_robot_bag(tmp_path / 'rc', rec, Imperfections(jitter=0.01, drop=0.005))
    f, P, d = _estimate(tmp_path / 'rc', tmp_path / 'out')
    out = capsys.readouterr().out
    assert 'detected: joint_2 (velocity reference): odd multisine: period 8192 samples' in out
    err = _db(P, truth_frf(rec, f))
    print(f'median |error| {np.median(err):.3f} dB (driven {np.median(err[1]):.4f} dB), '
          f'{f.size} lines')
    assert f.size >= 70 and np.median(err) < 1.0 and np.median(err[1]) < 0.1
    # 6 periods, the first skipped as transient, none lost
    assert d['meta']['periods'] == 5 and d['meta']['dropped']['periods'] == 0


def test_bursts_cost_no_period(run10, burst_bags, tmp_path, capsys):
    """
    The periods bursts touch are kept, their missing samples estimated (issue 55 item 5).

    Before, the 5 of 9 steady periods the bursts touched were dropped.
    """
    clean, burst, info = burst_bags
    f0, P0, d0 = _estimate(clean, tmp_path / 'clean')
    capsys.readouterr()
    f1, P1, d = _estimate(burst, tmp_path / 'burst')
    out = capsys.readouterr().out
    np.testing.assert_allclose(f1, f0)
    meta = d['meta']
    n_steady = 10 - meta['transient_periods']
    assert meta['dropped']['periods'] == 0 and meta['periods'] == n_steady
    assert meta['transient_periods'] == d0['meta']['transient_periods']
    # the samples the bursts took from the steady periods (the transient period's are not
    # used), on the bag's grid
    period = 8.192
    lost = info['lost'] & (np.arange(info['lost'].size) >= meta['transient_periods'] * 8192)
    miss = meta['missing']
    assert abs(miss['samples'] - lost.sum()) <= len(BURSTS) and miss['units'] == n_steady
    hit = {int((a + x) // period) for a, dur in BURSTS for x in (0.0, dur)}
    assert miss['touched'] == len(hit - set(range(meta['transient_periods'])))
    summary = json.loads((tmp_path / 'burst' / 'summary.json').read_text())
    assert summary['missing']['detected/joint_2']['samples'] == miss['samples']
    assert len(summary['gaps']) == len(BURSTS)
    assert f'detected/joint_2: {miss["samples"]} missing samples' in out
    assert 'dropped for gaps' not in out
    assert f'{len(BURSTS)} gaps longer than 3 samples kept as missing data' in out
    err_truth = _db(P1, truth_frf(run10, f1))
    err_clean = _db(P1, P0)
    print(f'{miss["touched"]} of {n_steady} steady periods held {miss["samples"]} missing '
          f'samples, estimated and kept; median |error| to truth {np.median(err_truth):.3f} '
          f'dB, to the bag without bursts {np.median(err_clean):.4f} dB (max driven '
          f'{np.max(err_clean[1]):.4f} dB)')
    assert np.median(err_truth) < 1.0
    assert np.median(err_clean) < 0.05 and np.max(err_clean[1]) < 0.1


def test_streamed_and_in_memory_take_the_same_decisions(burst_bags, tmp_path):
    """
    Test that streamed and in-memory estimation take the same decisions.

    Blocks of 30 s, in memory and streamed: the same periods used and dropped, the same
    FRF up to the resampling of each window on its own timing fit (the least-squares grid of
    a window and of the whole bag agree to a fraction of a microsecond).
    """
    _, burst, _ = burst_bags
    _, Pm, dm = _estimate(burst, tmp_path / 'mem', '--window', '30')
    _, Ps, ds = _estimate(burst, tmp_path / 'str', '--window', '30', '--stream')
    for k in ('periods', 'transient_periods', 'blocks'):
        assert dm['meta'][k] == ds['meta'][k], k
    assert dm['meta']['missing']['samples'] == ds['meta']['missing']['samples'] > 0
    np.testing.assert_allclose(np.array(dm['meta']['dropped']['times']),
                               np.array(ds['meta']['dropped']['times']), atol=2e-3)
    rel = np.abs(Pm - Ps) / np.abs(Pm)
    z = np.abs(Pm - Ps) / np.sqrt(np.array(dm['noise_variance'])[:, 0])
    print(f'streamed vs in memory: relative difference median {np.median(rel):.1e}, max '
          f'{np.max(rel):.1e} (weak coupling lines); at most {np.max(z):.1e} noise std')
    assert np.median(rel) < 1e-5 and np.max(rel[1]) < 1e-4 and np.max(z) < 0.1


def test_too_little_left_is_refused_with_what_is_needed(run10, tmp_path, capsys):
    """
    A burst at the same time of every period: nothing to estimate those samples from.

    Then the periods it touches are dropped as before: exit 2, one line saying what is
    needed, nothing written.
    """
    bursts = [(1.0 + 8.192 * q, 0.09) for q in range(10)]
    write_robot_bag(tmp_path / 'all', run10, Imperfections(jitter=0.01, bursts=bursts))
    for mode in ((), ('--stream',)):
        assert main(['estimate', str(tmp_path / 'all'), '--out', str(tmp_path / 'o'),
                     *mode]) == 2
        err = capsys.readouterr().err
        assert err.count('\n') == 1 and 'Traceback' not in err
        assert '0 multisine periods without missing samples remain of 10' in err
        assert 'expected at least 2' in err and 'present in at least one of them' in err
        assert not (tmp_path / 'o').exists()
