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
The channels of an estimate from experiment segments: which series, named how, which joints.

A segment's series (effort u, velocity y, excitation r, position q), the channel names
``tau_m/<joint>`` and ``dq_m/<joint>``, the joints an estimate takes part with and the
channels picked from it afterwards, and the check of ``--joints``.
"""
from __future__ import annotations

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import EstimationError, FrfIdentInputError
import numpy as np


def channel_names(joint_names: list[str]) -> tuple[list[str], list[str]]:
    """Return the input (``tau_m/<joint>``) and output (``dq_m/<joint>``) channel names."""
    return ([f'tau_m/{j}' for j in joint_names], [f'dq_m/{j}' for j in joint_names])


def segment_arrays(rec: Recording, seg: Segment) -> dict[str, np.ndarray]:
    """Return a segment's effort u, velocity y, excitation r (else reference) and position q."""
    sl = rec.slice(seg.t_start, seg.t_end)
    exc = rec.excitation if rec.excitation is not None else rec.reference
    if exc is None:
        raise EstimationError('recording has no reference/excitation to estimate from')
    return {'u': rec.effort[sl], 'y': rec.velocity[sl], 'r': exc[sl], 'q': rec.position[sl]}


def joint_channels(frf: FrequencyResponse, joints: list[str]) -> FrequencyResponse:
    """
    Return the channels of ``frf`` from and to the named joints, in their order.

    A MIMO multisine excites every joint at once, so it is estimated with all of them and
    its channels are picked afterwards: an estimate from a subset of the inputs takes the
    others' response for its own (median error to the analytic FRF 0.029 dB against 0.004 dB
    picked, ``pytest -s test/cli/test_estimate_cli.py -k pick_channels``).

    Parameters
    ----------
    frf : FrequencyResponse
        An estimate with channel names ``'<signal>/<joint>'``.
    joints : list of str
        The joints wanted.

    Returns
    -------
    FrequencyResponse
        Its inputs and outputs of those joints.

    """
    def pick(names):
        return [n for j in joints for n in names if n.split('/', 1)[-1] == j]
    outs = pick(frf.outputs)
    out = frf.channels(outs, pick(frf.inputs))
    lines = frf.meta.get('detection_lines')
    if isinstance(lines, dict):          # per output channel: the picked ones
        idx = [frf.outputs.index(o) for o in outs]
        out.meta['detection_lines'] = {
            k: [v[i] for i in idx] if isinstance(v, list) and len(v) == len(frf.outputs)
            else v for k, v in lines.items()}
    return out


def experiment_joints(rec: Recording, wanted: list[str]) -> list[str]:
    """
    Return the joints an estimate of ``wanted`` takes part with: those the experiments excite.

    With multisine or chirp descriptors: the joints /frf/excitation names (a finite excitation
    somewhere), and ``wanted``, in the recording's order; a joint the experiment never drove
    (a gripper, a passive axis) stays out. Otherwise (excitation detected per joint)
    ``wanted``.

    Parameters
    ----------
    rec : Recording
        The recording with all joints.
    wanted : list of str
        The joints asked for.

    Returns
    -------
    list of str

    """
    if rec.excitation is None or not any(s.info.get('design') in ('multisine', 'chirp')
                                         for s in rec.segments):
        return list(wanted)
    driven = np.isfinite(rec.excitation).any(axis=0)
    return [j for j, d in zip(rec.joint_names, driven) if d or j in wanted]


def check_joints(joints: list[str], names: list[str] | None = None) -> None:
    """
    Refuse ``--joints`` naming a joint the bag does not have, or one twice.

    Parameters
    ----------
    joints : list of str
        The joints asked for.
    names : list of str, optional
        The bag's joints; not checked when omitted.

    Raises
    ------
    FrfIdentInputError
        Naming the joint and the bag's joints.

    """
    twice = sorted({j for j in joints if joints.count(j) > 1})
    if twice:
        raise FrfIdentInputError(f'--joints {",".join(joints)}: {", ".join(twice)} given twice')
    missing = [j for j in joints if names is not None and j not in names]
    if missing:
        raise FrfIdentInputError(f'--joints: {", ".join(missing)} not in the bag (its joints: '
                                 f'{", ".join(names)})')
