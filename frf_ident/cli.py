"""`frf-ident` command line (CONTRACT section 6).

Exit status: 0 success, 2 usage/input error (one line on stderr naming the file, field or
value), 1 failure. Set FRF_IDENT_DEBUG=1 to see tracebacks of failures.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Callable

from frf_ident.errors import FrfIdentInputError

_COMMANDS: dict[str, Callable[[argparse.Namespace], int]] = {}


def command(name: str):
    def register(fn):
        _COMMANDS[name] = fn
        return fn
    return register


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2 (argparse prints usage too)
        self.exit(2, f'frf-ident: error: {message}\n')


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog='frf-ident', description='Closed-loop FRF identification of flexible-joint '
                                              'robots (Saupe & Knoblach 2015).')
    sub = p.add_subparsers(dest='command', required=True, parser_class=_Parser)

    s = sub.add_parser('reproduce', help="reproduce the seed paper's Section 6 example")
    s.add_argument('what', choices=['paper'])
    s.add_argument('--out', required=True, type=Path, help='output directory')
    s.add_argument('--realisations', type=int, default=30, help='multisine n_p (paper: 30)')
    s.add_argument('--seed', type=int, default=2015)

    from frf_ident import commands  # noqa: F401  (registers further subcommands)
    for name, (help_text, add_args) in commands.SUBCOMMANDS.items():
        add_args(sub.add_parser(name, help=help_text))
    return p


@command('reproduce')
def _reproduce(args: argparse.Namespace) -> int:
    from frf_ident.reproduce import reproduce_paper, write_results
    if args.realisations < 2:
        raise FrfIdentInputError(f'--realisations={args.realisations}: need at least 2')
    results = reproduce_paper(n_realisations=args.realisations, seed=args.seed,
                              progress=lambda m: print(m, flush=True))
    for path in write_results(results, args.out):
        print(f'wrote {path}')
    f = results['findings']
    print(f"linear: median |error| multisine {f['linear']['multisine']['median_abs_error_db']:.2g}"
          f" dB, chirp {f['linear']['chirp']['median_abs_error_db']:.2g} dB")
    print(f"Fc = 50 N m: resonance peak drop multisine "
          f"{f['coulomb']['multisine_peak_drop_db']:.1f} dB, chirp "
          f"{f['coulomb']['chirp_peak_drop_db']:.1f} dB")
    print(f"k2 = 1.7 k1: resonance shift chirp {100 * f['stiffness']['chirp_resonance_shift']:+.1f}"
          f" %, multisine {100 * f['stiffness']['multisine_resonance_shift']:+.1f} %")
    print(f"multisine power / chirp power: {100 * f['power_ratio']:.1f} %")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return _COMMANDS[args.command](args)
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
