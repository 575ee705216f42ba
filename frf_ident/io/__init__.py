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
Data exchange with other tools, model files and the package's data files.

Import measured tables (CSV/MAT) as recordings, export frequency responses (python-control,
MATLAB idfrd, CSV, JSON); see docs/import_maps.md.
"""
from .export import from_control, read_frf, to_control, write_frf

__all__ = ['from_control', 'import_table', 'load_map', 'read_frf', 'to_control', 'write_frf']


def __getattr__(name: str):  # the importer pulls in yaml/scipy.io only when used
    """Load ``import_table`` (:mod:`frf_ident.io.importer`) and ``load_map`` on first use."""
    if name == 'import_table':
        from . import importer
        return importer.import_table
    if name == 'load_map':
        from . import import_map
        return import_map.load_map
    raise AttributeError(name)
