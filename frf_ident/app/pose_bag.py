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
A bag recorded at several poses (``identify --poses --one-bag``): estimated pose by pose.

Every segment descriptor of such a bag carries its ``pose_index`` and ``pose_rad``, and the
recording meta lists each pose's time range (``summary.poses``). :func:`bag_poses` reads
them from the experiment topic alone; ``frf-ident estimate`` of the bag is then a campaign
over its poses (:func:`estimate_pose_columns`: the bag over that pose's time range), one
folder per pose as for one bag per pose, with the summary table and the FRF map. A pose's
record is the same samples in both layouts (shifted in time by whole samples), so its FRF is
too, to the rounding of the time stamps (measured: 8e-16 relative).
"""
from __future__ import annotations

from dataclasses import dataclass
import json
from pathlib import Path
from typing import Any

from frf_ident.core.progress import Progress

__all__ = ['PoseSpan', 'bag_poses', 'estimate_pose_columns']


@dataclass(frozen=True)
class PoseSpan:
    """
    One pose of a multi-pose bag.

    Attributes
    ----------
    name : str
        Its folder name, ``pose_NN`` (NN the pose index).
    pose_rad : list of float or None
        The joint positions [rad].
    t_range : tuple of float
        Its time span in the bag [s].

    """

    name: str
    pose_rad: list[float] | None
    t_range: tuple[float, float]


def bag_poses(bag: Path) -> list[PoseSpan] | None:
    """
    Return the poses of a bag recorded at several, or None for any other bag.

    Parameters
    ----------
    bag : Path
        A bag directory or .mcap file.

    Returns
    -------
    list of PoseSpan or None
        In pose order; None when the segments carry fewer than two pose indices (or the bag
        cannot be read: the estimate reports that itself).

    """
    from frf_ident.bag import read_experiment
    from frf_ident.errors import FrfIdentInputError
    try:
        exp = read_experiment(bag)
    except FrfIdentInputError:              # not a bag (a CSV ...), or unreadable
        return None
    spans: dict[int, list] = {}
    for s in exp.segments:
        k = s.info.get('pose_index')
        if k is not None:
            spans.setdefault(int(k), []).append(s)
    if len(spans) < 2:
        return None
    listed = {int(p['pose_index']): p for p in exp.summary.get('poses', [])}
    out = []
    for k in sorted(spans):
        segs = spans[k]
        # the whole record of the pose when the meta lists it, else its segments' span
        t = ((listed[k]['t_start'], listed[k]['t_end']) if k in listed else
             (min(s.t_start for s in segs), max(s.t_end for s in segs)))
        out.append(PoseSpan(f'pose_{k:02d}', segs[0].info.get('pose_rad'),
                            (float(t[0]), float(t[1]))))
    return out


def estimate_pose_columns(pose: Path, out: Path, progress: Progress, *, bag: Path,
                          spans: list[PoseSpan], **options: Any) -> dict[str, Any]:
    """
    Estimate one pose of a multi-pose bag (the campaign task; the input is the pose's name).

    Parameters
    ----------
    pose : Path
        The pose's :attr:`PoseSpan.name`.
    out : Path
        Its output folder.
    progress : callable
        Called with one line per step.
    bag : Path
        The bag.
    spans : list of PoseSpan
        Its poses (:func:`bag_poses`).
    **options
        The keyword arguments of :func:`~frf_ident.app.estimate.estimate_bag` but
        ``t_range`` (the pose's).

    Returns
    -------
    dict
        The columns of :func:`~frf_ident.app.estimate.estimate_columns`, with the pose's
        ``pose_rad_J``; its summary.json records the pose as a one-pose bag's does.

    """
    from frf_ident.app.estimate import estimate_columns
    span = {s.name: s for s in spans}[Path(pose).name]
    progress(f'{bag}: {span.name} at {span.pose_rad} rad, t = {span.t_range[0]:.3f}-'
             f'{span.t_range[1]:.3f} s')
    cols = estimate_columns(bag, out, progress, t_range=span.t_range, **options)
    summary = json.loads((out / 'summary.json').read_text())
    experiment = summary.setdefault('experiment', {})
    experiment.pop('poses', None)
    experiment['pose_rad'] = span.pose_rad
    (out / 'summary.json').write_text(json.dumps(summary, indent=1, default=str))
    frf = json.loads((out / 'frf.json').read_text())
    outs = [c.rsplit('/', 1)[-1] for c in frf['outputs']]
    if span.pose_rad is not None and len(span.pose_rad) == len(outs):
        # where estimate_columns puts a one-pose bag's pose: after the band, before the modes
        items = list(cols.items())
        at = next((i for i, (k, _) in enumerate(items) if k.startswith('resonance_hz_')),
                  len(items))
        items[at:at] = [(f'pose_rad_{j}', q) for j, q in zip(outs, span.pose_rad)]
        cols = dict(items)
    return cols
