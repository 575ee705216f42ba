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
Excitation: signal designs, experiment procedures and detection in measured data.

- :mod:`frf_ident.core.excitation.multisine` — odd random-phase multisines (Sec. 4, eqs. 8-12)
- :mod:`frf_ident.core.excitation.chirp` — exponential chirps (Sec. 5, eqs. 15, 16, 26)
- :mod:`frf_ident.core.excitation.procedures` — a procedure as phases (:class:`Phase`) and
  the move phases' plan; :mod:`~frf_ident.core.excitation.plan_checks` refuses settings and
  plans beyond the limits
- :mod:`frf_ident.core.excitation.multisine_procedure` — the Section 7 multisine procedure
- :mod:`frf_ident.core.excitation.chirp_iteration` — the chirp iteration of Sec. 5.3
  (eqs. 17-19)
- :mod:`frf_ident.core.excitation.detect` — recover a multisine or chirp from a signal
  (:mod:`~frf_ident.core.excitation.multisine_detect`,
  :mod:`~frf_ident.core.excitation.chirp_detect`, with
  :mod:`~frf_ident.core.excitation.periodic_block`,
  :mod:`~frf_ident.core.excitation.detect_input` and
  :mod:`~frf_ident.core.excitation.detection_results`)
"""
