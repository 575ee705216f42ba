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
Every command's ``--out``: checked before any work, earlier outputs kept unless --overwrite.

A bad ``--out`` (empty, a file where a directory is wanted, a parent that is a file, not
writable) is one line on stderr and exit 2 before anything runs; estimate, diagnose and
reproduce refuse a directory holding their outputs of an earlier run unless ``--overwrite``,
which removes only their own earlier files.
"""
import os
from pathlib import Path

from frf_ident.cli import main
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
EMPS_MODEL = ROOT / 'config' / 'model_emps.yaml'
IDENTIFY = ['--realisations', '2', '--periods', '2', '--resolution', '0.5',
            '--chirp-duration', '8', '--max-iterations', '2']
MAP = 'frf_ident_map: 1\ntime: {column: t}\njoints:\n  - {name: j, position: q, effort: tau}\n'


@pytest.fixture(scope='module')
def data(tmp_path_factory):
    """Return a tiny CSV (4 s at 1 kHz), its map and the bag `frf-ident import` made of it."""
    root = tmp_path_factory.mktemp('out_data')
    t = np.arange(4000) / 1000.0
    csv = root / 'd.csv'
    np.savetxt(csv, np.c_[t, np.sin(2 * np.pi * t), np.sin(2 * np.pi * 5 * t)],
               delimiter=',', header='t,q,tau', comments='')
    mp = root / 'map.yaml'
    mp.write_text(MAP)
    bag = root / 'bag'
    assert main(['import', str(csv), '--map', str(mp), '--out', str(bag)]) == 0
    return {'csv': csv, 'map': mp, 'bag': bag}


def argv(command, data, out):
    """Return the arguments of ``command`` on the tiny data, writing to ``out``."""
    return {
        'estimate': ['estimate', str(data['bag']), '--out', out],
        'diagnose': ['diagnose', str(data['csv']), '--map', str(data['map']), '--model',
                     str(EMPS_MODEL), '--out', out],
        'reproduce': ['reproduce', 'paper', '--out', out, '--realisations', '2'],
        'identify': ['identify', '--out', out, *IDENTIFY],
        'import': ['import', str(data['csv']), '--map', str(data['map']), '--out', out],
        'demo': ['demo', '--out', out],
    }[command]


def one_line(capsys, command):
    """Return the one stderr line of a refused command (no traceback)."""
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err, err
    assert err.startswith(f'frf-ident {command}: error: --out '), err
    return err


ALL = ['estimate', 'diagnose', 'reproduce', 'identify', 'import', 'demo']
DIRS = ['estimate', 'diagnose', 'reproduce', 'demo']          # an output directory
WRITERS = ['estimate', 'diagnose', 'reproduce']               # with --overwrite


@pytest.mark.parametrize('command', ALL)
def test_parent_that_is_a_file_is_refused_before_any_work(data, tmp_path, capsys, command):
    (tmp_path / 'existing_file').write_text('mine')
    out = str(tmp_path / 'existing_file' / 'sub')
    assert main(argv(command, data, out)) == 2
    err = one_line(capsys, command)
    assert out in err and "existing_file' is a file, not a directory" in err
    assert (tmp_path / 'existing_file').read_text() == 'mine'
    assert capsys.readouterr().out == ''            # nothing ran


@pytest.mark.parametrize('command', DIRS)
def test_file_where_a_directory_is_wanted_is_refused(data, tmp_path, capsys, command):
    out = tmp_path / 'existing_file'
    out.write_text('mine')
    assert main(argv(command, data, str(out))) == 2
    assert 'is a file, not a directory; expected an output directory' in one_line(capsys,
                                                                                  command)
    assert out.read_text() == 'mine'


@pytest.mark.parametrize('command', ['identify', 'import'])
def test_existing_bag_path_is_refused(data, tmp_path, capsys, command):
    out = tmp_path / 'existing_file'
    out.write_text('mine')
    assert main(argv(command, data, str(out))) == 2
    assert 'already exists; choose a new bag path' in one_line(capsys, command)
    assert out.read_text() == 'mine'


@pytest.mark.parametrize('command', ALL)
def test_empty_out_is_refused_not_the_current_directory(data, tmp_path, capsys, monkeypatch,
                                                        command):
    monkeypatch.chdir(tmp_path)
    assert main(argv(command, data, '')) == 2
    assert "--out '': empty" in one_line(capsys, command)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize('command', ALL)
def test_directory_that_is_not_writable_is_refused(data, tmp_path, capsys, monkeypatch,
                                                   command):
    locked = tmp_path / 'locked'
    locked.mkdir()
    real = os.access
    monkeypatch.setattr(os, 'access', lambda p, mode, *a, **k: False if Path(p) == locked
                        else real(p, mode, *a, **k))
    assert main(argv(command, data, str(locked / 'o'))) == 2
    assert f"directory '{locked}' is not writable" in one_line(capsys, command)
    assert list(locked.iterdir()) == []


@pytest.mark.parametrize('command, name', [('estimate', 'frf.json'),
                                           ('diagnose', 'report.json'),
                                           ('reproduce', 'results.json')])
def test_earlier_outputs_are_refused_without_overwrite(data, tmp_path, capsys, command, name):
    out = tmp_path / 'o'
    out.mkdir()
    (out / name).write_text('earlier run')
    assert main(argv(command, data, str(out))) == 2
    err = one_line(capsys, command)
    assert f"--out '{out}' already holds {name} of an earlier run" in err
    assert '--overwrite' in err
    assert (out / name).read_text() == 'earlier run'
    assert sorted(p.name for p in out.iterdir()) == [name]


@pytest.mark.parametrize('command', WRITERS)
def test_directory_without_outputs_is_accepted(data, tmp_path, command):
    """An existing directory with other files (or empty) is no earlier run: it is used."""
    out = tmp_path / 'o'
    out.mkdir()
    (out / 'notes.txt').write_text('mine')
    assert main(argv(command, data, str(out))) == 0
    assert (out / 'notes.txt').read_text() == 'mine'


def test_estimate_overwrite_replaces_only_its_own_files(data, tmp_path):
    out = tmp_path / 'o'
    assert main(argv('estimate', data, str(out))) == 0
    for name in ('frf.json', 'estimates.json', 'summary.json', 'bode.png'):
        (out / name).write_text('stale')
    (out / 'notes.txt').write_text('mine')
    assert main(argv('estimate', data, str(out)) + ['--overwrite']) == 0
    for name in ('frf.json', 'estimates.json', 'summary.json', 'bode.png'):
        assert (out / name).read_bytes() != b'stale', name
    assert (out / 'notes.txt').read_text() == 'mine'


def test_diagnose_overwrite_removes_a_stale_figure_of_the_earlier_run(data, tmp_path):
    """A time-series diagnosis draws no bode.png: an experiments run's one must not stay."""
    out = tmp_path / 'o'
    out.mkdir()
    for name in ('report.json', 'bode.png', 'residual.png'):
        (out / name).write_text('stale')
    (out / 'notes.txt').write_text('mine')
    assert main(argv('diagnose', data, str(out)) + ['--overwrite']) == 0
    assert not (out / 'bode.png').exists()
    assert (out / 'report.json').read_text().startswith('{')
    assert (out / 'residual.png').read_bytes()[:4] == b'\x89PNG'
    assert (out / 'notes.txt').read_text() == 'mine'


