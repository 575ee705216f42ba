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
Application functions used by both the CLI and the nodes: one module per job.

- :mod:`frf_ident.app.identify` — run the experiments in closed loop, record a bag (or one
  per pose, the model linearised at each from the robot's URDF)
- :mod:`frf_ident.app.campaign` — one application function mapped over many inputs (serial,
  worker processes or Dask), one summary table
  (its parts: :mod:`~frf_ident.app.campaign_inputs`, :mod:`~frf_ident.app.campaign_executors`,
  :mod:`~frf_ident.app.campaign_summary`)
- :mod:`frf_ident.app.frf_map` — resonance and antiresonance per axis against the pose
- :mod:`frf_ident.app.estimate` — estimate FRFs from a bag (in memory, or streamed by
  :mod:`frf_ident.app.stream_estimate` when it would not fit)
- :mod:`frf_ident.app.import_data` — measured CSV/MAT tables to bags
- :mod:`frf_ident.app.diagnose` — what the nominal model lacks, the extended model
- :mod:`frf_ident.app.reproduce` — the paper's Section 6 example
- :mod:`frf_ident.app.demo` and :mod:`frf_ident.app.graph` — the node graph driven end to end
- :mod:`frf_ident.app.console` — progress output
- :mod:`frf_ident.app.outdir` — every command's ``--out``: checked before any work, a
  command's own earlier outputs replaced only with ``--overwrite``
"""
