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
ROS 2 parameter files and ``--ros-args`` parsing, shared by both backends.

The file format is rcl's (``rcl_yaml_param_parser``): top-level keys are node names (optionally
nested in namespace keys, optionally with ``*`` / ``**`` wildcards; ``/**`` matches every node),
each holding a ``ros__parameters`` map. Nested parameter maps are flattened with dots, as ROS does.
"""

from pathlib import Path
import re
from typing import Any, Iterator, Sequence

from frf_ident.errors import FrfIdentInputError
from frf_ident.io.yamlio import read_yaml_file, Yaml12FloatLoader
import yaml

_PARAMS_KEY = 'ros__parameters'


def _flatten(values: dict, prefix: str = '') -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in values.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            out.update(_flatten(value, f'{name}.'))
        else:
            out[name] = value
    return out


def _node_sections(tree: dict, prefix: str, path: str) -> Iterator[tuple[str, dict]]:
    for key, value in tree.items():
        if not isinstance(value, dict):
            raise FrfIdentInputError(
                f'parameter file {path}: expected a map under {prefix}/{key}, got {value=}')
        fq = f'{prefix}/{str(key).strip("/")}'
        if _PARAMS_KEY in value:
            if not isinstance(value[_PARAMS_KEY], dict):
                raise FrfIdentInputError(
                    f'parameter file {path}: {fq}/{_PARAMS_KEY} must be a map')
            yield fq, value[_PARAMS_KEY]
        else:
            yield from _node_sections(value, fq, path)


def _pattern(fq_key: str) -> re.Pattern:
    parts = re.split(r'(\*\*|\*)', fq_key)
    regex = ''.join('.*' if p == '**' else '[^/]*' if p == '*' else re.escape(p) for p in parts)
    return re.compile(f'^{regex}$')


def load_params_file(path: 'str | Path', node_name: 'str | None',
                     namespace: str = '/') -> dict[str, Any]:
    """
    Return the parameters a ROS parameter file assigns to node ``namespace/node_name``.

    Wildcard sections (``/**``, ``/*``, ...) apply first, exact node sections override them.
    With ``node_name=None`` only the all-nodes section ``/**`` applies.
    """
    path = str(path)
    # missing, unreadable, not UTF-8, not YAML: one line naming the file
    tree = read_yaml_file(path, 'parameter file')
    if tree is None:
        return {}
    if not isinstance(tree, dict):
        raise FrfIdentInputError(f'parameter file {path=} must hold a map of node names')
    ns = '/' + namespace.strip('/')
    fq_name = f'{ns.rstrip("/")}/{node_name}'
    wildcard: dict[str, Any] = {}
    exact: dict[str, Any] = {}
    for key, values in _node_sections(tree, '', path):
        if node_name is None:
            if key == '/**':
                wildcard.update(_flatten(values))
        elif '*' in key:
            if _pattern(key).match(fq_name):
                wildcard.update(_flatten(values))
        elif key == fq_name:
            exact.update(_flatten(values))
    return {**wildcard, **exact}


def _parse_value(text: str) -> Any:
    """Parse a ``-p name:=value`` value the way rcl does: as a YAML scalar or flow sequence."""
    try:
        return yaml.load(text, Loader=Yaml12FloatLoader) if text != '' else ''
    except yaml.YAMLError as exc:
        raise FrfIdentInputError(f'cannot parse parameter value {text=}: {exc}') from exc


def _split_ros_args(argv: Sequence[str]) -> tuple[list[str], list[str]]:
    """(arguments inside ``--ros-args`` sections, the rest); a section ends at ``--``."""
    ros: list[str] = []
    rest: list[str] = []
    inside = False
    for arg in argv:
        if arg == '--ros-args':
            inside = True
        elif arg == '--' and inside:
            inside = False
        else:
            (ros if inside else rest).append(arg)
    return ros, rest


def ros_args_sections(argv: Sequence[str]) -> list[str]:
    """Return the arguments in ``--ros-args`` sections (each ends at ``--`` or at argv's end)."""
    return _split_ros_args(argv)[0]


def strip_ros_args(argv: Sequence[str]) -> list[str]:
    """``argv`` without its ``--ros-args`` sections (as ``rclpy.utilities.remove_ros_args``)."""
    return _split_ros_args(argv)[1]


# ROS arguments that take one value and do not concern parameters.
_IGNORED_WITH_VALUE = {'-r', '--remap', '--log-level', '-e', '--enclave', '--log-config-file'}
_IGNORED_FLAGS = {'--enable-rosout-logs', '--disable-rosout-logs', '--enable-stdout-logs',
                  '--disable-stdout-logs', '--enable-external-lib-logs',
                  '--disable-external-lib-logs'}


def check_params_files(argv: Sequence[str], node_name: 'str | None' = None) -> None:
    """
    Read every ``--params-file`` of ``argv`` (other ROS arguments are not looked at).

    rcl's own parser fails on an unreadable or non-UTF-8 file with a traceback; this one
    names the file in one line.

    Parameters
    ----------
    argv : sequence of str
        The command line.
    node_name : str, optional
        The node whose sections are read.

    Raises
    ------
    FrfIdentInputError
        A file is missing, not UTF-8, not YAML or not a map of node names.

    """
    args = ros_args_sections(argv)
    for arg, value in zip(args, args[1:]):
        if arg == '--params-file':
            load_params_file(value, node_name)


def parse_ros_args(argv: Sequence[str], node_name: 'str | None' = None,
                   namespace: str = '/') -> tuple[dict[str, Any], dict[str, Any]]:
    """
    Parse ``--ros-args --params-file FILE -p name:=value`` as ``ros2 run`` passes them.

    Returns ``(params_file_values, overrides)``: the values every ``--params-file`` assigns to
    ``node_name`` (later files win; with ``node_name=None`` only the ``/**`` wildcard sections
    apply) and the ``-p`` assignments (later ones win). Overrides take precedence over file values.
    Remapping and logging arguments are accepted and ignored.
    """
    args = ros_args_sections(argv)
    file_values: dict[str, Any] = {}
    overrides: dict[str, Any] = {}
    it = iter(args)
    for arg in it:
        if arg in ('--params-file', '-p', '--param') or arg in _IGNORED_WITH_VALUE:
            value = next(it, None)
            if value is None:
                raise FrfIdentInputError(f'ROS argument {arg!r} needs a value')
            if arg == '--params-file':
                file_values.update(load_params_file(value, node_name, namespace))
            elif arg in ('-p', '--param'):
                name, sep, text = value.partition(':=')
                if not sep or not name:
                    raise FrfIdentInputError(
                        f'ROS parameter argument must look like name:=value, got {value=}')
                node, colon, pname = name.rpartition(':')
                if colon and node_name is not None and node != node_name:
                    continue
                overrides[pname if colon else name] = _parse_value(text)
        elif arg in _IGNORED_FLAGS:
            continue
        else:
            raise FrfIdentInputError(f'unknown ROS argument {arg=} in {list(argv)=}')
    return file_values, overrides
