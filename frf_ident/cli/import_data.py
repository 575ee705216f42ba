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
"""`frf-ident import FILE.csv|FILE.mat --map MAP.yaml --out BAG`."""
from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ['DESCRIPTION', 'HELP', 'add_arguments', 'run']

HELP = 'convert measured data (CSV or MAT table) into a bag, using a map file'
DESCRIPTION = """\
Converts measured data (a CSV or MAT table) into a bag with a YAML map: the joints, or the
inputs and outputs of a test rig, their columns, scales and units. The map format is in
docs/import_maps.md; examples: config/map_emps.yaml, config/map_kuka_kr300.yaml,
config/map_daisy_arm.yaml. It prints what it did: samples, rate, derived signals, and the
excitation it recognises. An existing BAG is never overwritten."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """
    Add the arguments of ``import``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; the arguments are added to it.

    """
    p.add_argument('file', type=Path, help='measured data: .csv or .mat')
    p.add_argument('--map', type=Path, required=True,
                   help='YAML map: time, joints and their columns/variables, unit scales '
                        '(see docs/import_maps.md; examples in config/map_*.yaml)')
    p.add_argument('--out', required=True, help='bag directory to create (must not exist)')


def run(args: argparse.Namespace) -> int:
    """
    Import the file and write the bag.

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
        The file or map is unusable, or the bag exists (one line naming it).

    """
    from frf_ident.app.console import say
    from frf_ident.app.import_data import import_file
    import_file(args.file, args.map, args.out, progress=say)
    return 0
