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
Figures of the HTML report (matplotlib, Agg backend). Each function writes one PNG.

- :func:`bode_figure` — magnitude and phase per channel with 2-sigma uncertainty bands
- :func:`snr_figure` — coherence-like SNR per line, |P|^2 / var(P) in dB
- :func:`spectrogram_figure` — PSD of the torques over time (like Fig. 3 of the paper)
- :func:`timeseries_figure` — torque, velocity and reference over time
- :func:`iteration_figure` — chirp iteration: error to u_des per iteration and channel
- :func:`paper_figure` — Figures 4 and 5 of the paper (``frf-ident reproduce paper``)
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

from frf_ident.core.diagnosis.residual import lowpass
from frf_ident.core.diagnosis.result import DiagnosisResult
from frf_ident.core.diagnosis.thresholds import FC_HZ
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.recording import JOINT_STATE_FRF_UNIT
import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402
from scipy import signal  # noqa: E402

DPI = 100
#: models (reference, nominal, extended) are drawn under the measured data
REF_STYLE = {'color': 'k', 'lw': 1.3, 'zorder': 2}
#: measured data on top of every model line
MEASURED_Z = 3
#: a log frequency axis labels 2x and 5x its decades while it spans at most this many decades
#: (wider, the labels of a 4.6 inch panel touch; the decades alone are labelled then)
LABELLED_MINORS_DECADES = 2.5


def _hz_label(x: float, _pos: int | None = None) -> str:
    return f'{x:g}'


def frequency_axis(ax: plt.Axes, which: str = 'x', label: str | None = 'frequency [Hz]'
                   ) -> None:
    """
    Make a log frequency axis read at a glance: plain numbers at 1, 2 and 5 per decade.

    Decades are labelled as plain numbers (0.1, 1, 10, 100, not 10^k); 2x and 5x each decade
    too while the view spans at most :data:`LABELLED_MINORS_DECADES` decades; the other minor
    ticks stay unlabelled, so labels never overlap.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes; its ``which`` axis must be (or become) logarithmic.
    which : {'x', 'y'}, optional
        The frequency axis.
    label : str or None, optional
        Axis label; None leaves it.

    """
    axis = ax.xaxis if which == 'x' else ax.yaxis
    (ax.set_xscale if which == 'x' else ax.set_yscale)('log')

    def minor(x: float, pos: int | None = None) -> str:
        lo, hi = sorted(axis.get_view_interval())
        if lo <= 0 or np.log10(hi / lo) > LABELLED_MINORS_DECADES:
            return ''
        lead = round(x / 10 ** np.floor(np.log10(x) + 1e-9), 6)
        return _hz_label(x) if lead in (2.0, 5.0) else ''
    axis.set_major_locator(matplotlib.ticker.LogLocator(base=10.0, subs=(1.0,)))
    axis.set_major_formatter(matplotlib.ticker.FuncFormatter(_hz_label))
    axis.set_minor_locator(matplotlib.ticker.LogLocator(base=10.0, subs=np.arange(2, 10),
                                                        numticks=100))
    axis.set_minor_formatter(matplotlib.ticker.FuncFormatter(minor))
    if label is not None:
        (ax.set_xlabel if which == 'x' else ax.set_ylabel)(label)


def under_title(fig: plt.Figure) -> float:
    """Return the top of the panels' area, leaving a 0.4 inch band for the suptitle."""
    return 1.0 - 0.4 / fig.get_figheight()


