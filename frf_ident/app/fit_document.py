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
The fit.json mapping of `frf-ident fit`: one function per fit kind (docs/CONTRACT.md §8).

Every fitted value carries ``std`` (Cramer-Rao), ``model_error`` (the bound of the bias a
missing structure can leave, :mod:`frf_ident.core.fit.model_error`; zeros where the cost test
passes) and ``std_reported`` (both combined: what the console, fit.html and the figures
show), and the cost test's one-line ``verdict``.
"""
from __future__ import annotations

from dataclasses import asdict
from typing import Any

from frf_ident.core.fit.cost import CostTest
from frf_ident.core.fit.coupled import CoupledFit
from frf_ident.core.fit.physical import PhysicalFit
from frf_ident.core.fit.rational import OrderSelection
import numpy as np

__all__ = ['cost_dict', 'coupled_dict', 'physical_dict', 'rational_dict']


def _num(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None


def cost_dict(c: CostTest) -> dict[str, Any]:
    """Return the cost test as the JSON mapping of fit.json."""
    return {'cost': c.cost, 'dof': c.dof, 'ratio': c.ratio, 'p_value': _num(c.p_value),
            'limit': _num(c.limit), 'weighted': c.weighted,
            'structure_missing': c.structure_missing, 'verdict': c.verdict}


def _delay(delay_s: float, std_s: float, reported_s: float, hold_s: float) -> dict[str, Any]:
    fitted = bool(np.isfinite(std_s))
    return {'delay_s': delay_s, 'delay_std_s': std_s if fitted else None,
            'delay_std_reported_s': reported_s if fitted else None, 'hold_s': hold_s,
            'time_delay_s': max(delay_s - hold_s, 0.0)}


def physical_dict(fit: PhysicalFit, hold_s: float) -> dict[str, Any]:
    """
    Return one axis's two-mass fit as its fit.json entry.

    Parameters
    ----------
    fit : PhysicalFit
        The fit.
    hold_s : float
        The zero-order hold's half sample of the model file [s]: ``time_delay_s`` is the
        delay less it, as model.yaml writes it.

    Returns
    -------
    dict
        axis, parameters, std, model_error, std_reported, start, antiresonance_hz,
        resonance_hz, delay_s, delay_std_s, delay_std_reported_s, hold_s, time_delay_s, cost.

    """
    fa, fr = fit.resonances_hz()
    return {'axis': fit.name, 'parameters': fit.parameters(), 'std': fit.standard_errors(),
            'model_error': dict(zip(fit.names, fit.model_error.tolist())),
            'std_reported': dict(zip(fit.names, fit.reported_std.tolist())),
            'start': dict(zip(fit.names, fit.start.tolist())), 'antiresonance_hz': fa,
            'resonance_hz': fr,
            **_delay(fit.delay_s, fit.delay_std_s, fit.delay_reported_std_s, hold_s),
            'cost': cost_dict(fit.cost)}


def coupled_dict(fit: CoupledFit, hold_s: float) -> dict[str, Any]:
    """
    Return the coupled fit as its fit.json entry.

    Parameters
    ----------
    fit : CoupledFit
        The fit.
    hold_s : float
        The zero-order hold's half sample [s] (see :func:`physical_dict`).

    Returns
    -------
    dict
        axes [{axis, parameters, std, std_reported}], link_coupling, link_coupling_std,
        link_coupling_std_reported, the delay keys, cost, disagreements (lines).

    """
    c, sd = fit.link_coupling()
    _, rsd = fit.link_coupling(reported=True)
    return {'axes': [{'axis': n, 'parameters': fit.axis_parameters(i), 'std': fit.axis_std(i),
                      'std_reported': fit.axis_std(i, reported=True)}
                     for i, n in enumerate(fit.names)],
            'link_coupling': c, 'link_coupling_std': sd, 'link_coupling_std_reported': rsd,
            **_delay(fit.delay_s, fit.delay_std_s, fit.delay_reported_std_s, hold_s),
            'cost': cost_dict(fit.cost), 'disagreements': fit.disagreements()}


def rational_dict(sel: OrderSelection) -> dict[str, Any]:
    """
    Return the chosen rational fit and the orders tried as the fit.json entry.

    Parameters
    ----------
    sel : OrderSelection
        The fits tried and the chosen one.

    Returns
    -------
    dict
        order, n_num, inputs, outputs, num, den, modes (with in_band and the model-error
        bounds), reflected (poles the free fit had in the right half-plane), cost, aic,
        selected_by, runner_up (its order or null), tried [{order, cost, dof, aic,
        admissible, reflected}].

    """
    best = sel.best
    return {'order': best.order, 'n_num': best.num_scaled.shape[-1] - 1,
            'inputs': best.inputs, 'outputs': best.outputs, 'num': best.num, 'den': best.den,
            'modes': [asdict(m) for m in best.modes()], 'reflected': best.reflected,
            'cost': cost_dict(best.cost), 'aic': best.aic, 'selected_by': sel.reason,
            'runner_up': None if sel.runner_up is None else sel.fits[sel.runner_up].order,
            'tried': [{'order': f.order, 'cost': f.cost.cost, 'dof': f.cost.dof, 'aic': f.aic,
                       'admissible': f.admissible, 'reflected': f.reflected}
                      for f in sel.fits]}
