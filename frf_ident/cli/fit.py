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
`frf-ident fit DIR_OR_FRF [...] --out DIR [--order N] [--physical]`: a model fitted to an FRF.

Several inputs (estimate folders, a campaign folder, a glob or @LIST.txt) are a campaign:
one fit per FRF, and with ``--physical`` over FRFs measured at poses the global pose model.
``add_arguments`` and ``run`` as every command module (:mod:`frf_ident.cli.main`).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from frf_ident.cli.options import (add_campaign_arguments, add_fit_arguments,
                                   add_output_arguments, fit_options, run_many)

__all__ = ['DESCRIPTION', 'HELP', 'LOG_TO_OUT', 'add_arguments', 'run']

#: the --out DIR also gets the DEBUG trace as DIR/<command>.log (cli/main.py)
LOG_TO_OUT = True
HELP = 'fit a parametric model (rational or physical two-mass) to a measured FRF'
DESCRIPTION = """\
A parametric model fitted to a measured FRF by maximum likelihood, weighted by the FRF's
variance (docs/fit.md). --physical: the two-mass flexible joint per axis and, on a square FRF of
two or more axes, all axes with the link coupling, with a fitted input delay (printed as
model.yaml's time_delay: the delay beyond the zero-order hold's half sample); model.yaml keeps
every other key of --model (else of the default model, which the output names). Otherwise a
common-denominator rational model (model.mat): the order given, or the lowest admissible one
the cost test accepts (else the lowest AIC); every fit is stable, a mode outside the band or at
the stability limit makes an order inadmissible, and the orders tried, their costs and the
runner-up are printed. Standard errors are Cramer-Rao, widened by a model-error bound where the
cost test fails; each fit ends with a verdict ('parameters describe the data' / 'structure
missing: treat errors as lower bounds'). Writes fit.json, fit.png, fit.html and model.yaml or
model.mat; with --model also the margins of its velocity PI (loop.json, loop.png). Several
inputs are a campaign (docs/CAMPAIGNS.md)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the sources, ``--out``, the campaign and fit options and ``--band`` to ``p``."""
    p.add_argument('source', nargs='+', metavar='DIR_OR_FRF',
                   help='output directory of estimate (its frf.json) or an FRF file '
                        '(.json/.mat/.csv); or several, an estimate campaign folder, a glob or '
                        '@LIST.txt: a campaign, one folder per FRF under --out plus '
                        'summary.csv, summary.json, index.html and, with --physical over '
                        'FRFs measured at >= 3 poses, the global pose model (pose_model.json, '
                        '.yaml, .urdf, pose_validation.csv)')
    add_output_arguments(p)
    add_campaign_arguments(p)
    add_fit_arguments(p)
    p.add_argument('--band', type=float, nargs=2, metavar=('F_LOW', 'F_HIGH'),
                   help='fit only the lines in this band [Hz]')
    p.add_argument('--no-figure', action='store_true',
                   help='leave fit.png out (a campaign of many FRFs: the figure takes about '
                        'ten times the fit)')
    p.add_argument('--urdf', type=Path, default=None,
                   help='the robot URDF whose inertial parameters the pose model fits '
                        "(default: the demo robot's)")


def run(args: argparse.Namespace) -> int:
    """Fit and write the output directory (a campaign: 1 where an FRF failed), else 0."""
    from functools import partial

    from frf_ident.app.campaign_inputs import is_campaign
    from frf_ident.app.console import say
    from frf_ident.app.fit import fit_columns, fit_frf, is_fit_input, OUTPUT_FILES
    from frf_ident.app.outdir import check_out
    kw = {**vars(fit_options(args, args.band)), 'figure': not args.no_figure}
    if is_campaign(args.source, is_fit_input):
        after, after_outputs = None, ()
        if args.physical:
            from frf_ident.app.pose_model import pose_model_after, POSE_MODEL_FILES
            after = partial(pose_model_after, urdf=args.urdf, model=args.model, progress=say)
            after_outputs = POSE_MODEL_FILES
        return run_many(args, args.source, partial(fit_columns, **kw), OUTPUT_FILES, 'fit',
                        after=after, after_outputs=after_outputs, member=is_fit_input)
    out = check_out(args.out, outputs=OUTPUT_FILES, overwrite=args.overwrite)
    fit_frf(Path(args.source[0]), out, progress=say, **kw)
    return 0
