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
`frf-ident fit`: a parametric model fitted to a measured FRF, with its uncertainty.

Stages of :func:`fit_frf`: read the FRF (an ``estimate`` directory's frf.json, or any FRF file
:func:`~frf_ident.io.export.read_frf` reads), keep the band, fit
(:mod:`frf_ident.app.fit_stages`: the physical two-mass model
per axis with ``physical``, and the coupled robot on a square FRF; else a common-denominator
rational model of the given order or the order :func:`~frf_ident.core.fit.rational.
select_order` chooses), write fit.json (:mod:`frf_ident.app.fit_document`), the figure and the
model: model.yaml (:mod:`frf_ident.app.fitted_model`) for the physical fit, model.mat
(A, B, C, D) for the rational one; with a model file, check its velocity PI on the measured
loop (:func:`frf_ident.app.loop.run_loop`); last fit.html, the report page of it all.
``estimate --fit`` runs :func:`fit_frf` on the FRF it has just written.

Printed per fit: the parameters with their reported errors (Cramer-Rao, widened by the
model-error bound where the cost test fails) and units, the delay as model.yaml's
``time_delay``, the cost test and a one-line verdict; for a coupled fit the per-axis
details go to the log (``-v``, fit.log) and each disagreement of a per-axis and the coupled
estimate beyond their errors is named.
"""
from __future__ import annotations

from dataclasses import dataclass
import json
from pathlib import Path
from typing import Any, Callable

from frf_ident.app.fit_document import cost_dict, coupled_dict, physical_dict, rational_dict
from frf_ident.app.fit_stages import MAX_ORDER, physical_stage, rational_stage
from frf_ident.app.fitted_model import hold_of
from frf_ident.app.frf_source import axis_channels, read_source
from frf_ident.app.loop import LoopOutcome, run_loop
from frf_ident.app.outdir import clear_outputs
from frf_ident.core.fit.coupled import CoupledFit
from frf_ident.core.fit.physical import PhysicalFit
from frf_ident.core.fit.rational import OrderSelection
from frf_ident.core.jsonable import jsonable
from frf_ident.core.progress import Progress, sink
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.model_file import load_model
from frf_ident.report.fit_figures import fit_figure
from frf_ident.report.html import fit_sections, write_fit_report
import numpy as np

__all__ = ['FitOptions', 'FitOutcome', 'MAX_ORDER', 'OUTPUT_FILES', 'cost_dict', 'fit_columns',
           'fit_frf', 'is_fit_input', 'source_pose']

#: the files :func:`fit_frf` may write into its output directory (loop.*: with a model file)
OUTPUT_FILES = ('fit.json', 'fit.png', 'fit.html', 'model.yaml', 'model.xml', 'model.urdf',
                'model.mat', 'loop.json', 'loop.png')


@dataclass
class FitOutcome:
    """
    What ``fit`` found and wrote.

    Attributes
    ----------
    physical : list of PhysicalFit or None
        Per-axis physical fits (``physical=True``).
    coupled : CoupledFit or None
        All axes and the link coupling (``physical=True`` on a square FRF of >= 2 axes).
    rational : OrderSelection or None
        The rational fits tried and the chosen one (``physical=False``).
    files : list of Path
        The files written.
    loop : LoopOutcome or None
        The model file's velocity PI checked on the measured FRF (with ``model``).

    """

    physical: list[PhysicalFit] | None
    coupled: CoupledFit | None
    rational: OrderSelection | None
    files: list[Path]
    loop: LoopOutcome | None = None


@dataclass(frozen=True)
class FitOptions:
    """
    The keyword arguments of :func:`fit_frf` (how ``estimate --fit`` passes them on).

    Attributes
    ----------
    order : int or None
        Rational model order; None: chosen by the cost test.
    physical : bool
        Fit the two-mass joint per axis.
    delay_s : float or None
        Known input delay [s]; None: fitted (physical fit).
    band : tuple of float or None
        (low, high) [Hz] to fit.
    model : str or Path or None
        Model file: the base of model.yaml and the controller the margins check.

    """

    order: int | None = None
    physical: bool = False
    delay_s: float | None = None
    band: tuple[float, float] | None = None
    model: str | Path | None = None

    def __post_init__(self) -> None:
        """Refuse a delay for the rational fit (FrfIdentInputError, one line)."""
        if self.delay_s is not None and not self.physical:
            raise FrfIdentInputError(f'--delay {self.delay_s}: only with --physical (the '
                                     f'rational model has no delay: its order takes up the '
                                     f'phase lag)')


def is_fit_input(p: Path) -> bool:
    """Return whether ``p`` is an estimate output folder (one holding frf.json)."""
    return (Path(p) / 'frf.json').is_file()


def source_pose(source: str | Path) -> list[float] | None:
    """
    Return the pose [rad] an FRF was measured at, when its estimate folder records one.

    Parameters
    ----------
    source : str or Path
        An estimate output folder (its summary.json, from a bag of ``identify --poses``)
        or an FRF file (no pose).

    Returns
    -------
    list of float or None
        The joint positions, or None.

    """
    p = Path(source) / 'summary.json'
    if not p.is_file():
        return None
    try:
        pose = json.loads(p.read_text()).get('experiment', {}).get('pose_rad')
    except (OSError, ValueError, AttributeError):
        return None
    return [float(v) for v in pose] if isinstance(pose, list) else None


def fit_frf(source: str | Path, out: Path, *, order: int | None = None, physical: bool = False,
            delay_s: float | None = None, band: tuple[float, float] | None = None,
            model: str | Path | None = None, figure: bool = True,
            progress: Progress | None = None) -> FitOutcome:
    """
    Fit a model to a measured FRF and write fit.json, fit.png and the model.

    Parameters
    ----------
    source : str or Path
        Directory with frf.json, or an FRF file.
    out : Path
        Output directory (created if missing; the caller has checked it).
    order : int, optional
        Rational model order; None: chosen by :func:`~frf_ident.core.fit.rational.
        select_order` among 1..:data:`MAX_ORDER`. Ignored with ``physical``.
    physical : bool, optional
        Fit the two-mass flexible joint per axis instead and write model.yaml.
    delay_s : float, optional
        Known input delay of the physical model [s] (half a sample for a zero-order hold);
        None: fitted with the other parameters (ignored by the rational fit).
    band : tuple of float, optional
        (low, high) [Hz]: fit only these lines.
    model : str or Path, optional
        Model file whose other keys (limits, controller, sample rate) model.yaml keeps, and
        whose velocity PI is checked on the measured FRF (loop.json, loop.png; the margins
        section of fit.html) when it has one PI per axis of the FRF.
    figure : bool, optional
        Draw fit.png (default); a campaign of many FRFs may leave it out (it takes about
        ten times the fit's CPU time on a 3 x 3 FRF).
    progress : callable, optional
        Called with one line of text per stage.

    Returns
    -------
    FitOutcome
        The fits and the files written.

    Raises
    ------
    FrfIdentInputError
        The source cannot be read, the band keeps too few lines, an order is not >= 1, or a
        delay is given without ``physical``.

    """
    FitOptions(order, physical, delay_s, band, model)        # refuses what does not go together
    frf = read_source(source)
    if band is not None:
        frf = frf.select((frf.freq_hz >= band[0]) & (frf.freq_hz <= band[1]))
    if frf.freq_hz.size < 4:
        raise FrfIdentInputError(f'--band {band}: keeps {frf.freq_hz.size} lines of '
                                 f'{source}; a fit needs at least 4')
    var, which = frf.variance(), frf.variance_kind()
    say = sink(progress)
    say(f'fit: {frf.noutputs}x{frf.ninputs} FRF, {frf.freq_hz.size} lines '
        f'{frf.freq_hz.min():.3g}-{frf.freq_hz.max():.3g} Hz, weights: '
        f'{which + " variance" if which else "none (relative error)"}')
    out.mkdir(parents=True, exist_ok=True)
    clear_outputs(out, OUTPUT_FILES)
    res = (physical_stage(frf, var, delay_s, model, out, say) if physical
           else rational_stage(frf, var, order, out, say))
    files = res.files
    if figure:
        files.append(fit_figure(frf.freq_hz, res.measured, res.fitted, res.variance, res.names,
                                out / 'fit.png', res.verdicts))
    hold = hold_of(model) if physical else 0.0
    doc = {'source': str(source), 'pose_rad': source_pose(source),
           'freq_hz': [float(frf.freq_hz.min()), float(frf.freq_hz.max())],
           'n_lines': int(frf.freq_hz.size), 'variance': which,
           'delay_s': None if delay_s is None else float(delay_s),
           'physical': None if res.physical is None else
           [physical_dict(f, hold) for f in res.physical],
           'coupled': None if res.coupled is None else coupled_dict(res.coupled, hold),
           'rational': None if res.rational is None else rational_dict(res.rational),
           'files': [p.name for p in files] + ['fit.json']}
    (out / 'fit.json').write_text(json.dumps(jsonable(doc), indent=1))
    files.append(out / 'fit.json')
    say(f'fit: wrote {", ".join(p.name for p in files)} to {out}')
    loop = _loop_stage(source, out, model, len(axis_channels(frf)), say)
    sections = fit_sections(physical=res.physical or (), coupled=res.coupled,
                            rational=None if res.rational is None else res.rational.best,
                            check=None if loop is None else loop.check,
                            fit_png='fit.png' if figure else None,
                            loop_png=None if loop is None else 'loop.png', hold_s=hold)
    page = write_fit_report(out / 'fit.html', title=f'Fit of {source}', sections=sections)
    say(f'fit: report {page}')
    return FitOutcome(res.physical, res.coupled, res.rational, files + [page], loop)


def _loop_stage(source: str | Path, out: Path, model: str | Path | None, n_axes: int,
                say: Callable[[str], None]) -> LoopOutcome | None:
    """Check the model file's velocity PI on the measured FRF when it has one per axis."""
    if model is None:
        return None
    n_pi = load_model(model)[2].kp.size
    if n_pi != n_axes:
        say(f'loop: no margins: the controller of {model} has {n_pi} axes, the FRF {n_axes}')
        return None
    return run_loop(source, out, model=model, page=False, progress=say)


def fit_columns(source: Path, out: Path, progress: Progress, **options: Any) -> dict[str, Any]:
    """
    Fit one FRF of a campaign and return its summary columns (the task of ``fit A B ...``).

    Parameters
    ----------
    source : Path
        An estimate output folder or an FRF file.
    out : Path
        Its output folder.
    progress : callable
        Called with one line per stage (the input's log).
    **options
        The keyword arguments of :func:`fit_frf`.

    Returns
    -------
    dict
        ``fit`` (physical, coupled or rational), the cost ratio and p-value; per axis J of
        a physical fit each parameter ``<key>_J`` (and the coupled fit's
        ``link_coupling_J_K``), its resonance ``resonance_hz_J``; the rational fit's
        ``order``; ``pose_rad_J`` when the FRF was measured at a pose.

    """
    res = fit_frf(source, out, progress=progress, **options)
    cols: dict[str, Any] = {}
    if res.coupled is not None:
        c = res.coupled
        cost = c.cost
        cols['fit'] = 'coupled'
        for i, name in enumerate(c.names):
            cols.update({f'{k}_{name}': float(f'{v:.6g}')
                         for k, v in c.axis_parameters(i).items()})
        coupling = c.link_coupling()[0]
        for i, j in zip(*np.triu_indices(len(c.names), 1)):
            cols[f'link_coupling_{c.names[i]}_{c.names[j]}'] = float(f'{coupling[i, j]:.6g}')
    elif res.physical is not None:
        cost = max((f.cost for f in res.physical), key=lambda c: c.ratio)   # the worst axis
        cols['fit'] = 'physical'
        for f in res.physical:
            cols.update({f'{k}_{f.name}': float(f'{v:.6g}') for k, v in f.parameters().items()})
    else:
        cost = res.rational.best.cost
        cols.update({'fit': 'rational', 'order': res.rational.best.order})
    for f in res.physical or []:
        cols[f'resonance_hz_{f.name}'] = round(f.resonances_hz()[1], 4)
    cols.update({'cost_ratio': round(float(cost.ratio), 3),
                 'p_value': None if not np.isfinite(cost.p_value) else
                 float(f'{cost.p_value:.3g}')})
    pose = source_pose(source)
    names = [f.name for f in res.physical or []]
    if pose is not None and len(pose) == len(names):
        cols.update({f'pose_rad_{n}': q for n, q in zip(names, pose)})
    return cols
