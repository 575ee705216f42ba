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
`frf-ident reproduce paper`: the academic example of Saupe & Knoblach (2015), Section 6.

Single flexible joint (Jm 35, Jo 150, d 400, k1 1.5e5, bs 1e-3, torque limit 150 N m), open
loop, no noise; three cases (linear, Fc = 50 N m, k2 = 1.7 k1) x two designs (odd random
multisine 1-60 Hz, 12.3 s, n_p = 30, n_q = 1; exponential chirp 1-60 Hz, 20 s, 150 N m).
Writes results.json (estimates, analytic FRF, power ratio, the paper's findings as numbers)
and Bode plots like the paper's Figures 4 and 5.
"""
from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

from frf_ident.app.console import progress_bar
from frf_ident.app.outdir import clear_outputs
from frf_ident.core.excitation.chirp import chirp_phase_flips, ChirpDesign
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.core.model.params import AxisParams, RobotParams
from frf_ident.core.progress import Progress, sink
from frf_ident.core.simulation.analytic import two_mass_frf
from frf_ident.core.simulation.open_loop import (resonance_peak, run_open_loop_chirp,
                                                 run_open_loop_multisine)
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.errors import DesignError
import numpy as np

_log = logging.getLogger(__name__)

__all__ = ['CASES', 'OUTPUT_FILES', 'PAPER_AXIS', 'PAPER_REALISATIONS', 'PAPER_SEED',
           'RESONANCE_BAND', 'analytic_linear', 'findings', 'paper_plant', 'reproduce_paper',
           'write_results']

PAPER_AXIS = {'name': 'joint_1', 'motor_inertia': 35.0, 'link_inertia': 150.0,
              'stiffness': 1.5e5, 'damping': 400.0, 'torque_limit': 150.0}
CASES = {
    'linear': {},
    'coulomb': {'coulomb_friction': 50.0},
    'stiffness': {'stiffness_k2': 1.7 * 1.5e5, 'stiffness_breakpoint': 1e-3},
}
RESONANCE_BAND = (6.0, 40.0)
#: the files :func:`write_results` writes into its output directory, results.json first
OUTPUT_FILES = ('results.json', 'figure4_coulomb.png', 'figure5_stiffness.png')


def paper_plant(case: str, fs: float = 1000.0, substeps: int = 4) -> FlexibleJointPlant:
    """
    Build the Section 6 single-joint plant of one case (eqs. 20-22).

    Parameters
    ----------
    case : {'linear', 'coulomb', 'stiffness'}
        A key of :data:`CASES`: no nonlinearity, Fc = 50 N m, or k2 = 1.7 k1 beyond
        bs = 1e-3 rad.
    fs : float, optional
        Sample rate in Hz.
    substeps : int, optional
        Integrator substeps per sample.

    Returns
    -------
    FlexibleJointPlant
        The plant (open loop, no noise, torque limit 150 N m).

    Raises
    ------
    KeyError
        ``case`` is not one of :data:`CASES`.

    """
    axis = AxisParams(**PAPER_AXIS, **CASES[case])
    return FlexibleJointPlant(RobotParams([axis], sample_rate=fs, substeps=substeps))


def analytic_linear(freq_hz: np.ndarray) -> np.ndarray:
    """
    Return the analytic FRF dq_m / tau_m of the linear Section 6 plant.

    Parameters
    ----------
    freq_hz : array_like
        Frequencies in Hz.

    Returns
    -------
    ndarray of complex
        :func:`~frf_ident.core.simulation.analytic.two_mass_frf` with :data:`PAPER_AXIS`.

    """
    a = PAPER_AXIS
    return two_mass_frf(freq_hz, a['motor_inertia'], a['link_inertia'], a['stiffness'],
                        a['damping'])


#: the paper's n_p of the Section 6 multisine, and the seed of our reproduction
PAPER_REALISATIONS = 30
PAPER_SEED = 2015


def reproduce_paper(*, n_realisations: int = PAPER_REALISATIONS, seed: int = PAPER_SEED,
                    fs: float = 1000.0, substeps: int = 4,
                    progress: Progress | None = None) -> dict[str, Any]:
    """
    Run all cases and designs of Section 6; return the results.json content.

    The multisine realisations are drawn once and used for every case, so the cases differ
    only in the plant.

    Parameters
    ----------
    n_realisations : int, optional
        Multisine realisations n_p (the paper's 30); n_q = 1 after one transient period.
    seed : int, optional
        Seed of the random phases.
    fs : float, optional
        Sample rate of the simulation in Hz.
    substeps : int, optional
        Integrator substeps per sample.
    progress : callable, optional
        Called with one line per experiment; default silent.

    Returns
    -------
    dict
        ``paper``, ``plant``, ``multisine_design``, ``chirp_design``, ``cases`` (case ->
        design -> estimate, input power ...), ``power_ratio`` (multisine over chirp input
        power, linear case), ``power_ratio_per_realisation``, ``analytic`` (the linear FRF)
        and ``findings`` (:func:`findings`).

    Raises
    ------
    DesignError
        ``n_realisations`` < 1, or ``seed`` negative.

    """
    if seed < 0:
        raise DesignError(f'--seed {seed}: expected an integer >= 0')
    say = sink(progress)
    design = design_odd_multisine(1.0, 60.0, bound=150.0, resolution_hz=0.1, fs=fs)
    rng = np.random.default_rng(seed)
    realisations = [multisine_realisation(design, 1, rng, fs=fs) for _ in range(n_realisations)]
    chirp = ChirpDesign(1.0, 60.0, 20.0, np.array([[150.0]]))
    out: dict[str, Any] = {
        'paper': 'Saupe & Knoblach (2015), Section 6',
        'plant': dict(PAPER_AXIS, stiffness_breakpoint=1e-3),
        'multisine_design': {**design.to_dict(), 'n_p': n_realisations, 'n_q': 1,
                             'transient_periods': 1, 'period_s': design.period},
        'chirp_design': chirp.to_dict(),
        'cases': {},
    }
    with progress_bar(2 * len(CASES), 'reproduce', unit='run') as bar:
        for case in CASES:
            plant = paper_plant(case, fs, substeps)
            _log.debug('%s: multisine (%d realisations x %.1f s)', case, n_realisations,
                       design.period)
            ms = run_open_loop_multisine(plant, design, n_realisations=n_realisations,
                                         n_periods=1, rng=rng, realisations=realisations)
            bar.update()
            _log.debug('%s: chirp (%.0f s)', case, chirp.duration)
            ch = run_open_loop_chirp(plant, chirp, chirp_phase_flips(1))
            bar.update()
            say(f'{case}: multisine {n_realisations} x {design.period:.1f} s and chirp '
                f'{chirp.duration:.0f} s simulated')
            out['cases'][case] = {
                'multisine': _estimate_entry(ms.frf, ms.input_power, detection=ms.detection,
                                             crest_factor=ms.crest_factor),
                'chirp': _estimate_entry(ch.frf, ch.input_power),
            }
    lin_ms = out['cases']['linear']['multisine']
    out['power_ratio'] = lin_ms['input_power'] / out['cases']['linear']['chirp']['input_power']
    out['power_ratio_per_realisation'] = _power_ratios(realisations, design, fs, out)
    f_an = np.geomspace(0.8, 70, 600)
    p_an = analytic_linear(f_an)
    out['analytic'] = {'freq_hz': f_an.tolist(), 're': p_an.real.tolist(),
                       'im': p_an.imag.tolist()}
    out['findings'] = findings(out)
    return out


def _estimate_entry(frf, input_power: float, **extra: Any) -> dict[str, Any]:
    p = frf.response[0, 0]
    entry = {'freq_hz': frf.freq_hz.tolist(), 're': p.real.tolist(), 'im': p.imag.tolist(),
             'input_power': input_power}
    if frf.total_variance is not None:
        entry['total_variance'] = frf.total_variance[0, 0].tolist()
    entry.update(extra)
    return entry


def _power_ratios(realisations, design, fs, out) -> list[float]:
    t = np.arange(design.period_samples(fs)) / fs
    chirp_power = out['cases']['linear']['chirp']['input_power']
    return [float(np.mean(r.evaluate(t)[0] ** 2) / chirp_power) for r in realisations]


def _complex(entry: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(entry['freq_hz']), np.asarray(entry['re']) + 1j * np.asarray(entry['im'])


def findings(results: dict[str, Any]) -> dict[str, Any]:
    """
    Return the paper's findings as numbers: the estimates against the analytic FRF.

    Parameters
    ----------
    results : dict
        The ``cases`` and ``power_ratio`` of :func:`reproduce_paper`'s result.

    Returns
    -------
    dict
        ``linear`` (median / max |error| in dB per design), the analytic resonance
        frequency and peak, ``peaks`` per case/design, ``coulomb`` (drop of the resonance
        peak in dB with Fc = 50 N m), ``stiffness`` (relative shift of the resonance with
        k2 = 1.7 k1) and ``power_ratio``.

    """
    f_lin = {}
    for design in ('multisine', 'chirp'):
        f, p = _complex(results['cases']['linear'][design])
        err = 20 * np.log10(np.abs(p / analytic_linear(f)))
        f_lin[design] = {'median_abs_error_db': float(np.median(np.abs(err))),
                         'max_abs_error_db': float(np.max(np.abs(err)))}
    f_dense = np.geomspace(*RESONANCE_BAND, 4000)
    fr_true, peak_true = resonance_peak(f_dense, analytic_linear(f_dense), RESONANCE_BAND)
    peaks = {}
    for case in results['cases']:
        for design in ('multisine', 'chirp'):
            f, p = _complex(results['cases'][case][design])
            fr, pk = resonance_peak(f, p, RESONANCE_BAND)
            peaks[f'{case}/{design}'] = {'resonance_hz': fr, 'peak_db': pk}
    lin_ms = peaks['linear/multisine']
    lin_ch = peaks['linear/chirp']
    return {
        'linear': f_lin,
        'analytic_resonance_hz': fr_true,
        'analytic_peak_db': peak_true,
        'peaks': peaks,
        'coulomb': {
            'multisine_peak_drop_db': lin_ms['peak_db'] - peaks['coulomb/multisine']['peak_db'],
            'chirp_peak_drop_db': lin_ch['peak_db'] - peaks['coulomb/chirp']['peak_db'],
        },
        'stiffness': {
            'chirp_resonance_shift': peaks['stiffness/chirp']['resonance_hz'] / fr_true - 1,
            'multisine_resonance_shift':
                peaks['stiffness/multisine']['resonance_hz'] / fr_true - 1,
        },
        'power_ratio': results['power_ratio'],
    }


def write_results(results: dict[str, Any], out_dir: Path) -> list[Path]:
    """
    Write results.json and the Figure 4/5 style Bode plots into ``out_dir``.

    Parameters
    ----------
    results : dict
        The result of :func:`reproduce_paper`.
    out_dir : Path
        Output directory (created if missing); its :data:`OUTPUT_FILES` of an earlier run
        are removed before the new ones are written, nothing else is touched.

    Returns
    -------
    list of Path
        results.json, figure4_coulomb.png and figure5_stiffness.png.

    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    clear_outputs(out_dir, OUTPUT_FILES)
    path = out_dir / OUTPUT_FILES[0]
    path.write_text(json.dumps(results, indent=1))
    from frf_ident.report.figures import paper_figure
    written = [path]
    for name, case in zip(OUTPUT_FILES[1:], ('coulomb', 'stiffness')):
        written.append(paper_figure(results, case, out_dir / name))
    return written
