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
Middleware layer: the same node code on rclpy (ROS 2 Jazzy) or on plain Cyclone DDS.

The backend is rclpy when ``import rclpy`` works, otherwise the Cyclone DDS backend
(:mod:`frf_ident.middleware.dds_backend`), which speaks ROS 2's wire conventions so a ROS 2 graph
with rmw_cyclonedds_cpp sees its topics and calls its services. ``FRF_IDENT_MIDDLEWARE=rclpy|dds``
forces one.

Node code uses only this module: ``create_node``, ``msg`` / ``srv`` type lookups (messages are
built with keyword arguments and ROS field names), the QoS helpers, and rclpy's Node method names
(``create_publisher``, ``create_subscription``, ``create_timer``, ``create_service``,
``create_client``, ``declare_parameter``, ``get_parameter``, ``get_clock``, ``get_logger``,
``destroy_node``). Differences from plain rclpy: ``Client.call`` raises TimeoutError instead of
returning None, and ``None`` / ``[]`` parameter defaults are dynamically typed.
"""

import importlib
import os
import threading
from types import ModuleType
from typing import Any, Optional, Sequence

from frf_ident.middleware.params import (check_params_files, load_params_file, parse_ros_args,
                                         strip_ros_args)
from frf_ident.middleware.qos import (qos_clock, qos_default, qos_sensor_data, qos_transient_local,
                                      QosSpec)

__all__ = [
    'READY', 'QosSpec', 'backend', 'backend_name', 'check_params_files', 'create_node', 'init',
    'load_params_file', 'msg', 'ok', 'parameter_errors', 'parse_ros_args', 'qos_clock',
    'qos_default',
    'qos_sensor_data', 'qos_transient_local', 'shutdown', 'spin', 'spin_once', 'srv',
    'strip_ros_args',
]

ENV_BACKEND = 'FRF_IDENT_MIDDLEWARE'
#: first word of the line a node process prints on stdout once it is wired and spinning
READY = 'FRF_NODE_READY'
_backend: Optional[ModuleType] = None
_lock = threading.Lock()


def _select_backend() -> ModuleType:
    forced = os.environ.get(ENV_BACKEND, '').strip().lower()
    if forced not in ('', 'rclpy', 'dds'):
        raise ValueError(f'{ENV_BACKEND} must be "rclpy" or "dds", got {forced=}')
    if forced == 'dds':
        return importlib.import_module('frf_ident.middleware.dds_backend')
    try:
        importlib.import_module('rclpy')
    except ImportError as exc:
        if forced == 'rclpy':
            raise ImportError(f'{ENV_BACKEND}=rclpy but rclpy cannot be imported: {exc}') from exc
        return importlib.import_module('frf_ident.middleware.dds_backend')
    return importlib.import_module('frf_ident.middleware.rclpy_backend')


def backend() -> ModuleType:
    """
    Return the backend module (chosen once per process).

    Returns
    -------
    module
        :mod:`frf_ident.middleware.rclpy_backend` when rclpy imports, else
        :mod:`frf_ident.middleware.dds_backend`; ``FRF_IDENT_MIDDLEWARE`` forces one.

    Raises
    ------
    ValueError
        ``FRF_IDENT_MIDDLEWARE`` is set to something else than 'rclpy' or 'dds'.
    ImportError
        ``FRF_IDENT_MIDDLEWARE=rclpy`` but rclpy cannot be imported.

    """
    global _backend
    with _lock:
        if _backend is None:
            _backend = _select_backend()
        return _backend


def backend_name() -> str:
    """
    ``'rclpy'`` or ``'dds'``.

    Returns
    -------
    str
        Name of the backend in use (selecting it on first use).

    """
    return backend().BACKEND_NAME


def init(args: Optional[Sequence[str]] = None) -> None:
    """
    Initialise the middleware; ``args`` (default ``sys.argv``) may carry ``--ros-args``.

    Parameters
    ----------
    args : sequence of str, optional
        Command line including the program name; default ``sys.argv``.

    """
    backend().init(args)


def ok() -> bool:
    """
    Return true between :func:`init` (or the first :func:`create_node`) and :func:`shutdown`.

    Returns
    -------
    bool
        Whether the middleware is initialised and not shut down.

    """
    return backend().ok()


def shutdown() -> None:
    """Destroy all nodes and leave the DDS domain (safe to call twice)."""
    backend().shutdown()


def create_node(name: str, *, parameter_overrides: Optional[dict[str, Any]] = None,
                use_sim_time: Optional[bool] = None, namespace: str = '/',
                global_arguments: bool = True) -> Any:
    """
    Create a node on the chosen backend (initialising it with ``sys.argv`` if needed).

    Parameter precedence (lowest first): declared default, ``--params-file`` (``/**`` then the
    node's own section), ``-p name:=value``, ``parameter_overrides``, ``use_sim_time``.
    Use :func:`load_params_file` to pass a ROS parameter YAML as ``parameter_overrides``.

    Parameters
    ----------
    name : str
        Node name.
    parameter_overrides : dict, optional
        Parameter name -> value, overriding defaults and the command line.
    use_sim_time : bool, optional
        Forced value of the ``use_sim_time`` parameter; None (default): from the parameters.
    namespace : str, optional
        Node namespace; default ``'/'``.
    global_arguments : bool, optional
        False: the process's ``--ros-args`` (parameters, ``__node:=`` remaps) do not apply
        to this node (rclpy's ``use_global_arguments``); for a helper node of a process
        whose name a launch file remaps.

    Returns
    -------
    Node
        The backend's node, with rclpy's Node method names.

    """
    return backend().create_node(name, namespace=namespace,
                                 parameter_overrides=parameter_overrides,
                                 use_sim_time=use_sim_time, global_arguments=global_arguments)


def spin(node: Any, stop_event: Optional[threading.Event] = None) -> None:
    """
    Run ``node``'s callbacks in this thread until ``stop_event`` is set or shutdown.

    Parameters
    ----------
    node : Node
        A node from :func:`create_node`.
    stop_event : threading.Event, optional
        Spinning stops once it is set; default None: until shutdown (rclpy) or until the
        node is destroyed (DDS backend).

    """
    backend().spin(node, stop_event)


def spin_once(node: Any, timeout_sec: Optional[float] = None) -> None:
    """
    Wait up to ``timeout_sec`` for work and run the ready callbacks of ``node``.

    Parameters
    ----------
    node : Node
        A node from :func:`create_node`.
    timeout_sec : float, optional
        Longest wait in s; default None: wait until there is work.

    """
    backend().spin_once(node, timeout_sec)


def parameter_errors() -> tuple:
    """
    Exception types a node raises for a parameter of the wrong type or value.

    Returns
    -------
    tuple of type
        The backend's parameter exception classes, for an ``except`` clause.

    """
    return backend().PARAMETER_ERRORS


def msg(type_name: str) -> type:
    """
    Message class for ``pkg/msg/Type`` on the current backend.

    Parameters
    ----------
    type_name : str
        Full message type name, e.g. ``'sensor_msgs/msg/JointState'``.

    Returns
    -------
    type
        The message class; instances are built with keyword arguments (ROS field names).

    Raises
    ------
    KeyError
        The DDS backend does not know the type.

    """
    return _interface('message', type_name)


def srv(type_name: str) -> Any:
    """
    Service type for ``pkg/srv/Type`` (with ``.Request`` and ``.Response``).

    Parameters
    ----------
    type_name : str
        Full service type name, e.g. ``'std_srvs/srv/Trigger'``.

    Returns
    -------
    object
        rclpy's generated service class, or the DDS backend's ``ServiceType``; both have
        ``Request`` and ``Response`` message classes.

    Raises
    ------
    KeyError
        The DDS backend does not know the type.

    """
    return _interface('service', type_name)


def _interface(kind: str, type_name: str) -> Any:
    """Return a message or service type: rclpy's own, or the DDS backend's table of them."""
    b = backend()
    if b.BACKEND_NAME == 'rclpy':
        return (b.msg if kind == 'message' else b.srv)(type_name)
    from frf_ident.middleware import ros_types
    table = ros_types.MESSAGES if kind == 'message' else ros_types.SERVICES
    try:
        return table[type_name]
    except KeyError:
        raise KeyError(f'{kind} type not available on the DDS backend: {type_name=}; '
                       f'known: {sorted(table)}') from None
