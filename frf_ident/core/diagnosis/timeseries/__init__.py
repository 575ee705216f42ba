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
The time-series route: diagnose any record with joint states by inverse dynamics.

Records without identification experiments (normal motion, trajectories, imported tables)
are diagnosed from the inverse-dynamics residual of the nominal model, regressed on the
candidate effects' regressors in an analysis band. Floor plan, top to bottom:

- :mod:`.pipeline`: :func:`diagnose_timeseries`, the stages in order (prepare, groups per
  axis, selection, effects, held-out metrics, unexplained).
- :mod:`.effects`: regressor groups of an axis, their selection and the effects written from
  the chosen ones.
- :mod:`.extrapolation`: leave-range-out checks of position-dependent terms, and whether
  another record leaves the fitted range.
- :mod:`.diagnosable`: whether a record can be diagnosed at all (enough moving blocks).
- :mod:`.resonance`: peaks of the residual above the analysis band.

It uses the shared pieces one floor up (thresholds, result, common, residual, regressors,
selection, band, prediction) and never the experiments route.
"""
from .pipeline import diagnose_timeseries  # noqa: F401
