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
"""The examples in the core's docstrings run as written."""
import doctest
import importlib
import pkgutil

import frf_ident.core
import pytest


def core_modules():
    """Return the names of every module of frf_ident.core."""
    return sorted(m.name for m in pkgutil.walk_packages(frf_ident.core.__path__,
                                                        'frf_ident.core.'))


@pytest.mark.parametrize('name', [n for n in core_modules()
                                  if '>>>' in (importlib.util.find_spec(n).loader
                                               .get_source(n) or '')])
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name))
    assert result.attempted > 0 and result.failed == 0
