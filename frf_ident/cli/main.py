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
`frf-ident` command line: an explicit table of subcommands, one module each.

Each module in :mod:`frf_ident.cli` has ``HELP``, ``add_arguments(parser)`` and ``run(args)``
(and may have ``DESCRIPTION``, the paragraph ``frf-ident CMD --help`` and docs/commands.md
show); ``run`` translates the arguments and calls one application function of
:mod:`frf_ident.app`. docs/commands.md is generated from :func:`build_parser`
(``python -m frf_ident.cli.docs > docs/commands.md``, :mod:`frf_ident.cli.docs`).

Exit status: 0 success, 2 usage/input error (one line on stderr naming the file, field or
value), 1 failure. Set FRF_IDENT_DEBUG=1 to see tracebacks of failures.

Output (:mod:`frf_ident.cli.logsetup`): a few INFO lines per stage on stdout; ``-v`` adds the
DEBUG trace, ``-q`` keeps warnings only and hides progress bars; a command whose module sets
``LOG_TO_OUT = True`` (its ``--out`` is a directory) also writes the DEBUG trace to
``DIR/<command>.log``.
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path
import sys

from frf_ident import __version__
from frf_ident.cli import (demo, diagnose, estimate, fit, identify, import_data, loop, reproduce,
                           tune)
from frf_ident.cli.logsetup import configured
from frf_ident.errors import FrfIdentInputError

__all__ = ['COMMANDS', 'OneLineParser', 'build_parser', 'main']

#: subcommand name -> its module (HELP, add_arguments, run); the order is the help order
COMMANDS = {
    'identify': identify,
    'estimate': estimate,
    'import': import_data,
    'fit': fit,
    'loop': loop,
    'tune': tune,
    'diagnose': diagnose,
    'demo': demo,
    'reproduce': reproduce,
}


class OneLineParser(argparse.ArgumentParser):
    """
    Argparse that reports a usage error in one line with exit status 2.

    Parameters
    ----------
    *args, **kwargs
        Those of :class:`argparse.ArgumentParser` (``prog``, ``description``,
        ``formatter_class`` ...): the constructor is inherited unchanged.

    """

    def error(self, message: str) -> None:
        """
        Print ``prog: error: message`` on stderr and exit with status 2 (no usage text).

        Parameters
        ----------
        message : str
            What argparse found wrong.

        Raises
        ------
        SystemExit
            Always, with status 2.

        """
        self.exit(2, f'{self.prog}: error: {message}\n')


def build_parser() -> argparse.ArgumentParser:
    """
    Return the parser of every subcommand in :data:`COMMANDS`.

    Returns
    -------
    argparse.ArgumentParser
        ``frf-ident`` with one subparser per command, in help order.

    """
    p = OneLineParser(prog='frf-ident', description='Closed-loop FRF identification of '
                                                    'flexible-joint robots (Saupe & Knoblach '
                                                    '2015). Every command and option: '
                                                    'docs/commands.md.')
    p.add_argument('--version', action='version', version=f'frf-ident {__version__}',
                   help='print the version and exit')
    out = p.add_mutually_exclusive_group()
    out.add_argument('-v', '--verbose', action='store_true',
                     help='also print the DEBUG trace (search steps) on the console')
    out.add_argument('-q', '--quiet', action='store_true',
                     help='print warnings and errors only; no progress bars')
    sub = p.add_subparsers(dest='command', required=True, parser_class=OneLineParser)
    for name, module in COMMANDS.items():
        module.add_arguments(sub.add_parser(
            name, help=module.HELP, description=getattr(module, 'DESCRIPTION', module.HELP),
            formatter_class=argparse.RawDescriptionHelpFormatter))
    return p


def main(argv: list[str] | None = None) -> int:
    """
    Run ``frf-ident`` with ``argv``; return the exit status.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        0 success, 2 input error (one line on stderr), 1 failure, 130 interrupted.

    Raises
    ------
    SystemExit
        From argparse: ``--help`` (status 0) or a usage error (status 2).

    """
    args = build_parser().parse_args(argv)
    module = COMMANDS[args.command]
    log_file = (Path(args.out) / f'{args.command}.log'
                if getattr(module, 'LOG_TO_OUT', False) and str(args.out).strip() else None)
    with configured(verbose=args.verbose, quiet=args.quiet, log_file=log_file):
        return _run(module, args)


def _run(module, args: argparse.Namespace) -> int:
    try:
        return module.run(args)
    except FrfIdentInputError as exc:
        print(f'frf-ident {args.command}: error: {exc}', file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f'frf-ident {args.command}: interrupted', file=sys.stderr)
        return 130
    except Exception as exc:  # a failure, not a user mistake
        if os.environ.get('FRF_IDENT_DEBUG'):
            raise
        print(f'frf-ident {args.command}: failed: {type(exc).__name__}: {exc} '
              f'(FRF_IDENT_DEBUG=1 shows the traceback)', file=sys.stderr)
        return 1


if __name__ == '__main__':
    raise SystemExit(main())