def test_reproduce_overwrite_replaces_results(data, tmp_path):
    out = tmp_path / 'o'
    out.mkdir()
    (out / 'results.json').write_text('stale')
    (out / 'notes.txt').write_text('mine')
    assert main(argv('reproduce', data, str(out)) + ['--overwrite']) == 0
    assert (out / 'results.json').read_text().startswith('{')
    assert (out / 'notes.txt').read_text() == 'mine'


def test_overwrite_still_checks_the_path(data, tmp_path, capsys):
    (tmp_path / 'existing_file').write_text('mine')
    assert main(argv('estimate', data, str(tmp_path / 'existing_file'))
                + ['--overwrite']) == 2
    assert 'is a file, not a directory' in one_line(capsys, 'estimate')
    assert (tmp_path / 'existing_file').read_text() == 'mine'


@pytest.mark.parametrize('command', WRITERS)
def test_help_documents_overwrite(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([command, '--help'])
    assert exc.value.code == 0
    assert '--overwrite' in capsys.readouterr().out


def test_a_joint_given_twice_is_refused(data, tmp_path, capsys):
    """--joints q,q gave a '2x2' FRF of one joint (or a wrong 'no periods' cause)."""
    assert main(['estimate', str(data['bag']), '--out', str(tmp_path / 'e'),
                 '--joints', 'q,q']) == 2
    err = capsys.readouterr().err
    assert err.strip() == 'frf-ident estimate: error: --joints q,q: q given twice', err
