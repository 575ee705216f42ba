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
Simulation: the flexible-joint plant, its controller, the closed-loop runner, analytic FRFs.

- :mod:`frf_ident.core.simulation.plant` — the plant of eqs. 1, 2, 20-22 (its Python API)
- :mod:`frf_ident.core.simulation.linear` — the plant's linear state space, exact discretisation
- :mod:`frf_ident.core.simulation.packed` — the plant's parameters as the kernels' arrays
- :mod:`frf_ident.core.simulation.kernels` — the plant's compiled (numba) sample loop
- :mod:`frf_ident.core.simulation.controller` — velocity PI with torque limit (Fig. 2)
- :mod:`frf_ident.core.simulation.runner` — procedures run in closed loop into a Recording
- :mod:`frf_ident.core.simulation.open_loop` — open-loop experiments of the Section 6 example
- :mod:`frf_ident.core.simulation.analytic` — closed-form FRFs of the linear robot
"""
