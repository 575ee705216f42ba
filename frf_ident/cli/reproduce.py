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
"""`frf-ident reproduce paper --out DIR`: the seed paper's Section 6 example."""
from __future__ import annotations

import argparse

from frf_ident.app.reproduce import PAPER_REALISATIONS, PAPER_SEED
from frf_ident.cli.options import add_output_arguments
from frf_ident.errors import FrfIdentInputError

__all__ = ['DESCRIPTION', 'HELP', 'LOG_TO_OUT', 'add_arguments', 'run']

#: the DEBUG trace goes to ``--out``/<command>.log (``--out`` is a directory)
LOG_TO_OUT = True
HELP = "reproduce the seed paper's Section 6 example"
DESCRIPTION = """\
The paper's Section 6 example: three cases (linear, Fc = 50 N m, k2 = 1.7 k1) x two designs;
DIR/results.json (each estimate as freq_hz, re, im, the analytic FRF, the power ratio and the
paper's findings as numbers) and Figures 4/5 as PNG. The figures it prints are listed in
docs/method.md."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """
    Add the arguments of ``reproduce``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; the arguments are added to it.

    """
    p.add_argument('what', choices=['paper'])
    add_output_arguments(p)
    p.add_argument('--realisations', type=int, default=PAPER_REALISATIONS,
                   help=f'multisine n_p (paper: {PAPER_REALISATIONS})')
    p.add_argument('--seed', type=int, default=PAPER_SEED,
                   help=f'random phases of the multisine realisations (default {PAPER_SEED})')


def run(args: argparse.Namespace) -> int:
    """
    Reproduce Section 6, write results.json and the figures, print the findings.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    int
        Exit status: 0 (success).

    Raises
    ------
    FrfIdentInputError
        ``--realisations`` < 2, or ``--out`` is unusable or holds an earlier run's outputs
        without ``--overwrite``.

    """
    from frf_ident.app.console import say
    from frf_ident.app.outdir import check_out
    from frf_ident.app.reproduce import OUTPUT_FILES, reproduce_paper, write_results
    out = check_out(args.out, outputs=OUTPUT_FILES, overwrite=args.overwrite)
    if args.realisations < 2:
        raise FrfIdentInputError(f'--realisations={args.realisations}: need at least 2')
    results = reproduce_paper(n_realisations=args.realisations, seed=args.seed, progress=say)
    for path in write_results(results, out):
        say(f'wrote {path}')
    f = results['findings']
    say(f"linear: median |error| multisine {f['linear']['multisine']['median_abs_error_db']:.2g}"
        f" dB, chirp {f['linear']['chirp']['median_abs_error_db']:.2g} dB")
    say(f"Fc = 50 N m: resonance peak drop multisine {f['coulomb']['multisine_peak_drop_db']:.1f}"
        f" dB, chirp {f['coulomb']['chirp_peak_drop_db']:.1f} dB")
    say(f"k2 = 1.7 k1: resonance shift chirp {100 * f['stiffness']['chirp_resonance_shift']:+.1f}"
        f" %, multisine {100 * f['stiffness']['multisine_resonance_shift']:+.1f} %")
    say(f"multisine power / chirp power: {100 * f['power_ratio']:.1f} %")
    return 0
