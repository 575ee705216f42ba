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
`frf-ident fit DIR_OR_FRF --out DIR [--order N] [--physical]`: a model fitted to an FRF.

``add_arguments`` and ``run`` as every command module (:mod:`frf_ident.cli.main`).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from frf_ident.cli.options import add_fit_arguments, add_output_arguments, fit_options

__all__ = ['HELP', 'LOG_TO_OUT', 'add_arguments', 'run']

#: the --out DIR also gets the DEBUG trace as DIR/<command>.log (cli/main.py)
LOG_TO_OUT = True
HELP = 'fit a parametric model (rational or physical two-mass) to a measured FRF'


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the source, ``--out``, the fit options and ``--band`` to the parser ``p``."""
    p.add_argument('source', type=Path, metavar='DIR_OR_FRF',
                   help='output directory of estimate (its frf.json) or an FRF file '
                        '(.json/.mat/.csv)')
    add_output_arguments(p)
    add_fit_arguments(p)
    p.add_argument('--band', type=float, nargs=2, metavar=('F_LOW', 'F_HIGH'),
                   help='fit only the lines in this band [Hz]')


def run(args: argparse.Namespace) -> int:
    """Fit and write the output directory; return 0 (bad input: FrfIdentInputError)."""
    from frf_ident.app.console import say
    from frf_ident.app.fit import fit_frf, OUTPUT_FILES
    from frf_ident.app.outdir import check_out
    out = check_out(args.out, outputs=OUTPUT_FILES, overwrite=args.overwrite)
    fit_frf(args.source, out, **vars(fit_options(args, args.band)), progress=say)
    return 0
