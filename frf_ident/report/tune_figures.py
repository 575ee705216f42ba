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
The figure of ``frf-ident tune`` (matplotlib, Agg backend): loops before and after, with W.

Per axis one column: |L| and phase of the tuned loop at every pose (thin) and at the nominal
pose (thick) with the uncertainty band |L_0| (1 +- |W|) shaded; the model file's controller
("before", dashed) at the nominal pose; below, the Nyquist curves with discs of radius
|W L_0| along the tuned nominal curve (the set of loops the weight covers) and the circle of
radius 0.5 around -1 (the default modulus margin target).
"""
from __future__ import annotations

from pathlib import Path

from frf_ident.report.figures import frequency_axis
import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ['tune_figure']

DPI = 100
#: discs drawn along the nominal Nyquist curve
DISCS = 40


def _db(x: np.ndarray) -> np.ndarray:
    return 20.0 * np.log10(np.maximum(np.abs(x), 1e-300))


def tune_figure(freq_hz: np.ndarray, after: np.ndarray, nominal: int, weight: np.ndarray,
                before: np.ndarray | None, names: list[str], modulus_target: float,
                path: Path) -> Path:
    """
    Write the Bode and Nyquist plots of the tuned loops (module doc).

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        The lines [Hz].
    after : ndarray of complex, shape (n_poses, n_axes, n_freq)
        Tuned L_i = C_i P_ii at every pose.
    nominal : int
        Index of the nominal pose.
    weight : ndarray, shape (n_axes, n_freq)
        |W| of every axis.
    before : ndarray of complex, shape (n_axes, n_freq), or None
        The model file's loop at the nominal pose.
    names : list of str
        Axis names.
    modulus_target : float
        Radius of the circle around -1.
    path : Path
        PNG to write.

    Returns
    -------
    Path
        ``path``.

    """
    n = after.shape[1]
    fig, axs = plt.subplots(3, n, figsize=(4.5 * n, 10.5), squeeze=False)
    for c in range(n):
        am, ap, an = axs[:, c]
        l0 = after[nominal, c]
        for k in range(after.shape[0]):
            if k != nominal:
                am.semilogx(freq_hz, _db(after[k, c]), 'C0-', lw=0.5, alpha=0.5)
                ap.semilogx(freq_hz, np.degrees(np.unwrap(np.angle(after[k, c]))), 'C0-',
                            lw=0.5, alpha=0.5)
                an.plot(after[k, c].real, after[k, c].imag, 'C0-', lw=0.5, alpha=0.5)
        lo = np.abs(l0) * np.maximum(1 - weight[c], 1e-3)
        am.fill_between(freq_hz, _db(lo), _db(np.abs(l0) * (1 + weight[c])), color='C0',
                        alpha=0.2, lw=0, label='|L0| (1 +- |W|)')
        am.semilogx(freq_hz, _db(l0), 'C0-', lw=1.5, label='tuned')
        ap.semilogx(freq_hz, np.degrees(np.unwrap(np.angle(l0))), 'C0-', lw=1.5)
        an.plot(l0.real, l0.imag, 'C0-', lw=1.5)
        for q in np.linspace(0, freq_hz.size - 1, DISCS).astype(int):
            an.add_patch(plt.Circle((l0[q].real, l0[q].imag), weight[c, q] * abs(l0[q]),
                                    color='C0', alpha=0.08, lw=0))
        if before is not None:
            am.semilogx(freq_hz, _db(before[c]), 'C1--', lw=1.0, label='model file')
            ap.semilogx(freq_hz, np.degrees(np.unwrap(np.angle(before[c]))), 'C1--', lw=1.0)
            an.plot(before[c].real, before[c].imag, 'C1--', lw=1.0)
        am.axhline(0, color='k', lw=0.8)
        ap.axhline(-180, color='k', lw=0.8)
        an.add_patch(plt.Circle((-1, 0), modulus_target, color='C3', fill=False, lw=1))
        an.plot([-1], [0], 'r+')
        an.set_xlim(-3, 1.5)
        an.set_ylim(-2.5, 2.5)
        an.set_aspect('equal')
        am.set_title(f'{names[c]}: L = C P-hat', fontsize=9)
        am.set_ylabel('|L| [dB]')
        ap.set_ylabel('phase [deg]')
        am.legend(fontsize=7, loc='lower left')
        frequency_axis(am, label=None)
        frequency_axis(ap)
        an.set_xlabel('Re L [-]')
        an.set_ylabel('Im L [-]')
        for a in (am, ap, an):
            a.grid(True, which='both', alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return Path(path)
