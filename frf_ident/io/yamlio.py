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
    """SafeLoader that resolves floats as YAML 1.2 (and rcl) do."""


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
