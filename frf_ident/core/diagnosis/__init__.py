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
Diagnose where the nominal model fails and build the extended model.

What the nominal simulation gets wrong, which effect causes it, and the extended model
(docs/CONTRACT.md §7). Pure numpy/scipy; no middleware imports. Floor plan, top to bottom:

- :mod:`.pipeline`: :func:`diagnose`, the route the record calls for, then the cross-checks;
  :class:`Diagnosis`, what it returns (report.json from :meth:`Diagnosis.report`).
- :mod:`.crosscheck`: checks against what the route did not fit on (the least-squares
  baseline, other records, the spread of standard errors, the kinematics' gravity).
- :mod:`.experiments` and :mod:`.timeseries`: the two routes, independent of each other.
  Identification experiments (multisine and chirp segments with their reference) are
  diagnosed by closed-loop simulation and FRF estimates; any other record by the
  inverse-dynamics residual.
- Shared by both: :mod:`.result` and :mod:`.records` (the typed result and report entries),
  :mod:`.common` (effects, simulation of a model like a record, the §7 metrics),
  :mod:`.residual`, :mod:`.regressors`, :mod:`.selection`, :mod:`.band`, :mod:`.prediction`
  and :mod:`.thresholds` (every threshold, with its meaning and calibration).

The floors are an import contract (.importlinter): a floor imports only those below it.
"""
from .common import Effect, EFFECTS, has_experiments  # noqa: F401
from .crosscheck.kinematic_gravity import GravityBasis  # noqa: F401
from .pipeline import diagnose, Diagnosis  # noqa: F401
from .result import DiagnosisResult  # noqa: F401
