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
A tuned controller and its uncertainty weight as python-control objects.

- :func:`controller_tf`: C(z) = (kp + ki dt z / (z - 1)) prod_s F_s(z), discrete with
  ``dt``, the controller the simulation runs (input: velocity error, output: torque);
- :func:`filters_tf`: the filters alone, discrete; :func:`filters_tf_continuous` the
  continuous biquads they were discretised from;
- :func:`weight_tf`: W(s), continuous.

:func:`write_control_objects` pickles them per axis (``control_objects.pkl``: a dict
``{'controller', 'filters', 'filters_continuous', 'weight'}`` of ``{axis: TransferFunction}``;
unpickle only files you wrote: pickle runs code).
"""
from __future__ import annotations

import os
from pathlib import Path
import pickle
from typing import Any, Sequence

from frf_ident.core.loop.shaping import AxisSetting
from frf_ident.core.loop.uncertainty import UncertaintyWeight
import numpy as np

__all__ = ['controller_tf', 'filters_tf', 'filters_tf_continuous', 'weight_tf',
           'write_control_objects']


def filters_tf(setting: AxisSetting, dt: float):
    """Return the filters of one axis as a discrete python-control TransferFunction."""
    import control
    num, den = np.array([1.0]), np.array([1.0])
    for row in setting.sos():
        num, den = np.polymul(num, row[:3]), np.polymul(den, row[3:])
    return control.tf(num, den, dt, inputs='y', outputs='y_f', name=f'{setting.axis}_filters')


def filters_tf_continuous(setting: AxisSetting):
    """Return the continuous biquads of one axis as a python-control TransferFunction."""
    import control
    num, den = np.array([1.0]), np.array([1.0])
    for b in setting.filters:
        num, den = np.polymul(num, b.num_s), np.polymul(den, b.den_s)
    return control.tf(np.trim_zeros(num, 'f') if num.any() else num, den,
                      inputs='y', outputs='y_f', name=f'{setting.axis}_filters_s')


def controller_tf(setting: AxisSetting, dt: float):
    """Return C(z) = PI(z) F(z) of one axis (velocity error -> torque)."""
    import control
    pi = control.tf([setting.kp + setting.ki * dt, -setting.kp], [1.0, -1.0], dt)
    c = pi * filters_tf(setting, dt)
    return control.tf(c.num[0][0], c.den[0][0], dt, inputs='e', outputs='u',
                      name=f'{setting.axis}_controller')


def weight_tf(weight: UncertaintyWeight, axis: str = ''):
    """Return W(s) as a continuous python-control TransferFunction."""
    import control
    num, den = weight.num_den()
    return control.tf(num, den, name=f'{axis}_weight' if axis else None)


def write_control_objects(settings: Sequence[AxisSetting], weights: Sequence[UncertaintyWeight],
                          dt: float, path: str | os.PathLike[str]) -> Path:
    """
    Pickle the controller, filters and weight of every axis (module doc).

    Parameters
    ----------
    settings : sequence of AxisSetting
        One per axis.
    weights : sequence of UncertaintyWeight
        One per axis.
    dt : float
        Controller sample time [s].
    path : str or path-like
        File to write.

    Returns
    -------
    Path
        ``path``.

    """
    objs: dict[str, Any] = {
        'controller': {s.axis: controller_tf(s, dt) for s in settings},
        'filters': {s.axis: filters_tf(s, dt) for s in settings},
        'filters_continuous': {s.axis: filters_tf_continuous(s) for s in settings},
        'weight': {s.axis: weight_tf(w, s.axis) for s, w in zip(settings, weights)}}
    p = Path(path)
    with open(p, 'wb') as fh:
        pickle.dump(objs, fh)
    return p
