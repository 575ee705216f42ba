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
Campaigns: ``frf-ident estimate`` / ``diagnose`` over many bags, serial, on processes, on Dask.

The reference is the serial run in this process: worker processes and a Dask LocalCluster
must write the same estimate files byte for byte, a broken bag must fail in its own row while
the others succeed, and the exit status must say that one failed.
"""
import csv
import json
from pathlib import Path
import subprocess
import sys

from frf_ident.app.campaign_inputs import campaign_dirs, expand_inputs, is_campaign
from frf_ident.bag import write_recording
from frf_ident.cli import main
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.simulation.runner import IdentificationConfig, run_identification
from frf_ident.io.model_file import load_model, load_plant
import pytest

pytestmark = pytest.mark.xdist_group('test_campaign')

#: the files of each bag's folder that carry the estimates (bode.png is drawn from them)
ESTIMATE_FILES = ('frf.json', 'estimates.json')


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    """Three short multisine bags of the embedded robot (1 realisation x 2 periods of 1 s)."""
    root = tmp_path_factory.mktemp('bags')
    model, _, ctrl = load_model(None)
    for seed in (1, 2, 3):
        cfg = IdentificationConfig(MultisineConfig(n_realisations=1, n_periods=2,
                                                   resolution_hz=1.0, compensate=False,
                                                   seed=seed), None)
        rec = run_identification(load_plant(None, model), ctrl, cfg)
        write_recording(rec, root / f'run_{seed}')
    return root


def _outputs(out: Path) -> dict:
    return {(d.name, f): (d / f).read_bytes() for d in sorted(out.iterdir()) if d.is_dir()
            for f in ESTIMATE_FILES}


def _rows(out: Path) -> list[dict]:
    with open(out / 'summary.csv') as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope='module')
def serial(bags, tmp_path_factory):
    """Run the serial reference over the folder of bags."""
    out = tmp_path_factory.mktemp('serial') / 'out'
    assert main(['estimate', str(bags), '--out', str(out), '--jobs', '1']) == 0
    return out


def test_serial_writes_one_folder_per_bag_and_the_summary(serial):
    rows = _rows(serial)
    assert [r['out'] for r in rows] == ['run_1', 'run_2', 'run_3']
    assert all(r['status'] == 'ok' and r['primary'] == 'multisine' for r in rows), rows
    doc = json.loads((serial / 'summary.json').read_text())
    assert doc['n_inputs'] == 3 and doc['n_failed'] == 0 and doc['route'] == 'serial'
    frf = json.loads((serial / 'run_2' / 'frf.json').read_text())
    assert int(rows[1]['lines']) == len(frf['freq_hz'])
    assert 'run_3/' in (serial / 'index.html').read_text()
    assert (serial / 'run_1' / 'log.txt').read_text().splitlines()[-1].startswith('ok after')


def test_two_processes_write_the_serial_bytes(bags, serial, tmp_path):
    out = tmp_path / 'out'
    assert main(['estimate', str(bags / 'run_*'), '--out', str(out), '--jobs', '2']) == 0
    got = _outputs(out)
    assert got.keys() == _outputs(serial).keys() and got == _outputs(serial)
    # pytest-xdist runs its own threads in this process: the workers are spawned here
    assert json.loads((out / 'summary.json').read_text())['route'].startswith('processes=2 (')


def test_forked_workers_of_the_command_write_the_serial_bytes(bags, serial, tmp_path):
    """
    The command itself runs one thread, so its workers are forked: the same bytes.

    Forking saves each worker the 1.7 s of importing what the command already imported
    (benchmarks/campaign.py measures the speed-up).
    """
    out = tmp_path / 'out'
    subprocess.run([sys.executable, '-m', 'frf_ident', '-q', 'estimate', str(bags / 'run_*'),
                    '--out', str(out), '--jobs', '2'], check=True, capture_output=True)
    assert _outputs(out) == _outputs(serial)
    assert json.loads((out / 'summary.json').read_text())['route'] == 'processes=2 (fork)'


def test_dask_local_cluster_writes_the_serial_bytes(bags, serial, tmp_path):
    pytest.importorskip('distributed')
    out = tmp_path / 'out'
    lst = bags / 'two.txt'     # entries relative to the list file
    lst.write_text('# two of the runs\nrun_3\n\nrun_1\n')
    assert main(['estimate', f'@{lst}', '--out', str(out), '--scheduler', 'local',
                 '--jobs', '2']) == 0
    ref = _outputs(serial)
    assert _outputs(out) == {k: v for k, v in ref.items() if k[0] in ('run_1', 'run_3')}
    assert json.loads((out / 'summary.json').read_text())['route'] == 'dask local=2'


def test_a_broken_bag_fails_in_its_row_and_the_others_go_on(bags, tmp_path, capsys):
    broken = tmp_path / 'broken'
    broken.mkdir()
    (broken / 'metadata.yaml').write_text('rosbag2_bagfile_information: {version: 9}\n')
    out = tmp_path / 'out'
    # serial: the same row wrapper runs in every worker, without the cost of starting one
    assert main(['estimate', str(bags / 'run_1'), str(broken), str(bags / 'run_2'),
                 '--out', str(out), '--jobs', '1']) == 1
    rows = _rows(out)
    assert [r['status'] for r in rows] == ['ok', 'refused', 'ok'], rows
    assert rows[1]['error'] and '\n' not in rows[1]['error'] and rows[1]['primary'] == ''
    assert 'broken' in capsys.readouterr().out


def test_a_missing_input_is_refused_before_any_work(bags, tmp_path, capsys):
    out = tmp_path / 'out'
    assert main(['estimate', str(bags / 'run_1'), str(tmp_path / 'nope'),
                 '--out', str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'nope: no such bag' in err and not out.exists()


def test_inputs_expand_and_name_their_folders(bags, tmp_path):
    lst = tmp_path / 'l.txt'
    lst.write_text(f'\n{bags}/run_2\n# comment\n{bags}/run_1\n')
    got = expand_inputs([f'@{lst}', str(bags / 'run_1'), str(bags / 'run_[23]')])
    assert got == [bags / 'run_2', bags / 'run_1', bags / 'run_3']
    assert campaign_dirs([Path('a/x'), Path('b/x'), Path('c/x.mcap')]) == ['x', 'x_2', 'x_3']
    assert not is_campaign([str(bags / 'run_1')]) and is_campaign([str(bags)])
