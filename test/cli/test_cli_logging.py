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
Output for people: INFO stage lines on the console, the DEBUG trace with -v and in DIR/<cmd>.log.

`frf-ident reproduce paper` at 2 realisations (a few seconds) is the command: its per-experiment
lines are DEBUG, its per-case summaries INFO.
"""
import logging

from frf_ident.cli.logsetup import configured
from frf_ident.cli.main import COMMANDS, main
import pytest

DEBUG_LINE = 'linear: multisine (2 realisations'      # app/reproduce.py, per experiment
INFO_LINE = 'linear: multisine 2 x'                    # app/reproduce.py, per case


@pytest.fixture(scope='module')
def run(tmp_path_factory):
    """Run reproduce once with the default console; return its directory and what it said."""
    import contextlib
    import io
    out = tmp_path_factory.mktemp('logging') / 'paper'
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(['reproduce', 'paper', '--realisations', '2', '--out', str(out)]) == 0
    return out, buf.getvalue()


def test_default_console_shows_stages_not_the_trace(run):
    _, said = run
    assert INFO_LINE in said and DEBUG_LINE not in said
    assert 'wrote ' in said
    assert len(said.splitlines()) <= 15, said


def test_log_file_holds_the_trace(run):
    out, _ = run
    log = (out / 'reproduce.log').read_text()
    assert DEBUG_LINE in log and INFO_LINE in log and ' DEBUG ' in log


@pytest.mark.parametrize('flags, shown', [([], ['stage']), (['-v'], ['trace', 'stage']),
                                          (['-q'], ['problem'])])
def test_console_levels_of_the_global_options(monkeypatch, capsys, flags, shown):
    """-v adds the DEBUG trace, -q keeps warnings only; the options come before the command."""
    def fake_run(args):
        log = logging.getLogger('frf_ident.app.fake')
        log.debug('trace')
        log.info('stage')
        log.warning('problem')
        return 0
    monkeypatch.setattr(COMMANDS['reproduce'], 'run', fake_run)
    assert main(flags + ['reproduce', 'paper', '--out', '']) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines == [w for w in ('trace', 'stage', 'problem') if w in shown + ['problem']]


def test_a_command_refused_before_its_directory_exists_leaves_no_log(tmp_path, capsys):
    out = tmp_path / 'never'
    assert main(['reproduce', 'paper', '--realisations', '1', '--out', str(out)]) == 2
    assert not out.exists()
    assert capsys.readouterr().err.count('\n') == 1


def test_lines_logged_before_the_directory_exists_are_written_once_it_does(tmp_path):
    out = tmp_path / 'later' / 'x.log'
    log = logging.getLogger('frf_ident.test')
    with configured(log_file=out):
        log.debug('before the directory')
        assert not out.parent.exists()
        out.parent.mkdir()
        log.info('after it')
    lines = out.read_text().splitlines()
    assert [line.split(': ', 1)[1] for line in lines] == ['before the directory', 'after it']
    assert not logging.getLogger('frf_ident').handlers      # removed when the command ends


def test_a_dict_config_elsewhere_does_not_silence_the_command(capsys):
    """import-linter's dictConfig (test_layout) disabled the package's loggers: no output."""
    import logging.config
    log = logging.getLogger('frf_ident.app.earlier')
    logging.config.dictConfig({'version': 1})             # disables every existing logger
    assert log.disabled
    with configured():
        log.info('still shown')
    assert capsys.readouterr().out == 'still shown\n'
