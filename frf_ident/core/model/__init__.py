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
Robot model: typed parameters and the model-file schema (no file I/O).

- :mod:`frf_ident.core.model.params` — ``AxisParams`` per joint and ``RobotParams`` of the
  arm (eqs. 1, 2, 20-22)
- :mod:`frf_ident.core.model.fields` — checks of boolean and integer fields, shared with the
  import map
- :mod:`frf_ident.core.model.schema` — model-file mappings (docs/CONTRACT.md §5) to and from
  those classes, with one-line errors naming the field; YAML parsing is in
  :mod:`frf_ident.io.model_file`
"""
