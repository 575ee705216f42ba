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
A tuned velocity loop as parameter files ros2_control reads.

- :func:`pid_controller_params`: ros2_controllers' ``pid_controller`` (Jazzy), one DOF per
  joint, velocity reference and state, effort command. Parameter names as its parameter
  definition (``pid_controller/src/pid_controller.yaml`` of ros-controls/ros2_controllers,
  branch jazzy) and user doc (control.ros.org, "PID Controller") give them: ``dof_names``,
  ``command_interface``, ``reference_and_state_interfaces``, ``gains.<dof>.{p, i, d,
  u_clamp_max, u_clamp_min, antiwindup_strategy}``. Its PID is u = p e + i int e + d de/dt,
  this project's continuous PI; the output clamp is the torque limit and
  ``conditional_integration`` (no integration while the output is clamped) the nearest of
  its anti-windup strategies to the back-calculation the simulation runs.
- :func:`filter_chain_params`: the filters as ros2_controllers' ``chained_filter_controller``
  parameters: one chain per input interface ``<joint>/velocity``, each section a
  ``filters/TransferFunctionFilterDouble`` of the ROS ``filters`` package with ``b`` (input)
  and ``a`` (output, a[0] = 1) coefficients in powers of z^-1: exactly the section's
  [b0, b1, b2] and [1, a1, a2]. A joint without filters gets a pass-through section (b = a =
  [1]), so every input has its chain. The filtered velocity is exported as
  ``<joint>/filtered_velocity``; the PID must read that state for the filters to be in the
  loop (the PI then acts on r - F y, as in frf_ident's simulation).

Both return plain mappings of the ``<node>: {ros__parameters: ...}`` layout ``ros2 run ...
--params-file`` takes; :func:`write_params` writes them as YAML.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Sequence

from frf_ident.core.loop.shaping import AxisSetting
import numpy as np
import yaml

__all__ = ['FILTER_NODE', 'FILTER_TYPE', 'PID_NODE', 'filter_chain_params',
           'pid_controller_params', 'write_params']

#: controller (node) name of the PID parameters
PID_NODE = 'velocity_pid_controller'
#: controller (node) name of the filter chain parameters
FILTER_NODE = 'velocity_filter'
#: the ROS filters package's plugin for one transfer function on one double
FILTER_TYPE = 'filters/TransferFunctionFilterDouble'


def pid_controller_params(settings: Sequence[AxisSetting], torque_limits: Sequence[float] | None,
                          node: str = PID_NODE) -> dict[str, Any]:
    """
    Return ros2_controllers pid_controller parameters for the tuned PI of every joint.

    Parameters
    ----------
    settings : sequence of AxisSetting
        One per joint (its ``axis`` is the DOF name).
    torque_limits : sequence of float, optional
        Output clamp [N m] per joint (none: unclamped, the controller's default).
    node : str, optional
        The controller's name.

    Returns
    -------
    dict
        ``{node: {'ros__parameters': {...}}}``.

    """
    gains = {}
    for k, s in enumerate(settings):
        g: dict[str, Any] = {'p': float(s.kp), 'i': float(s.ki), 'd': 0.0}
        if torque_limits is not None:
            lim = float(torque_limits[k])
            g.update({'u_clamp_max': lim, 'u_clamp_min': -lim,
                      'antiwindup_strategy': 'conditional_integration'})
        gains[s.axis] = g
    return {node: {'ros__parameters': {
        'dof_names': [s.axis for s in settings],
        'command_interface': 'effort',
        'reference_and_state_interfaces': ['velocity'],
        'gains': gains}}}


def filter_chain_params(settings: Sequence[AxisSetting], node: str = FILTER_NODE
                        ) -> dict[str, Any]:
    """
    Return chained_filter_controller parameters running every joint's sections.

    Parameters
    ----------
    settings : sequence of AxisSetting
        One per joint.
    node : str, optional
        The controller's name.

    Returns
    -------
    dict
        ``{node: {'ros__parameters': {...}}}`` (module doc).

    """
    params: dict[str, Any] = {
        'input_interfaces': [f'{s.axis}/velocity' for s in settings],
        'output_interfaces': [f'{s.axis}/filtered_velocity' for s in settings]}
    for s in settings:
        chain = {}
        sos = s.sos()
        for k, row in enumerate(sos):
            b = s.filters[k]
            name = f'{s.axis}_{b.kind}_{b.frequency_hz:.4g}hz'.replace('.', 'p')
            chain[f'filter{k + 1}'] = {'name': name, 'type': FILTER_TYPE,
                                       'params': {'b': [float(x) for x in row[:3]],
                                                  'a': [float(x) for x in row[3:]]}}
        if not len(sos):
            chain['filter1'] = {'name': f'{s.axis}_pass', 'type': FILTER_TYPE,
                                'params': {'b': [1.0], 'a': [1.0]}}
        params[f'{s.axis}/velocity'] = {'filter_chain': chain}
    return {node: {'ros__parameters': params}}


def write_params(params: dict[str, Any], path: str | os.PathLike[str], comment: str = ''
                 ) -> Path:
    """
    Write a ``--params-file`` YAML (a comment block first).

    Parameters
    ----------
    params : dict
        The mapping (:func:`pid_controller_params`, :func:`filter_chain_params`).
    path : str or path-like
        File to write.
    comment : str, optional
        Lines written as ``#`` comments on top.

    Returns
    -------
    Path
        ``path``.

    """
    head = ''.join(f'# {line}\n' for line in comment.splitlines())
    p = Path(path)
    p.write_text(head + yaml.safe_dump(_plain(params), sort_keys=False,
                                       default_flow_style=None))
    return p


def _plain(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_plain(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    return x
