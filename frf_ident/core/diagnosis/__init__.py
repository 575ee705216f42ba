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

Diagnosis: what the nominal simulation gets wrong, which effect causes it, and the extended
model (docs/CONTRACT.md §7). Pure numpy/scipy; no middleware imports.
"""
from .common import apply_effect, Effect, EFFECTS, frf_error_db, nrmse, simulate_like  # noqa: F401
from .experiments.evaluator import Evaluator  # noqa: F401
from .experiments.pipeline import diagnose_experiments  # noqa: F401
from .result import DiagnosisResult, ExperimentsDetail, TimeseriesDetail  # noqa: F401
from .timeseries.pipeline import diagnose_timeseries  # noqa: F401
