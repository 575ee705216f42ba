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
`frf-ident tune FRF_OR_CAMPAIGN --out DIR [--model M.yaml | --rate HZ] [--targets K=V ...]`.

``add_arguments`` and ``run`` as every command module (:mod:`frf_ident.cli.main`).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from frf_ident.cli.options import add_output_arguments

__all__ = ['DESCRIPTION', 'HELP', 'LOG_TO_OUT', 'add_arguments', 'parse_targets', 'run']

#: the --out DIR also gets the DEBUG trace as DIR/<command>.log (cli/main.py)
LOG_TO_OUT = True
HELP = ('notch filters at the resonances and PI gains per axis shaped on the measured FRFs '
        '(worst case over a campaign), exported for ros2_control')
DESCRIPTION = """\
PI gains and notch / low-pass filters per axis, shaped on the measured FRFs (the method is
docs/tune.md, the files docs/CONTRACT.md §8). Several FRFs (a folder of estimate folders, a
glob, @LIST.txt) are one per pose or amplitude, on the same lines: the setting must hold at
all of them. --model gives the controller's rate, its PI (checked as 'before') and the base
of tuned_model.yaml; without it --rate. Prints per axis its resonances and their band, the
weight W(s), the setting, and where a target is missed the best achievable with one sentence
on what binds (target, pose, frequency; the phase of plant, delay, PI and filters there);
then the worst margins over the poses and the MIMO sensitivity peak before and after. Writes
tune.json, tune.html, tune.png, pid_controller.yaml (ros2_controllers pid_controller),
filters.yaml (chained_filter_controller), control_objects.pkl (python-control) and with
--model tuned_model.yaml; --verify identifies the model's simulation again with the tuned
controller and compares (DIR/verify/verify.json)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the sources, ``--out``, the controller, the targets and ``--verify`` to ``p``."""
    p.add_argument('source', nargs='+', metavar='FRF_OR_CAMPAIGN',
                   help='output directory of estimate (its frf.json) or an FRF file; or '
                        'several, a folder of them, a glob or @LIST.txt: one FRF per pose or '
                        'amplitude, the setting must hold at all of them')
    add_output_arguments(p)
    p.add_argument('--model', type=Path, default=None,
                   help="model file: its sample_rate, its controller (checked as 'before') "
                        'and the base of tuned_model.yaml')
    p.add_argument('--rate', type=float, default=None, metavar='HZ',
                   help="the controller's sample rate without --model [Hz]")
    p.add_argument('--targets', nargs='+', default=[], metavar='KEY=VALUE',
                   help='crossover_hz (default: as high as the margins allow), '
                        'phase_margin_deg (45), gain_margin_db (6), modulus_margin (0.5), '
                        'robust (no: |W T| reported; yes: |W T| < 1 required too)')
    p.add_argument('--modes', choices=('physical', 'rational'), default='physical',
                   help='fit of the resonances: the two-mass model per axis (default) or the '
                        'rational model (other plants)')
    p.add_argument('--order', type=int, default=None,
                   help='order of the rational mode fit (default: by the cost test)')
    p.add_argument('--nominal', default=None, metavar='NAME',
                   help='the nominal pose (input name); default the one nearest to the others')
    p.add_argument('--draws', type=int, default=None,
                   help='Monte-Carlo draws of the nominal FRF for the margins (default 50)')
    p.add_argument('--verify', action='store_true',
                   help="identify --model's robot again with the tuned controller (its "
                        'simulation) and compare the measured margins with the predicted ones')
    p.add_argument('--verify-band', type=float, nargs=2, default=None,
                   metavar=('F_LOW', 'F_HIGH'),
                   help="multisine band of --verify's identification [Hz] (default identify's "
                        '2 60): the band the tuned FRF was measured with')


def parse_targets(items: list[str]):
    """
    Return the TuneTargets of ``--targets KEY=VALUE ...``.

    Parameters
    ----------
    items : list of str
        ``crossover_hz=10`` etc.; ``robust=yes|no``.

    Returns
    -------
    TuneTargets
        The targets (defaults for keys not given).

    Raises
    ------
    FrfIdentInputError
        An unknown key, a value that is not a number, or a target out of range.

    """
    from dataclasses import fields

    from frf_ident.core.loop.targets import TuneTargets
    from frf_ident.errors import FrfIdentInputError
    keys = [f.name for f in fields(TuneTargets)]
    kw: dict[str, object] = {}
    for item in items:
        key, sep, val = item.partition('=')
        if not sep or key not in keys:
            raise FrfIdentInputError(f'--targets {item}: expected KEY=VALUE with KEY one of '
                                     f'{", ".join(keys)}')
        if key == 'robust':
            if val.lower() not in ('yes', 'no', 'true', 'false'):
                raise FrfIdentInputError(f'--targets {item}: expected robust=yes or robust=no')
            kw[key] = val.lower() in ('yes', 'true')
            continue
        try:
            kw[key] = float(val)
        except ValueError:
            raise FrfIdentInputError(f'--targets {item}: {val!r} is not a number') from None
    try:
        return TuneTargets(**kw)
    except ValueError as err:
        raise FrfIdentInputError(f'--targets: {err}') from err


def run(args: argparse.Namespace) -> int:
    """Tune and write the output directory; return 0 (bad input: FrfIdentInputError)."""
    from frf_ident.app.console import say
    from frf_ident.app.outdir import check_out
    from frf_ident.app.tune import run_tune
    from frf_ident.app.tune_files import OUTPUT_FILES
    from frf_ident.core.loop.check import DRAWS
    targets = parse_targets(args.targets)
    out = check_out(args.out, outputs=OUTPUT_FILES + ('verify',), overwrite=args.overwrite)
    run_tune(args.source, out, targets=targets, model=args.model, rate=args.rate,
             modes=args.modes, order=args.order, nominal=args.nominal,
             draws=DRAWS if args.draws is None else args.draws, verify=args.verify,
             verify_band=tuple(args.verify_band) if args.verify_band else None, progress=say)
    return 0
