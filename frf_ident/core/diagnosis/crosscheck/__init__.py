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
Cross-checks of a diagnosis against things it was not fitted on.

Run after either route (:mod:`frf_ident.core.diagnosis.pipeline`), they hold the diagnosis to
standards outside itself:

- :mod:`.baseline`: the 4-parameter least-squares fit an engineer would make, and the rule
  that an axis losing to it takes its terms.
- :mod:`.generalisation`: position-dependent terms dropped where other records say they do
  not generalise.
- :mod:`.spread`: standard errors against the spread between records or halves of a record.
- :mod:`.kinematic_gravity`: the gravity of the robot's kinematics instead of free
  sinusoids.
- :mod:`.validation`: the nominal and extended model judged on other records.

They may use both routes (a record is diagnosed again on other data) and the shared pieces.
"""
