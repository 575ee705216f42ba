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
docs/BENCHMARKS.md, generated from the runs themselves (``python -m benchmarks --markdown``).

Each section's run is stored as JSON under docs/benchmarks/<section>.json (a section's figures,
docs/benchmarks/img/<section>_*.png, are shown under its table): its rows, the
exact command, the date, the wall time and the machine (cores, CPU model, RAM, Python, load
average when it started). The page is rendered from all stored runs, so
``python -m benchmarks --markdown SECTION ...`` re-measures only those sections and keeps the
others as they were last measured. Nothing on the page is written by hand.
"""
from __future__ import annotations

import datetime
import json
import os
from pathlib import Path
import platform
import sys
from typing import Any, Callable, Iterable, Sequence

ROOT = Path(__file__).resolve().parent.parent
#: where the stored runs and the page live
RUNS_DIR = ROOT / 'docs' / 'benchmarks'
PAGE = ROOT / 'docs' / 'BENCHMARKS.md'
#: environment variables that change what a section measures (named in its command)
SETTINGS = ('FRF_BENCH_SCENES', 'KUKA_BC', 'FRF_IDENT_MIDDLEWARE', 'FRF_DEMO_BAG',
            'FRF_MODE_RUNS', 'FRF_MODE_SCENES', 'FRF_MODE_SEED')


def _cpu_model() -> str:
    try:
        for line in Path('/proc/cpuinfo').read_text().splitlines():
            if line.startswith('model name'):
                return line.split(':', 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _ram_gib() -> float:
    try:
        return os.sysconf('SC_PAGE_SIZE') * os.sysconf('SC_PHYS_PAGES') / 2 ** 30
    except (ValueError, OSError, AttributeError):
        return float('nan')


def machine() -> dict[str, Any]:
    """
    Describe the machine a section runs on.

    Returns
    -------
    dict
        ``cores``, ``cpu``, ``ram_gib``, ``python``, ``system`` and ``load_average`` (the
        1-minute load when the section started: the machine may be shared).

    """
    try:
        load = round(os.getloadavg()[0], 1)
    except OSError:
        load = None
    return {'cores': os.cpu_count(), 'cpu': _cpu_model(), 'ram_gib': round(_ram_gib(), 1),
            'python': platform.python_version(), 'system': f'{platform.system()} '
                                                           f'{platform.release()}',
            'load_average': load}


def command(names: Sequence[str]) -> str:
    """
    Return the command that re-measures ``names``, with the settings that were in force.

    Parameters
    ----------
    names : sequence of str
        The sections of this run.

    Returns
    -------
    str
        E.g. ``FRF_BENCH_SCENES=4 python -m benchmarks --markdown diagnosis``.

    """
    env = [f'{k}={portable(os.environ[k])}' for k in SETTINGS if os.environ.get(k)]
    return ' '.join(env + ['python -m benchmarks --markdown', *names])


def portable(value: str) -> str:
    """
    Return a setting as the page may show it: no path of the machine that measured.

    A path inside the repository becomes relative to it; any other absolute path becomes
    ``<path>`` (a data folder or a bag of that machine, which the reader substitutes).
    """
    if not os.path.isabs(value):
        return value
    try:
        return Path(value).resolve().relative_to(ROOT).as_posix()
    except ValueError:
        return '<path>'


def store(name: str, rows: Iterable[Sequence[str]], *, wall_s: float, cmd: str,
          started: dict[str, Any], runs_dir: Path = RUNS_DIR) -> Path:
    """
    Write one section's run to ``runs_dir/<name>.json``.

    Parameters
    ----------
    name : str
        The section.
    rows : iterable of (what, value, baseline, ratio)
        Its rows as the section returned them.
    wall_s : float
        Wall time of the section [s].
    cmd : str
        The command that ran it (:func:`command`).
    started : dict
        :func:`machine` when the section started.
    runs_dir : Path, optional
        Where runs are stored.

    Returns
    -------
    Path
        The JSON file.

    """
    runs_dir.mkdir(parents=True, exist_ok=True)
    path = runs_dir / f'{name}.json'
    now = datetime.datetime.now(datetime.timezone.utc)
    path.write_text(json.dumps({
        'section': name, 'command': cmd, 'date': now.strftime('%Y-%m-%d %H:%M UTC'),
        'wall_s': round(wall_s, 1), 'machine': started,
        'rows': [[str(c) for c in row] for row in rows]}, indent=1) + '\n')
    return path


def _cell(text: str) -> str:
    return str(text).replace('|', '\\|').replace('\n', ' ')


def _wall(seconds: float) -> str:
    return f'{seconds:.0f} s' if seconds < 120 else f'{seconds / 60:.1f} min'


def render(sections: dict[str, Callable[..., Any]], runs_dir: Path = RUNS_DIR) -> str:
    """
    Return the page: one block per stored section run, in the order of ``sections``.

    Parameters
    ----------
    sections : dict
        The registered sections (name -> function; its docstring's first line describes it).
    runs_dir : Path, optional
        Where the runs are stored.

    Returns
    -------
    str
        Markdown.

    """
    # a section's run is a record with its rows; the sweeps keep their per-scene records
    # beside them (a list per scene, e.g. diagnosis_sensor_runs_SEED.json), not sections
    stored = {p.stem: json.loads(p.read_text()) for p in sorted(runs_dir.glob('*.json'))}
    runs = {k: v for k, v in stored.items() if isinstance(v, dict) and 'rows' in v}
    order = [n for n in sections if n in runs] + sorted(n for n in runs if n not in sections)
    lines = ['# Benchmarks', '',
             '<!-- Generated by `python -m benchmarks --markdown [SECTION ...]` from '
             'docs/benchmarks/*.json. Do not edit by hand: re-run the section. -->', '',
             '**Generated file, never edited by hand.** Each section below was measured by the '
             "command it names, on the machine it names; each row puts frf_ident's figure "
             'beside a baseline measured in the same run. `python -m benchmarks --markdown '
             'SECTION ...` re-measures those sections and keeps the others.', '']
    missing = [n for n in sections if n not in runs]
    if missing:
        lines += ['Not measured yet: ' + ', '.join(f'`{n}`' for n in missing) + '.', '']
    for name in order:
        run = runs[name]
        m = run['machine']
        fn = sections.get(name)
        doc = (fn.__doc__ or '').strip().split('\n')[0] if fn else ''
        load = f', load average {m["load_average"]}' if m.get('load_average') is not None else ''
        lines += [f'## {name}', '']
        if doc:
            lines += [doc, '']
        lines += [f'Measured {run["date"]} by `{run["command"]}` in {_wall(run["wall_s"])} on '
                  f'{m["cores"]} cores ({m["cpu"]}), {m["ram_gib"]:g} GiB RAM, Python '
                  f'{m["python"]}, {m["system"]}{load}.', '',
                  '| measurement | frf_ident | baseline (same run) | ratio |',
                  '|---|---|---|---|']
        lines += ['| ' + ' | '.join(_cell(c) for c in (list(row) + [''] * 4)[:4]) + ' |'
                  for row in run['rows']]
        lines.append('')
        for png in sorted((runs_dir / 'img').glob(f'{name}_*.png')):
            lines += [f'![{png.stem}](benchmarks/img/{png.name})', '']
    return '\n'.join(lines)


def write_page(sections: dict[str, Callable[..., Any]], runs_dir: Path = RUNS_DIR,
               page: Path = PAGE) -> Path:
    """
    Render the stored runs into ``page``.

    Parameters
    ----------
    sections : dict
        The registered sections.
    runs_dir, page : Path, optional
        Where the runs are stored and the page goes.

    Returns
    -------
    Path
        ``page``.

    """
    page.write_text(render(sections, runs_dir))
    print(f'wrote {page.relative_to(ROOT) if page.is_relative_to(ROOT) else page}',
          file=sys.stderr)
    return page