def legend_below(fig: plt.Figure, axes: Sequence[plt.Axes], ncol: int = 3) -> float:
    """
    Put one legend of every labelled line under the panels, where it hides no data.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    axes : sequence of Axes
        Panels whose labelled artists go into the legend (duplicate labels once).
    ncol : int, optional
        Legend columns.

    Returns
    -------
    float
        The fraction of the figure height the legend takes (for ``tight_layout(rect=...)``).

    """
    seen: dict[str, Any] = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(lab, h)
    if not seen:
        return 0.0
    rows = -(-len(seen) // ncol)
    fig.legend(list(seen.values()), list(seen.keys()), loc='lower center', ncol=ncol,
               fontsize=8, frameon=False)
    return min(0.3, (0.28 * rows + 0.15) / fig.get_figheight())


def variance_of(frf: FrequencyResponse) -> tuple[np.ndarray | None, str]:
    """(variance, which): :meth:`FrequencyResponse.variance` and its kind ('' for none)."""
    return frf.variance(), frf.variance_kind() or ''


def _db(x: np.ndarray) -> np.ndarray:
    return 20.0 * np.log10(np.maximum(np.abs(x), 1e-300))


def _deg(p: np.ndarray) -> np.ndarray:
    return np.degrees(np.unwrap(np.angle(p)))


def _save(fig: plt.Figure, path: Path) -> Path:
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return Path(path)


def _channel_title(frf: FrequencyResponse, o: int, i: int) -> str:
    return f'{frf.inputs[i]} \u2192 {frf.outputs[o]}'


def bode_figure(frfs: Mapping[str, FrequencyResponse], path: Path, *,
                reference: FrequencyResponse | None = None, title: str = '',
                units: str | None = JOINT_STATE_FRF_UNIT) -> Path:
    """
    Bode diagram of every channel: magnitude [dB] above phase [deg], one column per input.

    Estimates are markers joined by thin lines, with a shaded +-2 sigma band (from the total
    variance, else the noise variance): |P| +- 2 sigma in magnitude and +-asin(2 sigma/|P|)
    in phase. ``reference`` is drawn as a black line under the estimates; ``units`` is the
    FRF's unit (magnitude in dB re 1 of it; None or '': unknown, plain dB). Every phase curve
    of a channel is unwrapped on the branch of the first one drawn (the reference, else the
    first estimate), so curves that agree are drawn on top of each other, never 360 deg
    apart. Where an estimate carries the multiple coherence of its outputs
    (``meta['coherence']``, (n_out, n_freq): the Welch H1 beside the LPM), a coherence panel
    is drawn under each output's phase. The legend sits under the panels.
    """
    first = next(iter(frfs.values()))
    n_out, n_in = first.noutputs, first.ninputs
    coherent = {k: v for k, v in frfs.items() if _coherence(v, n_out) is not None}
    rows = 3 if coherent else 2
    heights = [1.0, 1.0, 0.6][:rows] * n_out
    fig, axes = plt.subplots(rows * n_out, n_in, sharex=True, squeeze=False,
                             figsize=(4.6 * n_in + 0.6, 2.3 * sum(heights) + 0.8),
                             gridspec_kw={'height_ratios': heights})
    for o in range(n_out):
        for i in range(n_in):
            ax_m, ax_p = axes[rows * o, i], axes[rows * o + 1, i]
            anchor = None
            if reference is not None and reference.response.shape[:2] == (n_out, n_in):
                phase = _deg(reference.response[o, i])
                ax_m.semilogx(reference.freq_hz, _db(reference.response[o, i]), **REF_STYLE,
                              label='reference')
                ax_p.semilogx(reference.freq_hz, phase, **REF_STYLE)
                anchor = (reference.freq_hz, phase)
            for k, (label, frf) in enumerate(frfs.items()):
                if frf.response.shape[:2] == (n_out, n_in):
                    phase = _bode_channel(ax_m, ax_p, frf, o, i, f'C{k}', label, anchor)
                    anchor = anchor or (frf.freq_hz, phase)
            ax_m.set_title(_channel_title(first, o, i), fontsize=9)
            ax_m.set_ylabel((f'|P| [dB re 1 {units}]' if units else '|P| [dB]') if i == 0
                            else '')
            ax_p.set_ylabel('phase [deg]' if i == 0 else '')
            shown = [ax_m, ax_p]
            if coherent:
                shown.append(axes[rows * o + 2, i])
                _coherence_panel(axes[rows * o + 2, i], coherent, o, first.outputs[o], i == 0,
                                 colors={k: f'C{n}' for n, k in enumerate(frfs)})
            for ax in shown:
                ax.grid(True, which='both', alpha=0.3)
                frequency_axis(ax, label='frequency [Hz]' if ax is shown[-1] and o == n_out - 1
                               else None)
    bottom = legend_below(fig, [axes[0, 0]])
    fig.suptitle(title or 'Frequency response estimates (shaded: \u00b12\u03c3)')
    fig.tight_layout(rect=(0, bottom, 1, under_title(fig)))
    return _save(fig, path)


def _coherence(frf: FrequencyResponse, n_out: int) -> np.ndarray | None:
    coh = frf.coherence
    return coh if coh is not None and coh.shape[0] == n_out else None


def _coherence_panel(ax: plt.Axes, frfs: Mapping[str, FrequencyResponse], o: int, output: str,
                     label: bool, colors: Mapping[str, str]) -> None:
    for k, frf in frfs.items():
        ax.semilogx(frf.freq_hz, _coherence(frf, frf.noutputs)[o], '.-', ms=2, lw=0.5,
                    color=colors[k], zorder=MEASURED_Z)
    ax.set_ylim(0.0, 1.05)
    ax.set_ylabel('coherence [-]' if label else '')
    ax.set_title(f'multiple coherence of {output} ({", ".join(frfs)})', fontsize=8)


def aligned_phase_deg(freq_hz: np.ndarray, p: np.ndarray,
                      anchor: tuple[np.ndarray, np.ndarray] | None) -> np.ndarray:
    """
    Unwrap the phase of ``p`` [deg] on the 360 deg branch closest to ``anchor``.

    Parameters
    ----------
    freq_hz : ndarray
        Ascending frequencies of ``p``.
    p : ndarray
        Complex FRF values.
    anchor : (ndarray, ndarray) or None
        Ascending frequencies and unwrapped phase [deg] of the curve to align with; None:
        the plain unwrapped phase.

    Returns
    -------
    ndarray
        The unwrapped phase, shifted by the whole number of turns that brings its median
        difference to the anchor (on their common band, else at the nearest ends) within
        +-180 deg.

    """
    deg = _deg(p)
    if anchor is None or deg.size == 0 or anchor[0].size == 0:
        return deg
    fa, da = anchor
    common = (freq_hz >= fa[0]) & (freq_hz <= fa[-1])
    if np.any(common):
        diff = np.median(deg[common] - np.interp(freq_hz[common], fa, da))
    else:
        diff = deg[0] - np.interp(freq_hz[0], fa, da)
    return deg - 360.0 * np.round(diff / 360.0)


def _bode_channel(ax_m: plt.Axes, ax_p: plt.Axes, frf: FrequencyResponse, o: int, i: int,
                  color: str, label: str,
                  anchor: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    f, p = frf.freq_hz, frf.response[o, i]
    var, which = variance_of(frf)
    band = f' (\u00b12\u03c3 {which})' if var is not None else ''
    ax_m.semilogx(f, _db(p), '.-', color=color, ms=3, lw=0.5, label=f'{label}{band}',
                  zorder=MEASURED_Z)
    phase = aligned_phase_deg(f, p, anchor)
    ax_p.semilogx(f, phase, '.-', color=color, ms=3, lw=0.5, zorder=MEASURED_Z)
    if var is None:
        return phase
    sig2 = 2.0 * np.sqrt(np.maximum(var[o, i], 0.0))
    mag = np.abs(p)
    lo = _db(np.maximum(mag - sig2, mag * 1e-3))
    ax_m.fill_between(f, lo, _db(mag + sig2), color=color, alpha=0.2, lw=0)
    dphi = np.degrees(np.arcsin(np.clip(sig2 / np.maximum(mag, 1e-300), 0.0, 1.0)))
    ax_p.fill_between(f, phase - dphi, phase + dphi, color=color, alpha=0.2, lw=0)
    return phase


def snr_figure(frfs: Mapping[str, FrequencyResponse], path: Path) -> Path | None:
    """SNR per line, 10 log10(|P|^2 / var) [dB], one panel per channel; None without variances."""
    with_var = {k: v for k, v in frfs.items() if variance_of(v)[0] is not None}
    if not with_var:
        return None
    first = next(iter(with_var.values()))
    n_out, n_in = first.noutputs, first.ninputs
    fig, axes = plt.subplots(n_out, n_in, figsize=(4.6 * n_in + 0.6, 2.6 * n_out + 0.8),
                             sharex=True, sharey=True, squeeze=False)
    for k, (label, frf) in enumerate(frfs.items()):
        var, which = variance_of(frf)
        if var is None or frf.response.shape[:2] != (n_out, n_in):
            continue
        snr = 10 * np.log10(np.abs(frf.response) ** 2 / np.maximum(var, 1e-300))
        for o in range(n_out):
            for i in range(n_in):
                axes[o, i].semilogx(frf.freq_hz, snr[o, i], '.-', color=f'C{k}', ms=3, lw=0.5,
                                    label=f'{label} ({which} variance)')
    for o in range(n_out):
        for i in range(n_in):
            ax = axes[o, i]
            ax.axhline(20, color='0.4', ls='--', lw=0.8, label='20 dB: \u03c3 = 10 % of |P|')
            ax.axhline(0, color='C3', ls=':', lw=0.8, label='0 dB: \u03c3 = |P|')
            ax.set_title(_channel_title(first, o, i), fontsize=9)
            ax.grid(True, which='both', alpha=0.3)
            frequency_axis(ax, label='frequency [Hz]' if o == n_out - 1 else None)
            if i == 0:
                ax.set_ylabel('|P|\u00b2 / var [dB]')
    bottom = legend_below(fig, [axes[0, 0]])
    fig.suptitle('Signal-to-noise ratio per frequency line (higher is better)')
    fig.tight_layout(rect=(0, bottom, 1, under_title(fig)))
    return _save(fig, path)


def spectrogram_figure(x: np.ndarray, fs: float, names: Sequence[str], path: Path, *,
                       f_range: tuple[float, float] = (1.0, 60.0), t0: float = 0.0,
                       quantity: str = 'torque', unit: str = 'N m') -> Path:
    """
    PSD over time of each column of ``x`` (scipy.signal.spectrogram), log frequency axis.

    Windows of about 2 s (Hann, 7/8 overlap) resolve 1 Hz; colour is 10 log10 PSD in
    dB re 1 unit^2/Hz, the colour range spans 60 dB below the maximum.
    """
    x = np.asarray(x, dtype=float)
    n = x.shape[1]
    f_hi = min(f_range[1], 0.5 * fs)
    nper = int(min(x.shape[0], 2 ** int(np.ceil(np.log2(2.0 * fs)))))
    fig, axes = plt.subplots(n, 1, figsize=(10, 2.4 * n + 0.9), sharex=True, squeeze=False)
    for j in range(n):
        ax = axes[j, 0]
        f, t, sxx = signal.spectrogram(x[:, j] - np.mean(x[:, j]), fs=fs, window='hann',
                                       nperseg=nper, noverlap=7 * nper // 8, scaling='density')
        sel = (f >= f_range[0] * 0.9) & (f <= f_hi * 1.05)
        db = 10 * np.log10(np.maximum(sxx[sel], 1e-300))
        top = float(np.max(db)) if db.size else 0.0
        mesh = ax.pcolormesh(t + t0, f[sel], db, shading='gouraud', cmap='viridis',
                             vmin=top - 60, vmax=top, rasterized=True)
        frequency_axis(ax, 'y', label=f'{names[j]}\nfrequency [Hz]')
        ax.set_ylim(f_range[0], f_hi)
        fig.colorbar(mesh, ax=ax, pad=0.01).set_label(f'PSD [dB re ({unit})\u00b2/Hz]',
                                                      fontsize=8)
    axes[-1, 0].set_xlabel('time [s]')
    fig.suptitle(f'Power spectral density of the {quantity} over time '
                 f'({nper / fs:.3g} s Hann windows)')
    fig.tight_layout()
    return _save(fig, path)


def timeseries_figure(t: np.ndarray, series: Sequence[tuple[str, np.ndarray, str]],
                      names: Sequence[str], path: Path, *, max_points: int = 20000) -> Path:
    """Signals over time: one row per joint, one column per (label, (N, n) array, unit)."""
    t = np.asarray(t, dtype=float)
    step = max(1, t.size // max_points)
    n = len(names)
    fig, axes = plt.subplots(n, len(series), figsize=(5.0 * len(series) + 0.5, 1.9 * n + 0.9),
                             sharex=True, squeeze=False)
    for c, (label, data, unit) in enumerate(series):
        for j in range(n):
            ax = axes[j, c]
            ax.plot(t[::step], data[::step, j], lw=0.6, color=f'C{c}')
            ax.grid(True, alpha=0.3)
            if j == 0:
                ax.set_title(f'{label} [{unit}]', fontsize=9)
            if c == 0:
                ax.set_ylabel(names[j])
        axes[-1, c].set_xlabel('time [s]')
    fig.suptitle('Recorded signals' + (f' (every {step}th sample)' if step > 1 else ''))
    fig.tight_layout()
    return _save(fig, path)


def iteration_figure(iterations: Sequence[Mapping[str, Any]], path: Path,
                     channel_names: Sequence[str] | None = None,
                     tolerance_db: float | None = None) -> Path:
    """Error of the plant input to u_des [dB] per chirp iteration, one line per channel."""
    its = np.array([int(it['iteration']) for it in iterations])
    err = np.array([np.atleast_1d(np.asarray(iteration_errors(it), dtype=float))
                    for it in iterations])
    fig, ax = plt.subplots(figsize=(7, 4))
    for c in range(err.shape[1]):
        name = channel_names[c] if channel_names and c < len(channel_names) else f'channel {c}'
        ax.plot(its, err[:, c], 'o-', label=name)
    if tolerance_db is not None:
        ax.axhline(tolerance_db, color='0.4', ls='--', lw=0.8, label='tolerance')
    ax.axhline(0, color='k', lw=0.6)
    ax.set_xticks(its)
    ax.set_xlabel('iteration')
    ax.set_ylabel('error of u to u_des [dB]')
    ax.set_title('Chirp iteration (Sec. 5.3): convergence of the plant input to u_des')
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def iteration_errors(it: Mapping[str, Any]) -> list[float]:
    """Per-channel error [dB] of one iteration dict ('error_db' or 'error_db_per_channel')."""
    for key in ('error_db', 'error_db_per_channel'):
        if key in it:
            return [float(v) for v in np.atleast_1d(it[key])]
    raise KeyError(f"iteration {it.get('iteration')!r} has no 'error_db' list")


def magnitude_db(p: np.ndarray) -> np.ndarray:
    """20 log10 |p| (floored at 1e-300)."""
    return 20 * np.log10(np.maximum(np.abs(p), 1e-300))


def unwrapped_phase_deg(p: np.ndarray) -> np.ndarray:
    """Unwrapped phase of p in degrees."""
    return np.degrees(np.unwrap(np.angle(p)))


def paper_figure(results: dict[str, Any], case: str, path: Path) -> Path:
    """
    Draw Figure 4 or 5 of the paper.

    Figure 4 (case 'coulomb') / Figure 5 ('stiffness') of the paper: both designs side by
    side, magnitude and phase, linear model vs the linear-case and nonlinear-case estimates.
    """
    label = {'coulomb': 'Fc = 50 N m, k2 = k1', 'stiffness': 'Fc = 0 N m, k2 = 1.7 k1'}[case]
    fig, axes = plt.subplots(2, 2, figsize=(11, 6.5), sharex=True)
    f_an = np.asarray(results['analytic']['freq_hz'])
    p_an = np.asarray(results['analytic']['re']) + 1j * np.asarray(results['analytic']['im'])
    for col, design in enumerate(('chirp', 'multisine')):
        ax_m, ax_p = axes[0, col], axes[1, col]
        ax_m.semilogx(f_an, _db(p_an), 'k-', lw=1.2, label='linear model', zorder=2)
        ax_p.semilogx(f_an, _deg(p_an), 'k-', lw=1.2, zorder=2)
        for name, style, lab in (('linear', 'C0o', 'FRF est. Fc = 0 N m, k2 = k1'),
                                 (case, 'C3x', f'FRF est. {label}')):
            e = results['cases'][name][design]
            f = np.asarray(e['freq_hz'])
            p = np.asarray(e['re']) + 1j * np.asarray(e['im'])
            ax_m.semilogx(f, _db(p), style, ms=3.5, label=lab, zorder=MEASURED_Z)
            ax_p.semilogx(f, _deg(p), style, ms=3.5, zorder=MEASURED_Z)
        ax_m.set_title(f'{design} excitation')
        ax_m.set_ylabel(f'|P| [dB re 1 {JOINT_STATE_FRF_UNIT}]')
        ax_p.set_ylabel('phase [deg]')
        for ax in (ax_m, ax_p):
            ax.grid(True, which='both', alpha=0.3)
            frequency_axis(ax, label='frequency [Hz]' if ax is ax_p else None)
    bottom = legend_below(fig, [axes[0, 0]])
    fig.suptitle(f'Saupe & Knoblach (2015) Sec. 6 example: tau_m \u2192 dq_m, {label}')
    fig.tight_layout(rect=(0, bottom, 1, under_title(fig)))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def diagnosis_figures(out: Path, res: DiagnosisResult, rec: Any, mode: str
                      ) -> list[tuple[str, str]]:
    """
    Figures of ``frf-ident diagnose``: (file name, caption) pairs written into ``out``.

    Experiments: measured vs nominal vs extended FRF (diagonal) with the residual spectrum,
    and the torque residual against velocity and position. Time series: the inverse-dynamics
    residual in time, against velocity and against position.
    """
    figs: list[tuple[str, str]] = []
    if mode == 'experiments':
        est = res.detail.estimates
        n = rec.velocity.shape[1]
        fig, ax = plt.subplots(3, n, figsize=(5 * n, 9), squeeze=False, sharex=True)
        for i in range(n):
            for key, style in (('multisine', '-'), ('chirp', '--')):
                if key not in est['measured']:
                    continue
                f = est['measured'][key].freq_hz
                # models first and thinner, the measured curve last and on top
                for lab, col, lw, z in (('nominal', 'tab:red', 1.0, 2),
                                        ('extended', 'tab:green', 1.0, 2),
                                        ('measured', 'k', 1.6, MEASURED_Z)):
                    p = est[lab][key].response[i, i]
                    kw = {'color': col, 'lw': lw, 'zorder': z}
                    ax[0, i].semilogx(f, _db(p), style, label=f'{lab} {key}', **kw)
                    ax[1, i].semilogx(f, np.degrees(np.unwrap(np.angle(p))), style, **kw)
                for lab, col in (('nominal', 'tab:red'), ('extended', 'tab:green')):
                    r = est['measured'][key].response[i, i] / est[lab][key].response[i, i]
                    ax[2, i].semilogx(f, _db(r), style, color=col,
                                      label=f'{key}: measured/{lab}')
            for u in res.unexplained:
                if u.axis == rec.joint_names[i] and u.signature.band_hz:
                    ax[2, i].axvspan(*u.signature.band_hz, color='tab:orange', alpha=0.2,
                                     label='unexplained band')
            ax[0, i].set_title(f'{rec.joint_names[i]}: dq_m/tau_m (held-out data)')
            ax[0, i].set_ylabel(f'|P| [dB re 1 {JOINT_STATE_FRF_UNIT}]' if i == 0 else '')
            ax[1, i].set_ylabel('phase [deg]' if i == 0 else '')
            ax[2, i].set_ylabel('|P_measured / P_model| [dB]' if i == 0 else '')
            for a in ax[:, i]:
                a.grid(True, which='both', alpha=0.3)
                frequency_axis(a, label='frequency [Hz]' if a is ax[2, i] else None)
        bottom = legend_below(fig, list(ax[0]) + list(ax[2]), ncol=4)
        fig.tight_layout(rect=(0, bottom, 1, under_title(fig)))
        _save(fig, out / 'bode.png')
        figs.append(('bode.png', 'Measured vs nominal vs extended FRF (diagonal), and the '
                                 'residual spectrum |P_measured / P_model|'))
        sims = res.detail.sims
        fig, ax = plt.subplots(2, n, figsize=(5 * n, 6), squeeze=False)
        step = max(1, rec.t.size // 20000)
        for i in range(n):
            for lab, col in (('nominal', 'tab:red'), ('extended', 'tab:green')):
                du = rec.effort[::step, i] - sims[lab].effort[::step, i]
                ax[0, i].plot(rec.velocity[::step, i], du, '.', ms=1, color=col, label=lab)
                ax[1, i].plot(rec.position[::step, i], du, '.', ms=1, color=col, label=lab)
            ax[0, i].set_xlabel('motor velocity [rad/s]')
            ax[1, i].set_xlabel('motor position [rad]')
            ax[0, i].set_ylabel('torque residual [N m]')
            ax[0, i].legend(markerscale=8, fontsize=7)
            ax[0, i].set_title(rec.joint_names[i])
        _save(fig, out / 'residual.png')
        figs.append(('residual.png', 'Measured minus simulated torque (same reference, same '
                                     'controller) against velocity and position'))
        return figs
    r = res.detail.residual
    n = r.f.shape[1]
    fig, ax = plt.subplots(3, n, figsize=(5 * n, 9), squeeze=False)
    for i in range(n):
        nom = r.f[:, i]
        nom = lowpass(nom, rec.fs, FC_HZ)   # as the diagnosis low-passed its predictions
        ext = nom - (r.pred_extended[:, i] - r.pred_baseline[:, i])
        ax[0, i].plot(r.t, nom, 'k', lw=0.6, label='nominal residual')
        ax[0, i].plot(r.t, ext, color='tab:green', lw=0.6, label='extended residual')
        vm = np.r_[False, r.val_mask, False].astype(int)
        starts, ends = np.flatnonzero(np.diff(vm) == 1), np.flatnonzero(np.diff(vm) == -1)
        for k, (a, b) in enumerate(zip(starts, ends)):
            ax[0, i].axvspan(r.t[a], r.t[b - 1], color='0.9',
                             label='held out' if k == 0 else None)
        ax[0, i].set_title(rec.joint_names[i])
        ax[0, i].set_xlabel('t [s]')
        ax[0, i].legend(fontsize=6)
        ax[1, i].plot(r.v[:, i], nom, '.', ms=1, color='tab:red')
        ax[1, i].plot(r.v[:, i], ext, '.', ms=1, color='tab:green')
        ax[0, i].set_ylabel('residual [N m]' if i == 0 else '')
        ax[1, i].set_xlabel('velocity [rad/s]')
        ax[1, i].set_ylabel('inverse-dynamics residual [N m]' if i == 0 else '')
        ax[2, i].plot(r.q[:, i], nom, '.', ms=1, color='tab:red')
        ax[2, i].plot(r.q[:, i], ext, '.', ms=1, color='tab:green')
        ax[2, i].set_xlabel('position [rad]')
        ax[2, i].set_ylabel('inverse-dynamics residual [N m]' if i == 0 else '')
    _save(fig, out / 'residual.png')
    figs.append(('residual.png', 'Inverse-dynamics residual (measured torque minus the torque '
                                 'the model needs for the measured motion, low-passed) of the '
                                 'nominal (black/red) and extended (green) model, in time, '
                                 'against velocity and position; grey: held-out part'))
    return figs
