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
The experiments route: diagnose a record of identification experiments by simulation.

A record with multisine and chirp segments and their velocity reference is diagnosed by
simulating candidate models through the recorded controller and estimating them exactly like
the measurement. Floor plan, top to bottom:

- :mod:`.pipeline`: :func:`diagnose_experiments`, the stages in order (0: frequency-domain fit,
  1: torque-residual effects, 2: FRF-shape effects, second pass, joint refits, late ripples).
- :mod:`.held_out`, :mod:`.unexplained`: the closing stages (held-out duels, missing
  structure, the integrator check, the result).
- :mod:`.acceptance`, :mod:`.refit`: taking a candidate by the share of its axis' misfit it
  removes; refitting effects by simulation, alone or jointly.
- :mod:`.candidates`, :mod:`.frequency_fit`: each effect fitted from the evidence it leaves.
- :mod:`.search`, :mod:`.evaluator`: the state of one search; simulations, estimates, misfits
  and noise floors of candidate models.
- :mod:`.parallel`, :mod:`.simplex`, :mod:`.brent`: worker processes and the searches that
  hand them independent points.

It uses the shared pieces one floor up (thresholds, result, common, residual, regressors) and
never the time-series route.
"""
from .pipeline import diagnose_experiments  # noqa: F401
