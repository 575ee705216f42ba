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
"""Options several commands share: the output directory, campaigns, the experiment design."""
from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any, Callable, Sequence

__all__ = ['add_campaign_arguments', 'add_design_arguments', 'add_fit_arguments',
           'add_output_arguments', 'fit_options', 'run_many']


def add_output_arguments(p: argparse.ArgumentParser) -> None:
    """
    Add ``--out DIR`` and ``--overwrite`` (estimate, diagnose, reproduce).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.

    """
    p.add_argument('--out', required=True,
                   help='output directory (refused when it holds the outputs of an earlier '
                        'run, unless --overwrite)')
    p.add_argument('--overwrite', action='store_true',
                   help="replace this command's outputs of an earlier run in --out (its own "
                        'files only; nothing else is touched)')


def add_campaign_arguments(p: argparse.ArgumentParser, one_input: str = '') -> None:
    """
    Add ``--jobs N`` and ``--scheduler ADDRESS`` (commands that take several inputs).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    one_input : str
        What ``--jobs`` means with one input, appended to its help ('' : nothing).

    """
    p.add_argument('--jobs', type=int, default=None, metavar='N',
                   help='with several inputs: worker processes, one input each (default: all '
                        'cores; 1: one after the other in this process)' + one_input)
    p.add_argument('--scheduler', default=None, metavar='ADDRESS',
                   help='with several inputs: run them on a Dask cluster, its scheduler '
                        'address (tcp://HOST:8786; inputs and --out on a file system the '
                        'workers share), or "local" for a LocalCluster of --jobs workers on '
                        '127.0.0.1 (needs the [cluster] extra)')


def run_many(args: argparse.Namespace, specs: Sequence[Any], task: Callable[..., dict],
             outputs: Sequence[str], title: str, *, after: Any = None,
             after_outputs: Sequence[str] = (), member: Any = None,
             inputs: Sequence[Any] | None = None) -> int:
    """
    Run a command's task over several inputs (a campaign) and return the exit status.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``out``, ``overwrite``, ``jobs``, ``scheduler``.
    specs : sequence
        The inputs as given (paths, folders, globs, ``@list.txt``).
    task : callable
        Picklable ``task(input, out_dir, progress) -> dict`` (the command's app function).
    outputs : sequence of str
        The files the task writes into an input's folder.
    title : str
        The command's name.
    after : callable, optional
        Called with the :class:`~frf_ident.app.campaign_summary.CampaignResult`; returns the paths
        it wrote into ``--out`` (the FRF map of an estimate campaign).
    after_outputs : sequence of str
        The files ``after`` may write into ``--out`` (checked before any work).
    member : callable, optional
        What an input is when not a bag (:func:`~frf_ident.app.campaign_inputs.expand_inputs`).
    inputs : sequence of Path, optional
        The inputs already expanded (the poses of a multi-pose bag); ``specs`` is then not
        expanded.

    Returns
    -------
    int
        0 when every input succeeded, 1 when some did not (their rows say why).

    """
    from frf_ident.app.campaign import run_campaign
    from frf_ident.app.campaign_inputs import expand_inputs
    from frf_ident.app.console import say
    res = run_campaign(task, list(inputs) if inputs is not None else
                       expand_inputs(specs, member), args.out, outputs=outputs,
                       root_outputs=after_outputs, overwrite=args.overwrite, jobs=args.jobs,
                       scheduler=args.scheduler, title=title, progress=say)
    for path in (after(res) if after is not None else []):
        say(f'wrote {path}')
    return 1 if res.n_failed else 0


def add_design_arguments(p: argparse.ArgumentParser, ms: Any, ch: Any) -> None:
    """
    Add the multisine and chirp design options with the defaults of ``ms`` and ``ch``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser (identify, demo).
    ms : MultisineConfig
        Default multisine design.
    ch : ChirpConfig
        Default chirp design.

    """
    p.add_argument('--realisations', type=int, default=ms.n_realisations,
                   help=f'multisine n_p (default {ms.n_realisations}; paper: 10)')
    p.add_argument('--periods', type=int, default=ms.n_periods,
                   help=f'multisine n_q (default {ms.n_periods}; paper: 5)')
    p.add_argument('--resolution', type=float, default=ms.resolution_hz,
                   help=f'multisine frequency resolution [Hz] (default {ms.resolution_hz}; '
                        f'paper: 0.1 -> 12.3 s periods)')
    p.add_argument('--chirp-duration', type=float, default=ch.duration,
                   help=f'chirp length [s] (default {ch.duration}; paper: 20)')
    p.add_argument('--max-iterations', type=int, default=ch.max_iterations,
                   help=f'chirp iteration steps at most (default {ch.max_iterations})')


def add_fit_arguments(p: Any) -> None:
    """
    Add ``--order``, ``--physical``, ``--delay``, ``--model`` (``fit``, ``estimate --fit``).

    Parameters
    ----------
    p : argparse.ArgumentParser or argument group
        Where the options go.

    """
    p.add_argument('--order', type=int, default=None,
                   help='order (number of poles) of the rational model (default: the lowest '
                        'the cost test accepts)')
    p.add_argument('--physical', action='store_true',
                   help='fit the two-mass flexible joint per axis and write model.yaml')
    p.add_argument('--delay', type=float, default=None, metavar='S',
                   help='input delay of the physical model [s], fixed (default: fitted with '
                        'the parameters; a sampled FRF shows at least half a sample, e.g. '
                        '0.0005 at 1 kHz)')
    p.add_argument('--model', type=Path, default=None,
                   help='model file whose other keys (limits, controller, sample rate) the '
                        'fitted model.yaml keeps, and whose velocity PI is checked on the '
                        'measured FRF (margins: loop.json, loop.png and fit.html)')


def fit_options(args: argparse.Namespace, band: Any = None) -> Any:
    """
    Return the :class:`~frf_ident.app.fit.FitOptions` of :func:`add_fit_arguments`.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``order``, ``physical``, ``delay``, ``model``.
    band : sequence of float, optional
        (low, high) [Hz] to fit.

    Returns
    -------
    FitOptions
        The keyword arguments of :func:`~frf_ident.app.fit.fit_frf`.

    """
    from frf_ident.app.fit import FitOptions
    return FitOptions(order=args.order, physical=args.physical, delay_s=args.delay,
                      band=tuple(band) if band else None, model=args.model)
