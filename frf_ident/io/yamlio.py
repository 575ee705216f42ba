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

:func:`read_yaml_file` reads a whole file (map files, model files): it refuses text that is
not UTF-8 and YAML syntax errors with one line naming the file, in the caller's error class.
"""
from __future__ import annotations

import os
from pathlib import Path
import re
from typing import Any

from frf_ident.errors import FrfIdentInputError
import yaml

__all__ = ['Yaml12FloatLoader', 'load_yaml', 'read_utf8', 'read_yaml_file']


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


def read_utf8(path: str | os.PathLike[str], what: str = 'file',
              error: type[FrfIdentInputError] = FrfIdentInputError) -> str:
    """
    Read a UTF-8 text file (a leading byte-order mark is dropped).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str, optional
        What the file is, for error messages (``'map file'``, ``'model file'``).
    error : type, optional
        The :class:`~frf_ident.errors.FrfIdentInputError` subclass to raise.

    Returns
    -------
    str
        The text.

    Raises
    ------
    FrfIdentInputError
        (``error``) The file is missing, unreadable or not UTF-8 text; one line naming the
        file (and the offending byte and its offset).

    """
    p = Path(path)
    try:
        data = p.read_bytes()
    except FileNotFoundError as err:
        raise error(f'{p}: {what} not found') from err
    except OSError as err:
        raise error(f'{p}: cannot read {what} ({err.strerror or err})') from err
    try:
        return data.decode('utf-8-sig')
    except UnicodeDecodeError as err:
        bad = data[err.start] if err.start < len(data) else 0
        raise error(f'{p}: not UTF-8 text (byte 0x{bad:02x} at offset {err.start}); save the '
                    f'{what} as UTF-8') from err


def read_yaml_file(path: str | os.PathLike[str], what: str = 'YAML file',
                   error: type[FrfIdentInputError] = FrfIdentInputError) -> Any:
    """
    Read and parse a UTF-8 YAML file with YAML 1.2 float rules (:func:`load_yaml`).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str, optional
        What the file is, for error messages (``'map file'``, ``'model file'``).
    error : type, optional
        The :class:`~frf_ident.errors.FrfIdentInputError` subclass to raise.

    Returns
    -------
    object
        The parsed document.

    Raises
    ------
    FrfIdentInputError
        (``error``) The file is missing, unreadable, not UTF-8 text or not valid YAML; one
        line naming the file (and the line of a syntax error).

    """
    text = read_utf8(path, what, error)
    try:
        return load_yaml(text)
    except yaml.reader.ReaderError as err:   # e.g. control characters (binary data)
        raise error(f'{path}: not valid YAML: character #x{err.character:04x} at offset '
                    f'{err.position} is not allowed in YAML text') from err
    except yaml.YAMLError as err:
        mark = getattr(err, 'problem_mark', None)
        at = f' at line {mark.line + 1}' if mark is not None else ''
        problem = getattr(err, 'problem', None) or str(err).splitlines()[0]
        raise error(f'{path}: not valid YAML{at} ({problem})') from err
