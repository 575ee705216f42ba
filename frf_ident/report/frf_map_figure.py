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
"""The FRF map figure: resonance and antiresonance of each axis over the bags of a campaign."""
from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402  (the backend is chosen first)

__all__ = ['frf_map_figure']


def frf_map_figure(labels: Sequence[str], freqs: Mapping[str, tuple[Sequence, Sequence]],
                   path: Path) -> Path:
    """
    Draw a row per axis: resonance and antiresonance [Hz] per bag (x: bag and pose).

    Parameters
    ----------
    labels : sequence of str
        One x tick label per bag (its folder and pose, one line per joint).
    freqs : mapping
        Joint -> (resonances, antiresonances) [Hz], one value (or None) per bag.
    path : Path
        The PNG to write.

    Returns
    -------
    Path
        ``path``.

    """
    n = max(len(freqs), 1)
    # one column each, so a variation of a few percent is not flattened by the other's scale
    fig, axes = plt.subplots(n, 2, figsize=(max(8.0, 1.2 * len(labels)), 2.4 * n),
                             sharex=True, squeeze=False)
    x = list(range(len(labels)))
    for row, (joint, pair) in zip(axes, freqs.items()):
        for ax, values, what, style in zip(row, pair, ('resonance', 'antiresonance'),
                                           ('o-', 's--')):
            ax.plot(x, [float('nan') if v is None else v for v in values], style)
            ax.set_ylabel(f'{joint} {what} [Hz]', fontsize=8)
            ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xticks(x)
        ax.set_xticklabels(labels, fontsize=7)
    fig.suptitle('FRF map: resonance and antiresonance per axis (pose [rad] under each bag)')
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
