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
:func:`~frf_ident.io.export.read_frf` reads), keep the band, fit (the physical two-mass model
per axis with ``physical``, else a common-denominator rational model of the given order or the
lowest order the cost test accepts), write fit.json, the figure and the model: model.yaml (the
model file the other commands take) for the physical fit, model.mat (A, B, C, D) for the
rational one; with a model file, check its velocity PI on the measured loop
(:func:`frf_ident.app.loop.run_loop`: loop.json, loop.png); last fit.html, the report page
of it all. ``estimate --fit`` runs :func:`fit_frf` on the FRF it has just written.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, replace
import json
from pathlib import Path
from typing import Any, Callable

from frf_ident.app.frf_source import axis_channels, read_source
from frf_ident.app.loop import LoopOutcome, run_loop
from frf_ident.app.outdir import clear_outputs
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.fit.cost import CostTest
from frf_ident.core.fit.coupled import CoupledFit, fit_coupled
from frf_ident.core.fit.physical import fit_two_mass, PhysicalFit
from frf_ident.core.fit.rational import OrderSelection, select_order
from frf_ident.core.jsonable import jsonable
from frf_ident.core.progress import Progress, sink
from frf_ident.core.simulation.controller import PIVelocity
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.lti import write_lti_mat
from frf_ident.io.model_file import load_model, save_model
from frf_ident.report.fit_figures import fit_figure
from frf_ident.report.html import fit_sections, write_fit_report
import numpy as np

__all__ = ['FitOptions', 'FitOutcome', 'MAX_ORDER', 'OUTPUT_FILES', 'cost_dict', 'fit_columns',
           'fit_frf', 'is_fit_input', 'source_pose']

#: the files :func:`fit_frf` may write into its output directory (loop.*: with a model file)
OUTPUT_FILES = ('fit.json', 'fit.png', 'fit.html', 'model.yaml', 'model.mat', 'loop.json',
                'loop.png')
#: highest order tried when no --order is given: 9 states (3 twists, 6 velocities) describe the
#: 3-axis robot's velocity FRF; 12 leaves room for a second mode per axis
MAX_ORDER = 12


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


def cost_dict(c: CostTest) -> dict[str, Any]:
    """Return the cost test as the JSON mapping of fit.json."""
    def num(x):
        return float(x) if np.isfinite(x) else None
    return {'cost': c.cost, 'dof': c.dof, 'ratio': c.ratio, 'p_value': num(c.p_value),
            'limit': num(c.limit), 'weighted': c.weighted,
            'structure_missing': c.structure_missing}


def _physical_dict(fit: PhysicalFit) -> dict[str, Any]:
    fa, fr = fit.resonances_hz()
    return {'axis': fit.name, 'parameters': fit.parameters(), 'std': fit.standard_errors(),
            'start': dict(zip(fit.names, fit.start.tolist())), 'antiresonance_hz': fa,
            'resonance_hz': fr, 'delay_s': fit.delay_s,
            'delay_std_s': fit.delay_std_s if fit.delay_fitted else None,
            'cost': cost_dict(fit.cost)}


def _rational_dict(sel: OrderSelection) -> dict[str, Any]:
    best = sel.best
    return {'order': best.order, 'n_num': best.num_scaled.shape[-1] - 1,
            'inputs': best.inputs, 'outputs': best.outputs, 'num': best.num, 'den': best.den,
            'modes': [asdict(m) for m in best.modes()], 'cost': cost_dict(best.cost),
            'aic': best.aic, 'selected_by': sel.reason,
            'tried': [{'order': f.order, 'cost': f.cost.cost, 'dof': f.cost.dof, 'aic': f.aic}
                      for f in sel.fits]}


def _coupled_dict(fit: CoupledFit) -> dict[str, Any]:
    c, sd = fit.link_coupling()
    return {'axes': [{'axis': n, 'parameters': fit.axis_parameters(i), 'std': fit.axis_std(i)}
                     for i, n in enumerate(fit.names)],
            'link_coupling': c, 'link_coupling_std': sd, 'delay_s': fit.delay_s,
            'delay_std_s': fit.delay_std_s if np.isfinite(fit.delay_std_s) else None,
            'cost': cost_dict(fit.cost)}


