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
Estimation: FRFs from recorded data and the checks that the data support them.

- :mod:`frf_ident.core.estimation.frd` — ``FrequencyResponse``, the result object
- :mod:`frf_ident.core.estimation.spectra` — eq. 7, the BLA of eq. 14, Sec. 5.1 chirp spectra
- :mod:`frf_ident.core.estimation.described` — estimates from a Recording with experiment
  descriptors, from :mod:`~frf_ident.core.estimation.multisine_estimate` (the BLA, its
  :mod:`~frf_ident.core.estimation.compensation`) and
  :mod:`~frf_ident.core.estimation.chirp_estimate`; their
  :mod:`~frf_ident.core.estimation.channels` and :mod:`~frf_ident.core.estimation.segment_counts`
- :mod:`frf_ident.core.estimation.detected` — estimates from data without descriptors, block
  by block: :mod:`~frf_ident.core.estimation.excitation_options` (what is given),
  :mod:`~frf_ident.core.estimation.detected_segments` (detection and its checks),
  :mod:`~frf_ident.core.estimation.detected_spectra` (periods, gaps filled; chirp lines),
  :mod:`~frf_ident.core.estimation.detected_estimator` (the column estimates)
- :mod:`frf_ident.core.estimation.checks` — refusals: clipping, band, periods, coverage
- :mod:`frf_ident.core.estimation.lpm`, :mod:`~frf_ident.core.estimation.lpm_frames` — the
  Local Polynomial Method (lines; frames of time records)
- :mod:`frf_ident.core.estimation.missing_periodic`,
  :mod:`~frf_ident.core.estimation.missing_lpm` — samples a gap took, estimated with the FRF
  (periodic records; the LPM), accounted for in :mod:`~frf_ident.core.estimation.missing`
"""
