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
YAML reading shared by model files and ROS parameter files.

PyYAML implements YAML 1.1, which reads ``1.5e5`` (no dot, or no exponent sign) as a string;
rcl and YAML 1.2 read it as a float, and the model-file contract's own example uses it.
"""
from __future__ import annotations

import re
from typing import Any

import yaml

__all__ = ['Yaml12FloatLoader', 'load_yaml']


class Yaml12FloatLoader(yaml.SafeLoader):
    """
    SafeLoader that resolves floats as YAML 1.2 (and rcl) do.

    Parameters
    ----------
    stream : str, bytes or file-like
        The YAML text to load, as for :class:`yaml.SafeLoader`.

    """


Yaml12FloatLoader.add_implicit_resolver(
    'tag:yaml.org,2002:float',
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                |[-+]?\.(?:inf|Inf|INF)
                |\.(?:nan|NaN|NAN))$""", re.X),
    list('-+0123456789.'))


def load_yaml(text: str) -> Any:
    """
    Parse YAML text with YAML 1.2 float rules.

    Parameters
    ----------
    text : str
        The YAML document.

    Returns
    -------
    object
        The parsed document (mapping, list or scalar).

    Raises
    ------
    yaml.YAMLError
        The text is not valid YAML.

    """
    return yaml.load(text, Loader=Yaml12FloatLoader)
