"""The paper-reproduction figures (matplotlib, Agg). Bode grids of estimates:
:func:`frf_ident.report.figures.bode_figure`."""
from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402



def _db(p: np.ndarray) -> np.ndarray:
    return 20 * np.log10(np.maximum(np.abs(p), 1e-300))


def _deg(p: np.ndarray) -> np.ndarray:
    return np.degrees(np.unwrap(np.angle(p)))


def paper_figure(results: dict[str, Any], case: str, path: Path,
                 analytic: Callable[[np.ndarray], np.ndarray]) -> Path:
    """Figure 4 (case 'coulomb') / Figure 5 ('stiffness') of the paper: both designs side by
    side, magnitude and phase, linear model vs the linear-case and nonlinear-case estimates."""
    label = {'coulomb': 'Fc = 50 N m, k2 = k1', 'stiffness': 'Fc = 0 N m, k2 = 1.7 k1'}[case]
    fig, axes = plt.subplots(2, 2, figsize=(11, 6.5), sharex=True)
    f_an = np.asarray(results['analytic']['freq_hz'])
    p_an = np.asarray(results['analytic']['re']) + 1j * np.asarray(results['analytic']['im'])
    for col, design in enumerate(('chirp', 'multisine')):
        ax_m, ax_p = axes[0, col], axes[1, col]
        ax_m.semilogx(f_an, _db(p_an), 'k-', lw=1.2, label='linear model')
        ax_p.semilogx(f_an, _deg(p_an), 'k-', lw=1.2)
        for name, style, lab in (('linear', 'C0o', 'FRF est. Fc = 0 N m, k2 = k1'),
                                 (case, 'C3x', f'FRF est. {label}')):
            e = results['cases'][name][design]
            f = np.asarray(e['freq_hz'])
            p = np.asarray(e['re']) + 1j * np.asarray(e['im'])
            ax_m.semilogx(f, _db(p), style, ms=3.5, label=lab)
            ax_p.semilogx(f, _deg(p), style, ms=3.5)
        ax_m.set_title(f'{design} excitation')
        ax_m.set_ylabel('|P| / dB (rad/s per N m)')
        ax_p.set_ylabel('phase / deg')
        ax_p.set_xlabel('f / Hz')
        for ax in (ax_m, ax_p):
            ax.grid(True, which='both', alpha=0.3)
    axes[0, 0].legend(fontsize=8, loc='lower left')
    fig.suptitle(f'Saupe & Knoblach (2015) Sec. 6 example: tau_m -> dq_m, {label}')
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
