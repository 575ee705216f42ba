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
The distortion plot of an odd multisine experiment (one PNG).

Per output: the output level at the excited lines, at the non-excited odd lines (odd
nonlinearities) and at the even lines (even ones), and the noise level of the period mean,
in dB re 1 unit^2 over a logarithmic frequency axis (Pintelon & Schoukens' detection-line
plot). With several realisations the excited lines' nonlinear residual is drawn too.

The robust LPM plot (one realisation with several periods): per output |P| with the standard
deviation of its noise and of its stochastic nonlinear distortion, on one dB axis.
"""
from __future__ import annotations

from pathlib import Path

from frf_ident.core.estimation.distortion import DistortionLines
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.robust_levels import RobustLpmLevels
import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ['distortion_figure', 'level_comparison_figure', 'robust_lpm_figure']

#: marker style per kind of line: (label, colour, marker size)
STYLE = {'excited': ('excited lines', 'C0', 5), 'odd': ('non-excited odd lines', 'C3', 4),
         'even': ('even lines', 'C2', 3)}


def _db(p: np.ndarray) -> np.ndarray:
    return 10 * np.log10(np.maximum(p, 1e-300))


def _log_ticks(ax: plt.Axes) -> None:
    """Plain numbers on a log frequency axis: 1, 2, 5, 10, 20, 50 ... (no 3x10^0)."""
    def label(x: float, _pos: int) -> str:
        lead = round(x / 10 ** np.floor(np.log10(x))) if x > 0 else 0
        return f'{x:g}' if lead in (1, 2, 5) else ''
    ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(label))
    ax.xaxis.set_minor_formatter(matplotlib.ticker.FuncFormatter(label))


def _rows(n: int):
    """Return a figure with one full-width row of axes per output."""
    return plt.subplots(n, 1, figsize=(7.5, 2.6 * n + 0.8), sharex=True, squeeze=False)


def _save_rows(fig, axes, path: Path, title: str) -> Path:
    """Grid, frequency axis and legend of the rows of :func:`_rows`; write and close."""
    for ax in axes[:, 0]:
        ax.grid(True, which='both', alpha=0.3)
        _log_ticks(ax)
    axes[-1, 0].set_xlabel('frequency [Hz]')
    axes[0, 0].legend(fontsize=7, loc='best')
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return Path(path)


def distortion_figure(levels: DistortionLines, path: Path, *, title: str = '') -> Path:
    """
    Write the detection-line plot of ``levels``: one row per output.

    Parameters
    ----------
    levels : DistortionLines
        Per-line levels (:func:`~frf_ident.core.estimation.distortion.distortion_lines`).
    path : Path
        The PNG to write.
    title : str, optional
        Figure title.

    Returns
    -------
    Path
        ``path``.

    """
    fig, axes = _rows(len(levels.outputs))
    f = levels.freq_hz
    units = levels.unit_list()
    for o, ax in enumerate(axes[:, 0]):
        for kind, (label, colour, size) in STYLE.items():
            m = levels.kind == kind
            if np.any(m):
                ax.semilogx(f[m], _db(levels.power[o, m]), 'o', ms=size, color=colour,
                            mfc='none' if kind == 'excited' else colour, alpha=0.8, lw=0,
                            label=label)
        if levels.residual is not None:
            m = levels.kind == 'excited'
            ax.semilogx(f[m], _db(levels.residual[o, m]), 'x', ms=3, color='C1',
                        label='excited lines: nonlinear residual')
        if levels.noise is not None:
            ax.semilogx(f, _db(levels.noise[o]), '-', color='k', lw=1.0,
                        label='noise level (period mean)')
        unit = units[o] or 'unit'
        ax.set_ylabel(f'|Y|\u00b2 [dB re 1 ({unit})\u00b2]', fontsize=8)
        ax.set_title(levels.outputs[o], fontsize=9)
    return _save_rows(fig, axes, path, title or 'Output levels at excited, odd and even lines')


def _frf_unit(variance_unit: str) -> str:
    """Return '(y)/(u)' of a variance unit '(y)^2/(u)^2' ('' when it is not one)."""
    num, _, den = variance_unit.partition('^2/')
    return f'{num}/{den[:-2]}' if den.endswith('^2') and num else ''


def robust_lpm_figure(levels: RobustLpmLevels, frf: FrequencyResponse, path: Path, *,
                      title: str = '') -> Path:
    """
    Write |P|, its noise level and its nonlinear level per line (robust LPM), one row per output.

    All three on one axis in dB re 1 unit of P: 20 log10 |P|, and 10 log10 of the noise and
    of the stochastic nonlinear variance of P (their standard deviations). Where the
    nonlinear level stands above the noise, the nonlinear distortion dominates the
    uncertainty of this realisation's BLA; |P| far above both is a well determined line.

    Parameters
    ----------
    levels : RobustLpmLevels
        The estimate's ``meta['robust_lpm']`` read back (:meth:`RobustLpmLevels.from_dict`).
    frf : FrequencyResponse
        The estimate (one input); |P| is drawn at the lines of ``levels`` it holds.
    path : Path
        The PNG to write.
    title : str, optional
        Figure title.

    Returns
    -------
    Path
        ``path``.

    """
    fig, axes = _rows(len(levels.outputs))
    f = levels.freq_hz
    at = np.searchsorted(frf.freq_hz, f).clip(0, frf.freq_hz.size - 1)
    have = np.isclose(frf.freq_hz[at], f, rtol=1e-9, atol=0.0)
    for o, ax in enumerate(axes[:, 0]):
        row = frf.outputs.index(levels.outputs[o]) if levels.outputs[o] in frf.outputs else o
        mag = np.where(have, np.abs(frf.response[row, 0, at]), np.nan)
        ax.semilogx(f, 20 * np.log10(np.maximum(mag, 1e-300)), '-', color='C0', lw=1.2,
                    label='|P| (BLA of this realisation)')
        ax.semilogx(f, _db(levels.noise[o]), '-', color='k', lw=1.0,
                    label='noise level (std of P)')
        ax.semilogx(f, _db(levels.nonlinear[o]), '.', ms=4, color='C3',
                    label='stochastic nonlinear level (std of P)')
        unit = _frf_unit(levels.units[o]) or 'unit'
        ax.set_ylabel(f'[dB re 1 {unit}]', fontsize=8)
        ax.set_title(f'{frf.inputs[0] if frf.inputs else "input"} \u2192 {levels.outputs[o]}',
                     fontsize=9)
    return _save_rows(fig, axes, path,
                      title or f'Robust LPM: {levels.periods} periods of one realisation')


def level_comparison_figure(cmp, path: Path) -> Path:
    """
    Write |P| of every record and its change against the first, one row per output.

    Parameters
    ----------
    cmp : LevelComparison
        From :func:`~frf_ident.core.estimation.compare.compare_levels`.
    path : Path
        The PNG to write.

    Returns
    -------
    Path
        ``path``.

    """
    n = len(cmp.outputs)
    fig, axes = plt.subplots(n, 2, figsize=(10, 2.6 * n + 0.8), sharex=True, squeeze=False)
    f = cmp.freq_hz
    for o in range(n):
        ax_m, ax_c = axes[o]
        for k, name in enumerate(cmp.names):
            ax_m.semilogx(f, 20 * np.log10(np.maximum(np.abs(cmp.responses[k][o]), 1e-300)),
                          '.-', ms=3, lw=0.8, color=f'C{k}', label=name)
            ax_c.semilogx(f, cmp.change_db[k, o], '.-', ms=3, lw=0.8, color=f'C{k}')
            for fm in cmp.modes_hz[k][o]:
                ax_m.axvline(fm, color=f'C{k}', lw=0.6, ls=':')
        ax_m.set_ylabel('|P| [dB]', fontsize=8)
        ax_c.set_ylabel(f'|P| / |P of {cmp.names[0]}| [dB]', fontsize=8)
        ax_m.set_title(f'{cmp.inputs[0]} \u2192 {cmp.outputs[o]} (dotted: modes)', fontsize=9)
        for ax in (ax_m, ax_c):
            ax.grid(True, which='both', alpha=0.3)
            _log_ticks(ax)
    for ax in axes[-1]:
        ax.set_xlabel('frequency [Hz]')
    axes[0, 0].legend(fontsize=7, loc='best')
    fig.suptitle('Records at different levels: FRF and its change')
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return Path(path)