def _fitted_model(values: dict[str, dict[str, float]], coupling: np.ndarray | None,
                  delays: dict[str, float] | None, model: str | Path | None, out: Path) -> Path:
    """
    Write model.yaml: the base model (``model``, else the embedded default) with fitted axes.

    ``values`` maps each fitted axis to its five parameters. Every fitted axis keeps the other
    keys (limits, nonlinear effects) and the PI gains of the base model's axis of the same
    name, else of its first axis; a negative viscous friction estimate is written as 0. The
    link coupling is ``coupling`` (the coupled fit's), else left out. A fitted delay
    (``delays``, per axis) becomes the axis's ``time_delay`` less the half sample the
    zero-order hold of the model's sample rate adds by itself (at least 0).
    """
    _, base, ctrl = load_model(model)
    names = base.joint_names
    pick = [names.index(n) if n in names else 0 for n in values]
    extra = {n: {} if delays is None else {'time_delay': max(delays[n] - base.dt / 2, 0.0)}
             for n in values}
    axes = [replace(base.axes[k], name=n, **dict(v, viscous_friction=max(
        v['viscous_friction'], 0.0)), **extra[n]) for (n, v), k in zip(values.items(), pick)]
    robot = replace(base, axes=axes, link_coupling=coupling)
    pi = PIVelocity(ctrl.kp[pick], ctrl.ki[pick], robot.torque_limits(), robot.dt,
                    sos=ctrl.sos[pick])
    how = 'fitted with the link coupling' if coupling is not None else \
        'fitted per axis (link_coupling not fitted: left out)'
    return save_model(out / 'model.yaml', robot, pi,
                      extra={'description': f'two-mass parameters {how} by frf-ident fit; '
                                            f'other keys from {model or "the default model"}'})


