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
The exports of ``tune`` read back in the structure their consumers document.

pid_controller (ros2_controllers, Jazzy): parameter names and rules from its parameter
definition ros-controls/ros2_controllers, branch jazzy, ``pid_controller/src/
pid_controller.yaml``, shown as "List of parameters" in its user doc
https://control.ros.org/jazzy/doc/ros2_controllers/pid_controller/doc/userdoc.html:
``dof_names`` (string_array, unique, not empty), ``command_interface`` (string, not empty),
``reference_and_state_interfaces`` (string_array, 1 or 2 entries), ``gains.<dof>.{p, i, d,
u_clamp_max, u_clamp_min, antiwindup_strategy (back_calculation | conditional_integration |
legacy | none), ...}``; the example file ``pid_controller/test/pid_controller_params.yaml``
puts them under ``<controller>: ros__parameters:``.
chained_filter_controller (ros2_controllers, ``chained_filter_controller/src/
chained_filter_parameters.yaml`` and ``test/config/test_multiple_chained_filter.yaml``):
``input_interfaces``, ``output_interfaces``, per input ``<interface>.filter_chain.filterN.
{name, type, params}``; the ROS filters package's ``filters/TransferFunctionFilterDouble``
(ros/filters, branch ros2, ``include/filters/transfer_function.hpp``) reads ``params.a`` and
``params.b``: y = (b0 x + b1 x[-1] + ... - a1 y[-1] - ...) / a0.
The python-control objects are compared with the responses frf_ident computes.
"""
import pickle

from frf_ident.core.loop.notch import design_lowpass, design_notch
from frf_ident.core.loop.shaping import AxisSetting
from frf_ident.core.loop.uncertainty import fit_weight
from frf_ident.io.controller_lti import write_control_objects
from frf_ident.io.ros2_control import (filter_chain_params, pid_controller_params, PID_NODE,
                                       write_params)
import numpy as np
from scipy import signal
import yaml

#: the per-DOF gains keys of pid_controller.yaml (branch jazzy)
GAIN_KEYS = {'p', 'i', 'd', 'u_clamp_max', 'u_clamp_min', 'antiwindup', 'i_clamp_max',
             'i_clamp_min', 'antiwindup_strategy', 'tracking_time_constant', 'error_deadband',
             'feedforward_gain', 'angle_wraparound', 'save_i_term', 'activate_state_publisher'}
STRATEGIES = {'back_calculation', 'conditional_integration', 'legacy', 'none'}
FS = 1000.0


def _settings():
    n = design_notch(36.4, 36.8, 0.011, 0.5, FS)
    lp = design_lowpass(15.0, FS)
    return [AxisSetting('joint_1', 5460.0, 1.08e5, (n, lp)), AxisSetting('joint_2', 4000.0, 2e4),
            AxisSetting('joint_3', 1200.0, 9e3, (lp,))]


def test_pid_controller_yaml_in_the_documented_structure(tmp_path):
    s = _settings()
    path = write_params(pid_controller_params(s, [600.0, 800.0, 600.0]),
                        tmp_path / 'pid_controller.yaml', 'a comment\nover two lines')
    text = path.read_text()
    assert text.startswith('# a comment\n# over two lines\n')
    doc = yaml.safe_load(text)
    params = doc[PID_NODE]['ros__parameters']
    dofs = params['dof_names']
    assert dofs == ['joint_1', 'joint_2', 'joint_3'] and len(set(dofs)) == len(dofs)
    assert isinstance(params['command_interface'], str) and params['command_interface']
    assert params['command_interface'] == 'effort'
    assert 1 <= len(params['reference_and_state_interfaces']) < 3
    assert params['reference_and_state_interfaces'] == ['velocity']
    for a, lim in zip(s, [600.0, 800.0, 600.0]):
        g = params['gains'][a.axis]
        assert set(g) <= GAIN_KEYS
        assert (g['p'], g['i'], g['d']) == (a.kp, a.ki, 0.0)
        assert all(isinstance(g[k], float) for k in ('p', 'i', 'd', 'u_clamp_max'))
        assert g['u_clamp_max'] == lim and g['u_clamp_min'] == -lim
        assert g['antiwindup_strategy'] in STRATEGIES


def test_filter_chain_yaml_runs_the_sections(tmp_path):
    s = _settings()
    doc = yaml.safe_load(write_params(filter_chain_params(s), tmp_path / 'f.yaml').read_text())
    params = next(iter(doc.values()))['ros__parameters']
    assert params['input_interfaces'] == [f'{a.axis}/velocity' for a in s]
    assert params['output_interfaces'] == [f'{a.axis}/filtered_velocity' for a in s]
    x = np.random.default_rng(0).standard_normal(2000)
    for a in s:
        chain = params[f'{a.axis}/velocity']['filter_chain']
        assert list(chain) == [f'filter{k + 1}' for k in range(len(chain))]
        y = x.copy()
        for k in range(len(chain)):
            f = chain[f'filter{k + 1}']
            assert f['type'] == 'filters/TransferFunctionFilterDouble' and f['name']
            assert f['params']['a'][0] == 1.0
            y = signal.lfilter(f['params']['b'], f['params']['a'], y)
        want = signal.sosfilt(a.sos(), x) if a.filters else x
        np.testing.assert_allclose(y, want, rtol=1e-9, atol=1e-12)


def test_python_control_objects_have_the_responses_tune_computed(tmp_path):
    s = _settings()
    f = np.geomspace(1.0, 400.0, 50)
    w = fit_weight(f, 0.05 + 2 * np.exp(-((np.log(f) - np.log(40)) / 0.2) ** 2))
    path = write_control_objects(s, [w] * 3, 1 / FS, tmp_path / 'control_objects.pkl')
    objs = pickle.loads(path.read_bytes())
    assert set(objs) == {'controller', 'filters', 'filters_continuous', 'weight'}
    for a in s:
        c = objs['controller'][a.axis]
        assert c.dt == 1 / FS
        np.testing.assert_allclose(c(np.exp(2j * np.pi * f / FS)), a.response(f, 1 / FS),
                                   rtol=1e-8)
        cont = objs['filters_continuous'][a.axis](2j * np.pi * f)
        want = np.prod([b.continuous_response(f) for b in a.filters], axis=0) \
            if a.filters else np.ones(f.size)
        np.testing.assert_allclose(cont, want, rtol=1e-8)
        np.testing.assert_allclose(objs['weight'][a.axis](2j * np.pi * f), w.response(f),
                                   rtol=1e-8)
