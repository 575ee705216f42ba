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
The loop a velocity controller closes on a measured FRF: responses, draws and a PI proposal.

- :mod:`frf_ident.core.loop.check` — C(jw), L = C P-hat, the sensitivity peak, draws of the
  FRF from its variance and the typed margin results
- :mod:`frf_ident.core.loop.design` — PI gains for a target phase margin and bandwidth

The margins themselves are python-control's ``stability_margins`` on the FRD data, computed
in :mod:`frf_ident.app.loop` (python-control stays outside the core).
"""
