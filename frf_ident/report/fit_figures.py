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
Figures of ``frf-ident fit`` and ``frf-ident loop`` (matplotlib, Agg backend).

- :func:`fit_figure` — per channel: the fitted model over the measured FRF (magnitude and
  phase), and the residual per line in units of the FRF's standard deviation,
  |P - P_fit| / sigma, with the cost test's verdict
- :func:`loop_figure` — per axis: Bode of L = C P-hat with its 2-sigma band from the FRF
  variance, and the Nyquist curve of L with the circle the modulus margin leaves around -1
"""
from __future__ import annotations

from pathlib import Path

from frf_ident.report.figures import DPI, frequency_axis
import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ['fit_figure', 'loop_figure']


def _db(x: np.ndarray) -> np.ndarray:
    return 20.0 * np.log10(np.maximum(np.abs(x), 1e-300))


def fit_figure(freq_hz: np.ndarray, measured: np.ndarray, model: np.ndarray,
               variance: np.ndarray | None, names: list[str], path: Path,
               verdicts: list[str] | None = None) -> Path:
    """
    Write the model-over-FRF figure with the normalised residual.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Frequencies [Hz].
    measured, model : ndarray of complex, shape (n_ch, n_freq)
        Measured FRF and fitted model of every plotted channel.
    variance : ndarray, shape (n_ch, n_freq), or None
        Variance of the measured FRF: the residual is drawn as |P - P_fit| / sigma (about 1
        where the noise explains it); without it as the relative error |P - P_fit| / |P|.
    names : list of str
        One title per channel.
    path : Path
        PNG to write.
    verdicts : list of str, optional
        The cost test's verdict of each channel's fit, shown over its residual.

    Returns
    -------
    Path
        ``path``.

    """
    n = measured.shape[0]
    fig, axs = plt.subplots(3, n, figsize=(min(4.5 * n, 27.0), 8), sharex=True, squeeze=False)
    for c in range(n):
        am, ap, ar = axs[:, c]
        am.semilogx(freq_hz, _db(measured[c]), 'k.', ms=3, label='measured FRF')
        am.semilogx(freq_hz, _db(model[c]), 'C1-', lw=1.2, label='fitted model')
        ap.semilogx(freq_hz, np.degrees(np.unwrap(np.angle(measured[c]))), 'k.', ms=3)
        ap.semilogx(freq_hz, np.degrees(np.unwrap(np.angle(model[c]))), 'C1-', lw=1.2)
        err = np.abs(model[c] - measured[c])
        if variance is not None:
            ar.semilogx(freq_hz, err / np.sqrt(variance[c]), 'C3.-', lw=0.8, ms=3,
                        label='|P - P_fit| / \u03c3')
            ar.axhline(1.0, color='k', ls='--', lw=0.8, label='noise level (1 \u03c3)')
            ar.set_ylabel('|P - P_fit| / \u03c3 [-]')
        else:
            ar.semilogx(freq_hz, err / np.abs(measured[c]), 'C3.-', lw=0.8, ms=3,
                        label='|P - P_fit| / |P| (no variance)')
            ar.set_ylabel('|P - P_fit| / |P| [-]')
        ar.set_ylim(bottom=0)
        if verdicts:
            ar.set_title(verdicts[c], fontsize=8)
        am.set_title(names[c], fontsize=9)
        am.set_ylabel('|P| [dB]')
        ap.set_ylabel('phase [deg]')
        for a in (am, ap, ar):
            frequency_axis(a, label=None)
            a.grid(True, which='both', alpha=0.3)
        frequency_axis(ar)
    axs[0, 0].legend(fontsize=8)
    axs[2, 0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return Path(path)


def loop_figure(freq_hz: np.ndarray, loops: np.ndarray, draws: np.ndarray | None,
                names: list[str], modulus: list[float], path: Path) -> Path:
    """
    Write Bode and Nyquist plots of L per axis with the uncertainty of the draws.

    Parameters
    ----------
    freq_hz : ndarray, shape (n_freq,)
        Frequencies [Hz].
    loops : ndarray of complex, shape (n_axes, n_freq)
        L_i = C_i P_ii from the estimate.
    draws : ndarray of complex, shape (n_draws, n_axes, n_freq), or None
        L of the FRF's draws (their 2.5-97.5 % band is shaded).
    names : list of str
        Axis names.
    modulus : list of float
        Modulus margin of each axis (circle around -1).
    path : Path
        PNG to write.

    Returns
    -------
    Path
        ``path``.

    """
    n = loops.shape[0]
    fig, axs = plt.subplots(3, n, figsize=(4.5 * n, 10), squeeze=False)
    for c in range(n):
        am, ap, an = axs[:, c]
        mag, ph = _db(loops[c]), np.degrees(np.unwrap(np.angle(loops[c])))
        am.semilogx(freq_hz, mag, 'C0-', lw=1.2)
        ap.semilogx(freq_hz, ph, 'C0-', lw=1.2)
        an.plot(loops[c].real, loops[c].imag, 'C0-', lw=1.2)
        if draws is not None and draws.shape[0] > 2:
            dm = _db(draws[:, c])
            dp = ph + np.degrees(np.angle(draws[:, c] / loops[c]))
            for a, d in ((am, dm), (ap, dp)):
                lo, hi = np.percentile(d, [2.5, 97.5], axis=0)
                a.fill_between(freq_hz, lo, hi, color='C0', alpha=0.25, lw=0)
            for d in draws[:20, c]:
                an.plot(d.real, d.imag, 'C0-', lw=0.3, alpha=0.3)
        am.axhline(0, color='k', lw=0.8)
        ap.axhline(-180, color='k', lw=0.8)
        circle = plt.Circle((-1, 0), modulus[c], color='C3', fill=False, lw=1)
        an.add_patch(circle)
        an.plot([-1], [0], 'r+')
        an.set_xlim(-3, 1.5)
        an.set_ylim(-2.5, 2.5)
        an.set_aspect('equal')
        am.set_title(f'{names[c]}: L = C P-hat', fontsize=9)
        am.set_ylabel('|L| [dB]')
        ap.set_ylabel('phase [deg]')
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
