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
docs/commands.md, generated from the parser so that it cannot drift from the commands.

``python -m frf_ident.cli.docs > docs/commands.md`` writes it; test/cli/test_commands_doc.py
checks the file against :func:`render`. Every command of :data:`frf_ident.cli.main.COMMANDS`
gets its section: its ``HELP``, its ``DESCRIPTION`` (the module's paragraph, as
``frf-ident CMD --help`` shows it), whether it writes ``DIR/<command>.log`` (``LOG_TO_OUT``),
and a table of every argument with its help and default. Only this module's :data:`INTRO`
(output and errors, what all commands share) is written here; everything else comes from the
parser, so a command or option added anywhere appears after regeneration.
"""
from __future__ import annotations

import argparse
import sys

from frf_ident.cli.main import build_parser, COMMANDS

__all__ = ['INTRO', 'REGENERATE', 'main', 'render']

#: the command that regenerates docs/commands.md (said in the file and in the test)
REGENERATE = 'python -m frf_ident.cli.docs > docs/commands.md'

#: what every command shares: output and errors
INTRO = """\
Every command is one module of `frf_ident/cli` calling one application function of
`frf_ident/app`; the nodes call the same functions. The outside contract of the commands is
docs/CONTRACT.md §6 and §8.

## Output

Each command prints a few lines per stage: what it read, what it found, where it wrote it.
Long work shows a tqdm progress bar on stderr (only on a terminal). The global options go
before the command (table below): `-v` adds the DEBUG trace (e.g. every candidate the
diagnosis tries), `-q` keeps warnings and errors only and hides the bars. Commands whose
`--out` is a directory also write the whole trace, DEBUG included, to `DIR/<command>.log`:
{logged}. A command refused before it creates its directory leaves no log behind.
Library code logs through the standard `logging` module (`logging.getLogger(__name__)`):
stage summaries at INFO, search traces at DEBUG; `frf_ident/cli/logsetup.py` routes them.

## Errors

Errors on bad input: one line naming the file, field or value and what was expected, and
where one exists the option or value that makes the data usable; exit status 2 (1 for
failures; `FRF_IDENT_DEBUG=1` shows tracebacks). An excitation refused as unsafe for its robot
(e.g. desired chirp torques at the model's `torque_limit`) is such an input error too: one
line, exit 2, nothing run. Nothing already recorded is overwritten: `identify` and `import`
refuse an existing output path; a DIR holding an earlier run's outputs is refused by the
commands with `--overwrite` unless it is given.

## Data in the examples

The real data sets the tests, benchmarks and examples use are not part of the repository; each
is public: EMPS, the KUKA KR300 and the DaISy arm with their source in the header of their
import map (config/map_emps.yaml, config/map_kuka_kr300.yaml, config/map_daisy_arm.yaml), the
Silverbox from nonlinearbenchmark.org (Wigren & Schoukens, ECC 2013). The examples write their
path as `../shared/data/...`, where they lie beside the repository in the development setup;
give the path where you put them.
"""


def _cell(text: str) -> str:
    return ' '.join(str(text).split()).replace('|', '\\|')


def _name(action: argparse.Action) -> str:
    """Return how an argument is written: option strings and metavar, or the positional."""
    metavar = action.metavar if action.metavar is not None else (
        action.dest.upper() if action.option_strings else action.dest)
    if isinstance(metavar, tuple):
        metavar = ' '.join(metavar)
    if action.nargs == 0:
        return ', '.join(f'`{o}`' for o in action.option_strings)
    arg = {'+': f'{metavar} [{metavar} ...]', '*': f'[{metavar} ...]', '?': f'[{metavar}]'}.get(
        action.nargs, metavar if not isinstance(action.nargs, int) or isinstance(
            action.metavar, tuple) else ' '.join([metavar] * action.nargs))
    if not action.option_strings:
        return f'`{arg}`'
    return ', '.join(f'`{o} {arg}`' for o in action.option_strings)


def _meaning(action: argparse.Action) -> str:
    text = action.help or ''
    if action.choices is not None and not isinstance(action, argparse._SubParsersAction):
        text += f' (one of: {", ".join(map(str, action.choices))})'
    if action.required and action.option_strings:
        text += ' (required)'
    default = action.default
    if (default not in (None, False, argparse.SUPPRESS) and 'default' not in text
            and action.nargs != 0):
        text += f' (default: {default})'
    return _cell(text)


def _table(actions: list[argparse.Action]) -> list[str]:
    rows = [a for a in actions if not isinstance(a, (argparse._HelpAction,
                                                     argparse._SubParsersAction))]
    if not rows:
        return []
    return (['| argument | meaning |', '|---|---|']
            + [f'| {_name(a)} | {_meaning(a)} |' for a in rows] + [''])


def _groups(parser: argparse.ArgumentParser) -> list[str]:
    """Return the argument tables of a parser: its default groups, then each titled group."""
    default = {'positional arguments', 'options', 'optional arguments'}
    lines = _table([a for g in parser._action_groups if g.title in default
                    for a in g._group_actions])
    for g in parser._action_groups:
        if g.title not in default and g._group_actions:
            lines += [f'*{_cell(g.title)}*', ''] + _table(g._group_actions)
    return lines


def _synopsis(name: str, parser: argparse.ArgumentParser) -> str:
    parts = [f'frf-ident {name}']
    for a in parser._actions:
        if isinstance(a, argparse._HelpAction):
            continue
        if not a.option_strings:
            parts.append(_name(a).strip('`'))
        elif a.required:
            parts.append(_name(a).split(', ')[0].strip('`'))
    return ' '.join(parts) + ' [options]'


def render(parser: argparse.ArgumentParser | None = None) -> str:
    """
    Return docs/commands.md for a parser (default: the ``frf-ident`` parser).

    Parameters
    ----------
    parser : argparse.ArgumentParser, optional
        The program's parser (:func:`frf_ident.cli.main.build_parser`).

    Returns
    -------
    str
        The Markdown page, ending with a newline.

    """
    parser = parser or build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    logged = [n for n, m in COMMANDS.items() if getattr(m, 'LOG_TO_OUT', False)]
    lines = ['# Commands (`frf-ident`, also `python -m frf_ident`)', '',
             f'<!-- generated from the parser (frf_ident/cli) by `{REGENERATE}`: edit the help '
             f'texts there, not this file -->', '',
             INTRO.format(logged=', '.join(f'`{n}`' for n in logged)).rstrip(), '',
             '## Global options', '',
             f'`frf-ident [options] COMMAND ...`: {_cell(parser.description)}', '']
    lines += _groups(parser)
    lines += ['Commands: ' + ', '.join(f'[`{n}`](#frf-ident-{n})' for n in sub.choices), '']
    helps = {a.dest: a.help for a in sub._choices_actions}
    for name, cmd in sub.choices.items():
        module = COMMANDS.get(name)
        lines += [f'## frf-ident {name}', '', f'`{_synopsis(name, cmd)}`', '',
                  _cell(helps.get(name, '')).rstrip('.') + '.', '']
        desc = getattr(module, 'DESCRIPTION', None)
        if desc:
            lines += [' '.join(p.split()) for p in desc.split('\n\n')] + ['']
        if getattr(module, 'LOG_TO_OUT', False):
            lines += [f'Writes its whole trace to `DIR/{name}.log` (DIR: its `--out`).', '']
        lines += _groups(cmd)
    return '\n'.join(lines).rstrip() + '\n'


def main() -> int:
    """Print docs/commands.md on stdout (``python -m frf_ident.cli.docs``); return 0."""
    sys.stdout.write(render())
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
