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
The numerical core of frf_ident: pure numpy/scipy/numba, no ROS, bag, YAML or plotting.

The public API is re-exported here, as python-control does (``from frf_ident.core import
FrequencyResponse, design_odd_multisine``); each name is loaded from its module on first use,
so importing one part does not compile the plant kernels. Subpackages, by concept:

- :mod:`frf_ident.core.model` — robot parameters and the model-file schema
- :mod:`frf_ident.core.simulation` — plant, controller, closed-loop runner, analytic FRFs
- :mod:`frf_ident.core.excitation` — multisine and chirp designs, procedures, detection
- :mod:`frf_ident.core.estimation` — spectra, BLA, FRD objects, estimators, refusal checks
- :mod:`frf_ident.core.diagnosis` — what a model lacks, fitted from data
"""
from __future__ import annotations

import importlib
from typing import Any

#: public name -> module that defines it
_API = {
    'frf_ident.core.model.params': ['AxisParams', 'RobotParams'],
    'frf_ident.core.model.schema': ['default_robot', 'robot_from_dict', 'robot_to_dict'],
    'frf_ident.core.simulation.plant': ['FlexibleJointPlant'],
    'frf_ident.core.simulation.controller': ['controller_from_dict', 'PIVelocity'],
    'frf_ident.core.simulation.runner': ['IdentificationConfig', 'run_identification'],
    'frf_ident.core.simulation.analytic': ['closed_loop_frfs', 'robot_frf', 'robot_frf_sampled',
                                           'two_mass_frf'],
    'frf_ident.core.excitation.multisine': ['MultisineDesign', 'MultisineRealisation',
                                            'design_odd_multisine', 'mimo_phase_shifts',
                                            'multisine_realisation'],
    'frf_ident.core.excitation.chirp': ['ChirpDesign', 'chirp_phase_flips', 'exponential_chirp'],
    'frf_ident.core.excitation.chirp_iteration': ['ChirpConfig', 'ChirpIteration'],
    'frf_ident.core.excitation.multisine_procedure': ['MultisineConfig'],
    'frf_ident.core.excitation.multisine_detect': ['detect_multisine'],
    'frf_ident.core.excitation.chirp_detect': ['detect_chirp'],
    'frf_ident.core.excitation.detect': ['detect_excitation'],
    'frf_ident.core.estimation.frd': ['FrequencyResponse'],
    'frf_ident.core.estimation.spectra': ['best_linear_approximation',
                                          'best_linear_approximation_reference',
                                          'periodic_spectra'],
    'frf_ident.core.excitation.chirp_dft': ['chirp_excerpt_dft'],
    'frf_ident.core.estimation.chirp_estimate': ['chirp_frf'],
    'frf_ident.core.estimation.described': ['estimate_recording', 'multisine_frf'],
    'frf_ident.core.estimation.excitation_options': ['ExcitationOptions'],
    'frf_ident.core.recording': ['Recording', 'Segment'],
    'frf_ident.core.diagnosis.pipeline': ['diagnose', 'Diagnosis'],
    'frf_ident.core.diagnosis.experiments.pipeline': ['diagnose_experiments'],
    'frf_ident.core.diagnosis.timeseries.pipeline': ['diagnose_timeseries'],
}
_WHERE = {name: module for module, names in _API.items() for name in names}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    """Load a public name from its module on first access (PEP 562)."""
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """Return the module's names and the lazily loaded public API (for dir() and completion)."""
    return sorted(set(globals()) | set(__all__))
