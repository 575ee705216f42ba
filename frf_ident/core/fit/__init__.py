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
Parametric models fitted to a measured FRF, with their uncertainty.

- :mod:`frf_ident.core.fit.cost` — the ML cost of a fit against its chi-square expectation
- :mod:`frf_ident.core.fit.levy` — linear least-squares start: Levy / Sanathanan-Koerner
- :mod:`frf_ident.core.fit.physical` — the two-mass flexible joint per axis (eqs. 20-22)
- :mod:`frf_ident.core.fit.coupled` — all axes and the link coupling from the MIMO FRF
- :mod:`frf_ident.core.fit.rational` — a continuous-time rational model of chosen order
- :mod:`frf_ident.core.fit.stable` — its ML refit over stable denominators only
- :mod:`frf_ident.core.fit.modes` — the modes of a fitted denominator with their errors
- :mod:`frf_ident.core.fit.model_error` — the bias bound where the cost test fails
- :mod:`frf_ident.core.fit.delay` — the input delay's start and its model-file convention
"""
