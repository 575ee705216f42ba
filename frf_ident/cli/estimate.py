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
"""`frf-ident estimate BAG [BAG ...] --out DIR`: offline FRF estimation from bags."""
from __future__ import annotations

import argparse
from pathlib import Path

from frf_ident.cli.options import (add_campaign_arguments, add_fit_arguments,
                                   add_output_arguments, fit_options, run_many)

__all__ = ['DESCRIPTION', 'HELP', 'LOG_TO_OUT', 'add_arguments', 'excitation_options',
           'run']

#: the DEBUG trace goes to ``--out``/<command>.log (``--out`` is a directory)
LOG_TO_OUT = True
HELP = 'estimate FRFs offline from a bag'
DESCRIPTION = """\
Offline estimation: DIR/frf.json = {inputs, outputs, freq_hz, re, im, noise_variance,
total_variance} with re/im shaped (n_out, n_in, n_freq); DIR/estimates.json (every estimate
the bag supports: multisine reference-based / plain / uncompensated, chirp, or the LPM and its
Welch H1); DIR/summary.json (timing findings, experiment summary); DIR/bode.png; with a
multisine DIR/distortion.png, and DIR/robust_lpm.png where one realisation of a detected
multisine has two or more steady periods. A bag without descriptors is detected block by block
(--window; its excitation given by --input, --multisine-period, --chirp, --band, --method):
docs/bags.md, docs/LPM.md. A segment that started but never ended is left out with a warning; a
bag of several poses (identify --poses --one-bag) is estimated pose by pose into DIR/pose_NN/
(docs/CAMPAIGNS.md). --fit fits a model to the estimate as `fit` does."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """
    Add the arguments of ``estimate``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; the arguments are added to it.

    """
    from frf_ident.core.estimation.detected import DEFAULT_WINDOW_S, DEFAULT_WINDOW_SAMPLES
    from frf_ident.core.estimation.excitation_options import LPM_METHODS
    p.add_argument('bag', nargs='+',
                   help='a bag; or several, a folder of bags, a glob or @LIST.txt (one per '
                        'line): a campaign, one folder per bag under --out plus summary.csv, '
                        'summary.json, index.html and the FRF map (frf_map.csv, frf_map.png: '
                        'resonance and antiresonance per axis and pose); with --compare-levels '
                        'two or more records of the same channels at different levels')
    add_output_arguments(p)
    add_campaign_arguments(p)
    p.add_argument('--joints', help='comma list of joint names to analyse (default: all)')
    p.add_argument('--t-range', type=float, nargs=2, metavar=('START', 'END'),
                   help='analyse only this time range [s]')
    p.add_argument('--compare-levels', action='store_true',
                   help='records of the same channels at different excitation levels: '
                        'estimate each and compare FRF change per line, modes and distortion')
    p.add_argument('--primary', default=None,
                   help='which estimate goes to frf.json (default: multisine, else chirp)')
    p.add_argument('--stream', action='store_true',
                   help='read the bag window by window in bounded memory (automatic when the '
                        'bag would need more than --max-memory)')
    p.add_argument('--max-memory', type=float, default=None, metavar='MB',
                   help='memory the in-memory reader may use before streaming (default: a '
                        'quarter of RAM, at most 4096)')
    p.add_argument('--window', type=float, default=None, metavar='S',
                   help=f'block length [s] in which a bag without experiment descriptors is '
                        f'detected and estimated, in memory and streamed (default '
                        f'{DEFAULT_WINDOW_S:g} s, or {DEFAULT_WINDOW_SAMPLES:,} samples where the '
                        f'record is sampled slower; must hold a few multisine periods or a '
                        f'whole chirp)')
    f = p.add_argument_group('a model fitted to the estimate (what `frf-ident fit` does, into '
                             'the same folder)')
    f.add_argument('--fit', action='store_true',
                   help='fit a model to frf.json: fit.json, fit.png, fit.html and model.yaml '
                        '(--physical) or model.mat; with --model also the margins of its '
                        'velocity PI (loop.json, loop.png)')
    add_fit_arguments(f)
    g = p.add_argument_group('excitation of a bag without /frf/experiment descriptors '
                             '(what `detected:` prints; replaces detection)')
    g.add_argument('--input', metavar='JOINT', help='the excited joint (the only input)')
    kind = g.add_mutually_exclusive_group()
    kind.add_argument('--multisine-period', type=float, metavar='SECONDS',
                      help='multisine period [s]; block and lines are found in the data')
    kind.add_argument('--chirp', type=float, nargs=2, metavar=('F_LOW', 'F_HIGH'),
                      help='exponential chirp from F_LOW to F_HIGH [Hz] (needs --chirp-time)')
    g.add_argument('--band', type=float, nargs=2, metavar=('F_LOW', 'F_HIGH'),
                   help='analyse only the multisine lines in this band [Hz]')
    g.add_argument('--chirp-time', type=float, nargs=2, metavar=('T0', 'T1'),
                   help='sweep start and end [s from the first analysed sample]')
    g.add_argument('--method', choices=LPM_METHODS, default=None,
                   help='lpm: the excitation is not periodic (PRBS, noise, normal motion); '
                        'estimate with the Local Polynomial Method without detecting (used '
                        'anyway where no multisine or chirp is found), indirectly through '
                        'the reference r where it is recorded; lpm-direct: y on u directly '
                        '(biased towards -1/C where noise is fed back)')


def excitation_options(args: argparse.Namespace):
    """
    Return the --input/--multisine-period/--band/--chirp/--chirp-time/--method options.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    ExcitationOptions
        :class:`~frf_ident.core.estimation.excitation_options.ExcitationOptions` (None where an
        option is not given).

    """
    from frf_ident.core.estimation.excitation_options import ExcitationOptions

    def tup(v):
        return tuple(v) if v is not None else None
    return ExcitationOptions(input=args.input, multisine_period=args.multisine_period,
                             band=tup(args.band), chirp=tup(args.chirp),
                             chirp_time=tup(args.chirp_time), method=args.method)


def run(args: argparse.Namespace) -> int:
    """
    Estimate and write the output directory.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    int
        Exit status: 0 (success; a campaign: every bag), 1 (a campaign: some bag failed).

    Raises
    ------
    FrfIdentInputError
        ``--out`` is unusable or holds an earlier run's outputs without ``--overwrite``, or
        the bag cannot be read or does not support an estimate (one line naming it).

    """
    from functools import partial

    from frf_ident.app.campaign_inputs import is_campaign
    from frf_ident.app.console import say
    from frf_ident.app.estimate import estimate_bag, estimate_columns, OUTPUT_FILES
    from frf_ident.app.fit import OUTPUT_FILES as FIT_FILES
    from frf_ident.app.frf_map import MAP_FILES, write_frf_map
    from frf_ident.app.outdir import check_out
    from frf_ident.errors import FrfIdentInputError
    if args.compare_levels and len(args.bag) < 2:
        raise FrfIdentInputError('--compare-levels: expected two or more bags')
    alone = [o for o, v in (('--order', args.order is not None), ('--physical', args.physical),
                            ('--delay', args.delay is not None),
                            ('--model', args.model is not None)) if v]
    if alone and not args.fit:
        raise FrfIdentInputError(f'{alone[0]}: only with --fit')
    if args.fit and args.compare_levels:
        raise FrfIdentInputError('--fit: not with --compare-levels (fit each folder with '
                                 '`frf-ident fit`)')
    joints = [j.strip() for j in args.joints.split(',')] if args.joints else None
    kw = {'joints': joints, 't_range': tuple(args.t_range) if args.t_range else None,
          'primary': args.primary, 'options': excitation_options(args), 'stream': args.stream,
          'max_memory_mb': args.max_memory, 'window_s': args.window,
          'fit': fit_options(args) if args.fit else None}
    outputs = OUTPUT_FILES + (FIT_FILES if args.fit else ())
    if args.compare_levels:
        from frf_ident.app.compare_levels import compare_bags, COMPARE_FILES
        out = check_out(args.out, outputs=COMPARE_FILES, overwrite=args.overwrite)
        compare_bags([Path(b) for b in args.bag], out, progress=say, **kw)
        return 0
    if is_campaign(args.bag):
        return run_many(args, args.bag, partial(estimate_columns, **kw), outputs,
                        'estimate', after=write_frf_map, after_outputs=MAP_FILES)
    from frf_ident.app.pose_bag import bag_poses, estimate_pose_columns
    spans = bag_poses(Path(args.bag[0]))
    if spans is not None:                   # identify --poses --one-bag: a campaign of poses
        if args.t_range:
            raise FrfIdentInputError(f'--t-range with {args.bag[0]}: a bag of several poses is '
                                     f"estimated over each pose's own time range; leave "
                                     f'--t-range out')
        kw.pop('t_range')
        say(f'{args.bag[0]}: {len(spans)} poses, estimated one by one')
        return run_many(args, [s.name for s in spans],
                        partial(estimate_pose_columns, bag=Path(args.bag[0]), spans=spans, **kw),
                        outputs, 'estimate', after=write_frf_map, after_outputs=MAP_FILES,
                        member=None, inputs=[Path(s.name) for s in spans])
    out = check_out(args.out, outputs=outputs, overwrite=args.overwrite)
    estimate_bag(Path(args.bag[0]), out, progress=say, **kw)
    return 0
