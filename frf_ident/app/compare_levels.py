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
`frf-ident estimate A B C --compare-levels --out DIR`: records at different levels side by side.

Each bag is estimated as `estimate` does (into DIR/<k>_<bag name>/); the primary estimates
are then compared (:func:`~frf_ident.core.estimation.compare.compare_levels`): one printed
line per record and output, DIR/compare.json and DIR/compare.png.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Sequence

from frf_ident.app.estimate import estimate_bag
from frf_ident.app.outdir import clear_outputs
from frf_ident.core.progress import Progress, sink

__all__ = ['COMPARE_FILES', 'compare_bags']

#: the files :func:`compare_bags` writes beside the per-record directories
COMPARE_FILES = ('compare.json', 'compare.png')


def compare_bags(bags: Sequence[Path], out: Path, *, primary: str | None = None,
                 progress: Progress | None = None, **estimate_options):
    """
    Estimate every bag and compare the estimates (first bag: the reference).

    Parameters
    ----------
    bags : sequence of Path
        Two or more bags of the same channels at different excitation levels.
    out : Path
        Output directory (one sub-directory per bag, compare.json, compare.png).
    primary : str, optional
        Which estimate of each bag is compared (default: as `estimate` picks it).
    progress : callable
        Called with one line per step.
    **estimate_options
        Passed to :func:`~frf_ident.app.estimate.estimate_bag` (joints, t_range, options,
        stream, max_memory_mb, window_s).

    Returns
    -------
    LevelComparison
        The comparison.

    Raises
    ------
    EstimationError
        A bag is refused (named), or the estimates cannot be compared.

    """
    from frf_ident.core.estimation.compare import compare_levels
    from frf_ident.errors import EstimationError
    from frf_ident.report.distortion import level_comparison_figure
    progress = sink(progress)
    chosen, names = [], []
    for k, bag in enumerate(bags):
        progress(f'--- record {k + 1} of {len(bags)}: {bag}')
        estimates = estimate_bag(bag, out / f'{k + 1}_{bag.name}', primary=primary,
                                 progress=progress, **estimate_options)
        key = primary or ('multisine' if 'multisine' in estimates else next(iter(estimates)))
        chosen.append(estimates[key])
        names.append(bag.name)
    try:
        cmp = compare_levels(chosen, names)
    except EstimationError as exc:
        raise EstimationError(f'--compare-levels {" ".join(map(str, bags))}: {exc}') from None
    clear_outputs(out, COMPARE_FILES)
    for line in cmp.summary():
        progress(line)
    (out / 'compare.json').write_text(json.dumps(cmp.to_dict()))
    level_comparison_figure(cmp, out / 'compare.png')
    progress(f'wrote {out / "compare.json"} and {out / "compare.png"} ({len(bags)} records, '
             f'{cmp.freq_hz.size} shared lines)')
    return cmp
