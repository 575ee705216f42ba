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
"""`frf-ident identify --out BAG`: the identification experiments in closed loop, recorded."""
from __future__ import annotations

import argparse
from pathlib import Path

from frf_ident.cli.options import add_design_arguments
from frf_ident.core.excitation.chirp_iteration import ChirpConfig
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.errors import FrfIdentInputError

__all__ = ['DESCRIPTION', 'HELP', 'add_arguments', 'identification_config', 'run']

HELP = 'run the identification experiments in closed loop, record a bag'
DESCRIPTION = """\
Runs the Section 7 procedures in closed loop on the model's simulation or a plug-in plant and
records a rosbag2 MCAP bag (an existing path is refused). Before anything runs it prints each
plan's peak torque predicted on the model and refuses (exit 2, nothing recorded) a plan at 0.95
of a limit, naming the setting to lower. Plug-in plants: docs/real_robot.md. --poses: the
procedures at each pose on the model linearised there, one bag per pose or all in one bag
(docs/CAMPAIGNS.md)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """
    Add the arguments of ``identify``; defaults are those of MultisineConfig and ChirpConfig.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; the arguments are added to it.

    """
    ms, ch = MultisineConfig, ChirpConfig
    p.add_argument('--model', type=Path, help='model file (default: the embedded 3-axis model)')
    p.add_argument('--plant', help='plant plug-in "package.module:Class" (default: the '
                                   "model's own simulation)")
    p.add_argument('--out', required=True, help='bag directory to create (must not exist); '
                                                'with --poses a folder of bags, one per pose')
    p.add_argument('--poses', type=Path, default=None, metavar='FILE',
                   help='YAML "poses: [[q1, q2, q3], ...]" [rad] (optional "urdf: FILE"): run '
                        'the procedures at each pose on the simulation linearised there (link '
                        'inertia, coupling, gravity from the URDF; needs the [kinematics] '
                        'extra), one bag per pose plus poses.json')
    p.add_argument('--one-bag', action='store_true',
                   help='with --poses: all poses in one bag (--out/all_poses), each segment '
                        'descriptor carrying its pose_index; estimate of it gives one folder '
                        'per pose, as for one bag per pose')
    p.add_argument('--urdf', type=Path, default=None,
                   help="with --poses: the robot's URDF (default: the poses file's, else "
                        "the demo robot's urdf/robot_3axis_demo.urdf)")
    p.add_argument('--procedures', default='multisine,chirp',
                   help='comma list of multisine, chirp (default both)')
    p.add_argument('--amplitude-ratio', type=float, default=ms.amplitude_ratio,
                   help=f'multisine amplitude / constant velocity, at most 0.75 (default '
                        f'{ms.amplitude_ratio})')
    p.add_argument('--position-bound', type=float, default=ms.position_bound_deg,
                   help=f'multisine travel bound around the operating point [deg], sets the '
                        f'constant velocity (default {ms.position_bound_deg})')
    p.add_argument('--no-compensation', action='store_true',
                   help='skip the constant-velocity run (no periodic-disturbance compensation)')
    add_design_arguments(p, ms, ch)
    p.add_argument('--target-sd-db', type=float, default=0.0, metavar='DB',
                   help='end the multisine at the first whole period whose largest 1-sigma '
                        'magnitude sd over the diagonal channels is at most DB (default 0: '
                        'run the design; docs/live.md)')
    p.add_argument('--foxglove', type=int, default=None, metavar='PORT',
                   help='serve the live estimate on a Foxglove WebSocket at '
                        'ws://127.0.0.1:PORT during the run and, after it, until Ctrl-C '
                        '(0: a free port; needs the [foxglove] extra; docs/live.md)')
    p.add_argument('--seed', type=int, default=ms.seed,
                   help=f'random phases of the multisine realisations (default {ms.seed})')


def identification_config(args: argparse.Namespace):
    """
    Return the IdentificationConfig the arguments describe.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    IdentificationConfig
        Multisine and/or chirp configuration (None for a procedure not in ``--procedures``).

    Raises
    ------
    FrfIdentInputError
        ``--procedures`` is empty or names something other than multisine, chirp.

    """
    from frf_ident.core.estimation.target import UncertaintyTarget
    from frf_ident.core.simulation.runner import IdentificationConfig
    procs = {s.strip() for s in args.procedures.split(',') if s.strip()}
    unknown = procs - {'multisine', 'chirp'}
    if unknown or not procs:
        raise FrfIdentInputError(f'--procedures {args.procedures!r}: expected a comma list of '
                                 f'multisine, chirp')
    ms = MultisineConfig(n_realisations=args.realisations, n_periods=args.periods,
                         resolution_hz=args.resolution, compensate=not args.no_compensation,
                         amplitude_ratio=args.amplitude_ratio,
                         position_bound_deg=args.position_bound,
                         seed=args.seed) if 'multisine' in procs else None
    ch = ChirpConfig(duration=args.chirp_duration, max_iterations=args.max_iterations) \
        if 'chirp' in procs else None
    return IdentificationConfig(ms, ch, UncertaintyTarget(getattr(args, 'target_sd_db', 0.0)))


def run(args: argparse.Namespace) -> int:
    """
    Run the experiments and print what they did.

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
        The procedures, model, plant or output path is invalid.

    """
    from frf_ident.app.console import say
    from frf_ident.app.identify import run_identify, run_identify_poses
    if args.poses is not None:
        if args.foxglove is not None:
            raise FrfIdentInputError(f'--foxglove {args.foxglove} with --poses: the live view '
                                     f'serves one run; leave out --poses or --foxglove')
        if args.plant:
            raise FrfIdentInputError(f'--plant {args.plant} with --poses: poses linearise the '
                                     f"model's own simulation; leave out --plant")
        run_identify_poses(args.model, args.poses, identification_config(args), args.out,
                           urdf=args.urdf, one_bag=args.one_bag, progress=say)
        return 0
    for given, flag in ((args.urdf is not None, f'--urdf {args.urdf}'),
                        (args.one_bag, '--one-bag')):
        if given:
            raise FrfIdentInputError(f'{flag}: only used with --poses FILE')
    if args.foxglove is not None and not 0 <= args.foxglove <= 65535:
        raise FrfIdentInputError(f'--foxglove {args.foxglove}: expected a TCP port 0..65535 '
                                 f'(0: a free one)')
    rec = run_identify(args.model, args.plant, identification_config(args), args.out,
                       progress=say, foxglove_port=args.foxglove)
    s = rec.summary
    if 'multisine' in s:
        m = s['multisine']
        say(f"multisine: {m['segments']} segments, {m['lines']} lines, period "
            f"{m['period_s']:.3f} s, experiment time {m['experiment_time_s']:.1f} s")
    if 'chirp' in s:
        c = s['chirp']
        for it in c['iterations']:
            say(f"chirp iteration {it['iteration']}: error to u_des per channel "
                f"{', '.join(f'{e:.2f}' for e in it['error_db_per_channel'])} dB, "
                f"max |u| {', '.join(f'{u:.0f}' for u in it['max_abs_torque'])} N m "
                f"(limits {', '.join(f'{u:.0f}' for u in c['torque_limit'])})")
        say(f"chirp: {'converged' if c['converged'] else 'NOT converged'} after "
            f"{c['final_iteration']} iterations, experiment time {c['experiment_time_s']:.1f} s")
    say(f"total experiment time {s['total_experiment_time_s']:.1f} s (simulated in "
        f"{s['wall_time_s']:.1f} s); bag: {args.out}")
    return 0
