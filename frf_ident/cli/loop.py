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
`frf-ident loop DIR_OR_FRF --out DIR [--model M.yaml | --kp .. --ki ..] [--propose BW PM]`.

``add_arguments`` and ``run`` as every command module (:mod:`frf_ident.cli.main`).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from frf_ident.cli.options import add_output_arguments

__all__ = ['DESCRIPTION', 'HELP', 'LOG_TO_OUT', 'add_arguments', 'run']

#: the --out DIR also gets the DEBUG trace as DIR/<command>.log (cli/main.py)
LOG_TO_OUT = True
HELP = 'check a velocity PI on the measured loop L = C P-hat: margins with uncertainty'
DESCRIPTION = """\
Checks a velocity PI on the measured loop L_i = C_i P_ii of every axis: gain, phase and
modulus margins and the crossover with their standard deviations from draws of the FRF
(docs/fit.md); for several axes the peak of the largest singular value of S = (I + P C)^-1.
Margins are read within the measured band: no -180 deg crossing there reads 'no gain margin
within the measured band', and |L| above 1 at the band edge is named. --propose BW PM reads PI
gains off the FRF for that crossover and phase margin and checks them on the measured loop:
per axis 'targets met' or which target is missed and by how much. Writes loop.json, loop.png,
loop.html."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the source, ``--out``, the controller and ``--propose`` to the parser ``p``."""
    p.add_argument('source', type=Path, metavar='DIR_OR_FRF',
                   help='output directory of estimate (its frf.json) or an FRF file')
    add_output_arguments(p)
    p.add_argument('--model', type=Path, default=None,
                   help='model file whose controller (discrete velocity PI) is checked')
    p.add_argument('--kp', type=float, nargs='+', help='PI kp per axis [N m s/rad]')
    p.add_argument('--ki', type=float, nargs='+', help='PI ki per axis [N m/rad]')
    p.add_argument('--dt', type=float, default=None, metavar='S',
                   help='sample time of a discrete PI for --kp/--ki (default: continuous)')
    p.add_argument('--propose', type=float, nargs=2, metavar=('BANDWIDTH_HZ', 'PM_DEG'),
                   help='propose PI gains for this crossover and phase margin and check them '
                        'on the measured FRF')
    p.add_argument('--draws', type=int, default=None,
                   help='Monte-Carlo draws of the FRF for the uncertainties (default 50)')


def run(args: argparse.Namespace) -> int:
    """Check the loop and write the output directory; return 0 (bad input: FrfIdentInputError)."""
    from frf_ident.app.loop import OUTPUT_FILES, run_loop
    from frf_ident.app.console import say
    from frf_ident.app.outdir import check_out
    from frf_ident.core.loop.check import DRAWS
    out = check_out(args.out, outputs=OUTPUT_FILES, overwrite=args.overwrite)
    run_loop(args.source, out, kp=args.kp, ki=args.ki, dt=args.dt, model=args.model,
             propose=tuple(args.propose) if args.propose else None,
             draws=DRAWS if args.draws is None else args.draws, progress=say)
    return 0
