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
"""`frf-ident demo --out DIR`: node graph on the simulated robot, estimation, diagnosis."""
from __future__ import annotations

import argparse
from pathlib import Path

from frf_ident.cli.options import add_design_arguments

__all__ = ['DESCRIPTION', 'HELP', 'LOG_TO_OUT', 'add_arguments', 'run']

#: the DEBUG trace goes to ``--out``/<command>.log (``--out`` is a directory)
LOG_TO_OUT = True
HELP = 'the main job: node graph on the simulated robot, estimation, diagnosis'
DESCRIPTION = """\
The main job: the node graph (simulated 3-axis robot with friction, ripple, a stiffening gear
and noise, config/robot_3axis_demo.yaml) runs the identification over DDS, then estimation,
diagnosis against the nominal model (config/model_3axis.yaml), and the report. `make demo`
runs it into out/demo/ (replacing an earlier demo's): out/demo/graph/bag (the recorded bag),
out/demo/estimate/ (as `estimate` writes it), out/demo/diagnosis/ (as `diagnose` writes it,
with report.html). Without ROS 2 the nodes run on the built-in DDS backend; with ROS 2 sourced
on rclpy."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """
    Add the arguments of ``demo``; defaults are the demo's short experiments.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; the arguments are added to it.

    """
    from frf_ident.app.demo import DEMO_CHIRP, DEMO_MODEL, DEMO_MULTISINE, DEMO_ROBOT
    ms, ch = DEMO_MULTISINE, DEMO_CHIRP
    p.add_argument('--out', required=True,
                   help='output directory (refused when it already holds a demo bag)')
    p.add_argument('--model', type=Path,
                   help=f'nominal model for diagnosis (default config/{DEMO_MODEL})')
    p.add_argument('--robot', type=Path,
                   help=f'the simulated "real" robot (default config/{DEMO_ROBOT})')
    p.add_argument('--plant', default=None,
                   help="the plant node's plant: 'mujoco' (the --robot model's MJCF), "
                        "'mujoco:FILE.xml' or 'package.module:Class' (default: the --robot "
                        "model's own simulation)")
    add_design_arguments(p, ms, ch)


def run(args: argparse.Namespace) -> int:
    """
    Run the demo: node graph, estimation and diagnosis into ``--out``.

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
        A model or robot file is missing, or ``--out`` is unusable or already holds a bag.

    """
    from dataclasses import replace

    from frf_ident.app.console import say
    from frf_ident.app.demo import DEMO_CHIRP, DEMO_MULTISINE, run_demo
    from frf_ident.app.outdir import check_out
    out = check_out(args.out, outputs=(), overwrite=False)
    ms = replace(DEMO_MULTISINE, n_realisations=args.realisations, n_periods=args.periods,
                 resolution_hz=args.resolution)
    ch = replace(DEMO_CHIRP, duration=args.chirp_duration, max_iterations=args.max_iterations)
    return run_demo(out, model=args.model, robot=args.robot, multisine=ms, chirp=ch,
                    plant=args.plant, progress=say)
