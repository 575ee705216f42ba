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
Figure of the time-series residual's spectrum: the analysis band and what stands above it.

Per axis the Welch PSD of the extended model's inverse-dynamics residual (not low-passed),
its local noise floor and the scan's threshold above the analysis band, the band shaded grey
and each ``unexplained`` peak's band orange (:mod:`frf_ident.core.diagnosis.timeseries.resonance`).
"""
from __future__ import annotations

from pathlib import Path

from frf_ident.core.diagnosis.regressors import model_residual
from frf_ident.core.diagnosis.result import DiagnosisResult
from frf_ident.core.diagnosis.thresholds import FC_HZ, RESONANCE_FALSE_ALARM
from frf_ident.core.diagnosis.timeseries.resonance import scan_spectrum
from frf_ident.core.recording import Recording

from .figures import legend_below, plt, under_title

__all__ = ['residual_spectrum_figure']


def residual_spectrum_figure(res: DiagnosisResult, rec: Recording, path: Path, *,
                             title: str = '') -> Path:
    """
    Write the residual-spectrum figure of a time-series diagnosis.

    Parameters
    ----------
    res : DiagnosisResult
        The diagnosis (its extended model, band and unexplained entries).
    rec : Recording
        The diagnosed record.
    path : Path
        The PNG to write.
    title : str, optional
        The figure's title (the record's name).

    Returns
    -------
    Path
        ``path``.

    """
    fc = res.band.fc_hz if res.band is not None else FC_HZ
    f_all = model_residual(rec, res.extended)[0]
    n = f_all.shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(8.0, 3.4 * n + 1.2), squeeze=False)
    for i, ax in enumerate(axes[:, 0]):
        name = res.extended.joint_names[i]
        f, p, floor, thr = scan_spectrum(f_all[:, i], rec.fs, 0.0)
        ax.semilogy(f, p, color='k', lw=0.8, label='residual PSD (extended model)')
        ax.semilogy(f, floor, color='tab:blue', lw=1.0, label='local noise floor (running median)')
        _, _, _, thr_above = scan_spectrum(f_all[:, i], rec.fs, fc)
        above = f > fc
        ax.semilogy(f[above], thr_above * floor[above], color='tab:red', lw=1.0, ls='--',
                    label=f'threshold (false alarm {RESONANCE_FALSE_ALARM:g} per axis)')
        ax.axvspan(0.0, fc, color='0.85', label=f'analysis band 0-{fc:.3g} Hz')
        for u in res.unexplained:
            s = u.signature
            if u.axis == name and s.peak_hz is not None:
                ax.axvspan(*s.band_hz, color='tab:orange', alpha=0.35,
                           label='unexplained: resonance or line')
                ax.annotate(f'{u.kind.split()[0]} {s.peak_hz:.0f} Hz',
                            (s.band_hz[1], p.max()), fontsize=8, ha='left', va='top',
                            rotation=90)
        ax.set_xlim(0.0, f[-1])
        ax.set_ylabel(f'{name}: PSD [torque^2/Hz]')
        ax.grid(True, which='both', alpha=0.3)
    axes[-1, 0].set_xlabel('frequency [Hz]')
    fig.suptitle(title or 'inverse-dynamics residual of the extended model', fontsize=10)
    bottom = legend_below(fig, list(axes[:, 0]), ncol=3)
    fig.tight_layout(rect=(0, bottom, 1, under_title(fig)))
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return Path(path)