def _physical(frf: FrequencyResponse, var: np.ndarray | None, delay_s: float | None,
              progress: Callable[[str], None]):
    """Fit per axis, and the coupled robot when the FRF is square with >= 2 axes."""
    chans = axis_channels(frf)
    outs, ins = [o for _, o, _ in chans], [i for _, _, i in chans]
    names = [n for n, _, _ in chans]
    if len(chans) >= 2 and len(set(outs)) == len(outs) == frf.noutputs:
        sub = frf.response[np.ix_(outs, ins)]
        coupled = fit_coupled(frf.freq_hz, sub, None if var is None else var[np.ix_(outs, ins)],
                              delay_s=delay_s, names=names)
        for fit in coupled.per_axis:
            for line in fit.summary():
                progress(f'  per axis: {line}')
        for line in coupled.summary():
            progress(f'  {line}')
        values = {n: coupled.axis_parameters(k) for k, n in enumerate(names)}
        return coupled.per_axis, coupled, values, sub, coupled.model
    phys = [fit_two_mass(frf.freq_hz, frf.response[o, i], None if var is None else var[o, i],
                         delay_s=delay_s, name=n) for n, o, i in chans]
    for fit in phys:
        for line in fit.summary():
            progress(f'  {line}')
    measured = np.stack([frf.response[o, i] for _, o, i in chans])[:, None]
    return phys, None, {f.name: f.parameters() for f in phys}, measured, \
        np.stack([f.model for f in phys])[:, None]


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
        Rational model order; None: the lowest of 1..:data:`MAX_ORDER` the cost test accepts
        (else the lowest AIC). Ignored with ``physical``.
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
    var = frf.variance()
    which = frf.variance_kind()
    progress = sink(progress)
    progress(f'fit: {frf.noutputs}x{frf.ninputs} FRF, {frf.freq_hz.size} lines '
             f'{frf.freq_hz.min():.3g}-{frf.freq_hz.max():.3g} Hz, weights: '
             f'{which + " variance" if which else "none (relative error)"}')
    out.mkdir(parents=True, exist_ok=True)
    clear_outputs(out, OUTPUT_FILES)
    files: list[Path] = []
    phys, sel, coupled = None, None, None
    if physical:
        phys, coupled, values, measured, fitted = _physical(frf, var, delay_s, progress)
        delays = None
        if delay_s is None:
            delays = {f.name: (f.delay_s if coupled is None else coupled.delay_s)
                      for f in phys}
        files.append(_fitted_model(values, None if coupled is None else
                                   coupled.link_coupling()[0], delays, model, out))
        chans = axis_channels(frf)
        if coupled is not None:
            v = None if var is None else var[np.ix_([o for _, o, _ in chans],
                                                    [i for _, _, i in chans])]
            names = [f'{a} -> {b}: coupled fit' for b, _, _ in chans for a, _, _ in chans]
            verdicts = [_short(coupled.cost)] * len(names)
        else:
            v = None if var is None else np.stack([var[o, i] for _, o, i in chans])
            names = [f'{n}: two-mass fit' for n, _, _ in chans]
            verdicts = [_short(f.cost) for f in phys]
        measured = measured.reshape(-1, frf.freq_hz.size)
        fitted = fitted.reshape(measured.shape)
        v = None if v is None else v.reshape(measured.shape)
    else:
        if order is not None and order < 1:
            raise FrfIdentInputError(f'--order {order}: expected an order >= 1')
        orders = [order] if order is not None else range(1, MAX_ORDER + 1)
        sel = select_order(frf.freq_hz, frf.response, var, orders,
                           inputs=list(frf.inputs), outputs=list(frf.outputs))
        for line in sel.best.summary():
            progress(f'  {line}')
        if order is None:
            progress(f'  order {sel.best.order} chosen by the {sel.reason} '
                     f'(tried {sel.fits[0].order}-{sel.fits[-1].order})')
        files.append(write_lti_mat(sel.best, out / 'model.mat'))
        measured = frf.response.reshape(-1, frf.freq_hz.size)
        fitted = sel.best.model.reshape(measured.shape)
        v = None if var is None else var.reshape(measured.shape)
        names = [f'{a} -> {b}' for b in frf.outputs for a in frf.inputs]
        verdicts = [_short(sel.best.cost)] * len(names)
    if figure:
        files.append(fit_figure(frf.freq_hz, measured, fitted, v, names, out / 'fit.png',
                                verdicts))
    doc = {'source': str(source), 'pose_rad': source_pose(source),
           'freq_hz': [float(frf.freq_hz.min()), float(frf.freq_hz.max())],
           'n_lines': int(frf.freq_hz.size), 'variance': which,
           'delay_s': None if delay_s is None else float(delay_s),
           'physical': None if phys is None else [_physical_dict(f) for f in phys],
           'coupled': None if coupled is None else _coupled_dict(coupled),
           'rational': None if sel is None else _rational_dict(sel),
           'files': [p.name for p in files] + ['fit.json']}
    (out / 'fit.json').write_text(json.dumps(jsonable(doc), indent=1))
    files.append(out / 'fit.json')
    progress(f'fit: wrote {", ".join(p.name for p in files)} to {out}')
    loop = None
    if model is not None:
        n_pi, n_axes = load_model(model)[2].kp.size, len(axis_channels(frf))
        if n_pi == n_axes:
            loop = run_loop(source, out, model=model, page=False, progress=progress)
        else:
            progress(f'loop: no margins: the controller of {model} has {n_pi} axes, the FRF '
                     f'{n_axes}')
    sections = fit_sections(physical=phys or (), coupled=coupled,
                            rational=None if sel is None else sel.best,
                            check=None if loop is None else loop.check,
                            fit_png='fit.png' if figure else None,
                            loop_png=None if loop is None else 'loop.png')
    page = write_fit_report(out / 'fit.html', title=f'Fit of {source}', sections=sections)
    progress(f'fit: report {page}')
    return FitOutcome(phys, coupled, sel, files + [page], loop)


def _short(cost: CostTest) -> str:
    """Return the cost test's verdict in a few words for a figure title."""
    if not cost.weighted:
        return 'cost test: no FRF variance'
    word = 'structure missing' if cost.structure_missing else 'explained by the noise'
    return f'cost/dof {cost.ratio:.2f}: {word}'


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
