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
"""`frf-ident diagnose DATA [DATA ...] --model M.yaml --out DIR`: what the model gets wrong."""
from __future__ import annotations

import argparse
from pathlib import Path

from frf_ident.cli.options import add_campaign_arguments, add_output_arguments, run_many

__all__ = ['DESCRIPTION', 'HELP', 'LOG_TO_OUT', 'add_arguments', 'run']

#: the DEBUG trace goes to ``--out``/<command>.log (``--out`` is a directory)
LOG_TO_OUT = True
HELP = ('compare data with the nominal model, name the effects it lacks, extend the model '
        '(report.json, extended_model.yaml, report.html)')
DESCRIPTION = """\
Sim-to-real diagnosis (docs/diagnosis.md): DIR/report.json (effects, unexplained, rejected,
held-out metrics per axis and per OTHER record), DIR/extended_model.yaml, DIR/report.html.
DATA/OTHER: a bag, or CSV/MAT with --map (e.g. config/map_kuka_kr300.yaml). An OTHER must name
its joints as DATA does. Stretches a bag lost (gaps of more than 3 joint-state samples) are
bridged for the filters and the simulation and left out of fit and validation (0.1 s either
side, plus 0.5 s of settling for experiments); a line names them. It ends with one line per
effect found, per unexplained axis, the held-out error of the nominal and the extended model,
and where it wrote; the search itself goes to the DEBUG trace (-v, DIR/diagnose.log)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """
    Add the arguments of ``diagnose``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; the arguments are added to it.

    """
    p.add_argument('data', nargs='+',
                   help='bag (identify or robot), or CSV/MAT with --map; or several, a folder, '
                        'a glob or @LIST.txt: a campaign, one folder per record under --out '
                        'plus summary.csv, summary.json, index.html')
    p.add_argument('--model', type=Path, required=True, help='nominal model file')
    add_output_arguments(p)
    add_campaign_arguments(p, '; with one input: processes that simulate its candidate '
                              'models at once (default 2; 1: one after the other, the same '
                              'result)')
    p.add_argument('--map', type=Path, default=None,
                   help='import map for CSV/MAT data (config/map_*.yaml), used for --validate too')
    p.add_argument('--validate', type=Path, action='extend', nargs='+', default=[],
                   metavar='OTHER',
                   help='other records of the same robot (any supported format): report '
                        'baseline and extended metrics on each (joints named as in DATA); '
                        'several after one flag, or the flag repeated')
    p.add_argument('--urdf', type=Path, default=None,
                   help="the robot's URDF (needs the pin package): gravity with the structure "
                        'of its kinematics, base parameters fitted jointly over the axes, and '
                        'per axis shares of its inertia and Coriolis torque (a load inertia '
                        'changing with the pose) and of its gravity (time-series route; joints '
                        'named as the model axes)')
    p.add_argument('--no-fd-fit', dest='fd_fit', action='store_false',
                   help='skip stage 0, the frequency-domain physical fit that names a linear '
                        'parameter mismatch before any simulation search (experiments route; '
                        'for comparison: the mismatch is then read in the FRF-shape stage)')


def run(args: argparse.Namespace) -> int:
    """
    Diagnose and print the effects found and the held-out metrics.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    int
        Exit status: 0 (success; a campaign: every record), 1 (a campaign: some failed).

    Raises
    ------
    FrfIdentInputError
        The data, map or model file or ``--out`` is unusable, or ``--out`` holds an earlier
        run's outputs without ``--overwrite`` (one line naming it).

    """
    from functools import partial

    from frf_ident.app.campaign_inputs import is_campaign
    from frf_ident.app.console import say
    from frf_ident.app.diagnose import diagnose, diagnose_columns, OUTPUT_FILES
    from frf_ident.app.diagnosis_summary import diagnosis_summary
    from frf_ident.app.outdir import check_out
    if is_campaign(args.data):
        # the records run in parallel: each one simulates its candidates one after the other
        task = partial(diagnose_columns, model_path=args.model, map_path=args.map,
                       validate=args.validate, urdf=args.urdf, jobs=1, fd_fit=args.fd_fit)
        return run_many(args, args.data, task, OUTPUT_FILES, 'diagnose')
    out = check_out(args.out, outputs=OUTPUT_FILES, overwrite=args.overwrite)
    # one record: --jobs is the processes that simulate its candidate models at once
    res = diagnose(Path(args.data[0]), args.model, out, map_path=args.map,
                   validate=args.validate, urdf=args.urdf, progress=say,
                   jobs=args.jobs, fd_fit=args.fd_fit)
    for line in diagnosis_summary(res, out):
        say(line)
    return 0
