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
"""The measured FRF a fit or a loop check starts from: where it is read, its variance, its axes."""
from __future__ import annotations

from pathlib import Path

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.export import read_frf

__all__ = ['axis_channels', 'read_source']


def read_source(source: str | Path) -> FrequencyResponse:
    """
    Read an FRF: a directory's frf.json (the output of ``estimate``) or an FRF file.

    Parameters
    ----------
    source : str or Path
        Directory holding frf.json, or a .json/.mat/.csv FRF file.

    Returns
    -------
    FrequencyResponse
        The FRF.

    Raises
    ------
    FrfIdentInputError
        Nothing readable there (the message names the path).

    """
    p = Path(source)
    if p.is_dir():
        if not (p / 'frf.json').is_file():
            raise FrfIdentInputError(f'{p}: a directory without frf.json (expected the output '
                                     f'directory of frf-ident estimate, or an FRF file)')
        p = p / 'frf.json'
    return read_frf(p)


def axis_channels(frf: FrequencyResponse) -> list[tuple[str, int, int]]:
    """
    Return (joint, output index, input index) of every axis's own channel P_ii.

    Parameters
    ----------
    frf : FrequencyResponse
        Torque -> velocity FRF. The joint of a channel name is the part after its last
        ``/`` (``estimate`` names inputs ``tau_m/<joint>`` and outputs ``dq_m/<joint>``);
        each input's own output is the output of the same joint, else of the same index.

    Returns
    -------
    list of tuple
        One entry per input.

    Raises
    ------
    FrfIdentInputError
        An input has no output of its joint and no output at its index.

    """
    joints = [n.rsplit('/', 1)[-1] for n in frf.outputs]
    out = []
    for i, name in enumerate(frf.inputs):
        joint = name.rsplit('/', 1)[-1]
        if joint in joints:
            out.append((joint, joints.index(joint), i))
        elif i < frf.noutputs:
            out.append((joint, i, i))
        else:
            raise FrfIdentInputError(f'FRF input {name!r} has no output of its joint '
                                     f'(outputs {frf.outputs})')
    return out
