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
"""docs/BENCHMARKS.md is rendered from stored runs: re-measuring one section keeps the others."""
import os

from benchmarks import markdown as md


def _section_a():
    """Measure section a."""


def _section_b():
    """Measure section b."""


SECTIONS = {'a': _section_a, 'b': _section_b, 'c': _section_b}


def test_rerunning_one_section_keeps_the_others(tmp_path, monkeypatch):
    monkeypatch.setenv('FRF_BENCH_SCENES', '4')
    runs, page = tmp_path / 'runs', tmp_path / 'BENCHMARKS.md'
    machine = md.machine()
    md.store('a', [('rows | with a bar', '1 s', 'base 2 s', '2x')], wall_s=3.0,
             cmd=md.command(['a']), started=machine, runs_dir=runs)
    md.store('b', [('b row', 'old', 'base', '')], wall_s=200.0, cmd=md.command(['b']),
             started=machine, runs_dir=runs)
    md.store('b', [('b row', 'new', 'base', '')], wall_s=200.0, cmd=md.command(['b']),
             started=machine, runs_dir=runs)
    text = md.write_page(SECTIONS, runs, page).read_text()
    assert 'never edited by hand' in text
    assert text.index('## a') < text.index('## b')          # the sections' own order
    assert 'Not measured yet: `c`.' in text
    assert '| rows \\| with a bar | 1 s | base 2 s | 2x |' in text
    assert '| b row | new | base |  |' in text and 'old' not in text
    assert 'by `FRF_BENCH_SCENES=4 python -m benchmarks --markdown b` in 3.3 min' in text
    assert f'on {os.cpu_count()} cores (' in text and 'GiB RAM, Python 3.' in text
    assert 'Measure section b.' in text


def test_a_sections_figures_are_shown_under_its_table(tmp_path):
    runs, page = tmp_path / 'runs', tmp_path / 'BENCHMARKS.md'
    md.store('a', [('row', '1', '2', '')], wall_s=1.0, cmd=md.command(['a']),
             started=md.machine(), runs_dir=runs)
    (runs / 'img').mkdir()
    for name in ('a_first.png', 'a_second.png', 'b_other.png'):
        (runs / 'img' / name).write_bytes(b'')
    text = md.write_page(SECTIONS, runs, page).read_text()
    block = text[text.index('## a'):]
    assert block.index('| row | 1 | 2 |') < block.index('![a_first](benchmarks/img/a_first.png)')
    assert '![a_second](benchmarks/img/a_second.png)' in block
    assert 'b_other' not in text                       # section b was not measured


def test_the_command_names_no_path_of_the_machine(monkeypatch, tmp_path):
    """A bag in the repository is named relative to it, a folder elsewhere as <path>."""
    monkeypatch.setenv('FRF_DEMO_BAG', str(md.ROOT / 'out' / 'demo' / 'graph' / 'bag'))
    monkeypatch.setenv('KUKA_BC', str(tmp_path))
    monkeypatch.setenv('FRF_BENCH_SCENES', '4')
    cmd = md.command(['diagnosis_demo'])
    assert cmd == ('FRF_BENCH_SCENES=4 KUKA_BC=<path> FRF_DEMO_BAG=out/demo/graph/bag '
                   'python -m benchmarks --markdown diagnosis_demo'), cmd
    assert str(tmp_path) not in cmd and str(md.ROOT) not in cmd


def test_a_sweeps_scene_records_beside_the_runs_are_no_section(tmp_path):
    # the sensor sweep keeps every scene's score as a list in docs/benchmarks/; rendering
    # the page read it as a section's run and failed (list indices must be integers)
    runs = tmp_path / 'runs'
    md.store('a', [('x', '1', '2', '')], wall_s=1.0, cmd='python -m benchmarks a',
             started=md.machine(), runs_dir=runs)
    (runs / 'a_runs_123.json').write_text('[{"seed": 123}]')
    text = md.render({'a': lambda: []}, runs)
    assert '## a' in text and 'a_runs_123' not in text
