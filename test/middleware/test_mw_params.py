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
"""ROS parameter files, --ros-args parsing and parameter precedence on the DDS backend."""

import textwrap

from frf_ident.errors import FrfIdentInputError
from frf_ident.middleware import load_params_file, parse_ros_args, strip_ros_args
import pytest

YAML = textwrap.dedent("""
    /**:
      ros__parameters:
        use_sim_time: true
        rate_hz: 100.0
    frf_excitation:
      ros__parameters:
        controller_name: forward_velocity_controller
        joints: [joint1, joint2]
        rate_hz: 500.0
        limits:
          torque: 2.5
    /other_node:
      ros__parameters:
        rate_hz: 1.0
    robot:
      frf_plant:
        ros__parameters:
          stiffness: 1.0e4
    /robot/*:
      ros__parameters:
        in_robot_ns: true
""")


@pytest.fixture
def params_file(tmp_path):
    path = tmp_path / 'frf_ident.yaml'
    path.write_text(YAML)
    return path


def test_wildcard_and_node_specific(params_file):
    assert load_params_file(params_file, 'frf_excitation') == {
        'use_sim_time': True, 'rate_hz': 500.0, 'controller_name': 'forward_velocity_controller',
        'joints': ['joint1', 'joint2'], 'limits.torque': 2.5}
    assert load_params_file(params_file, 'other_node') == {'use_sim_time': True, 'rate_hz': 1.0}
    assert load_params_file(params_file, 'unknown') == {'use_sim_time': True, 'rate_hz': 100.0}
    assert load_params_file(params_file, None) == {'use_sim_time': True, 'rate_hz': 100.0}


def test_namespaced_sections(params_file):
    assert load_params_file(params_file, 'frf_plant', '/robot') == {
        'use_sim_time': True, 'rate_hz': 100.0, 'stiffness': 1.0e4, 'in_robot_ns': True}


def test_parse_ros_args(params_file):
    argv = ['prog', '--out', 'x', '--ros-args', '--params-file', str(params_file),
            '-p', 'rate_hz:=250', '--param', 'joints:=[a, b]', '-p', 'label:=hello',
            '-p', 'other_node:rate_hz:=3.0', '-r', '__node:=ignored', '--', 'tail']
    file_values, overrides = parse_ros_args(argv, 'frf_excitation')
    assert file_values['rate_hz'] == 500.0 and file_values['joints'] == ['joint1', 'joint2']
    assert overrides == {'rate_hz': 250, 'joints': ['a', 'b'], 'label': 'hello'}
    assert parse_ros_args(argv, 'other_node')[1]['rate_hz'] == 3.0
    assert strip_ros_args(argv) == ['prog', '--out', 'x', 'tail']
    assert parse_ros_args(['prog', '--flag']) == ({}, {})


@pytest.mark.parametrize('argv, match', [
    (['--ros-args', '-p', 'novalue'], 'name:=value'),
    (['--ros-args', '--params-file'], 'needs a value'),
    (['--ros-args', '--bogus'], 'unknown ROS argument'),
    (['--ros-args', '--params-file', '/nonexistent/p.yaml'], 'parameter file not found'),
])
def test_bad_ros_args(argv, match):
    with pytest.raises(FrfIdentInputError, match=match):
        parse_ros_args(argv, 'n')


def test_bad_params_file(tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text('node:\n  ros__parameters: [1, 2]\n')
    with pytest.raises(FrfIdentInputError, match='must be a map'):
        load_params_file(bad, 'node')
    bad.write_text('a: [unclosed\n')
    with pytest.raises(FrfIdentInputError, match='not valid YAML') as exc:
        load_params_file(bad, 'node')
    assert '\n' not in str(exc.value)          # PyYAML's message took 7 lines
    # a Latin-1 degree sign in a comment: one line naming the file (a UnicodeDecodeError before)
    bad.write_bytes(b'node:\n  ros__parameters:\n    # \xb0\n    a: 1\n')
    with pytest.raises(FrfIdentInputError, match=r'bad\.yaml: not UTF-8 text \(byte 0xb0'):
        load_params_file(bad, 'node')
    with pytest.raises(FrfIdentInputError, match='parameter file not found'):
        load_params_file(tmp_path / 'none.yaml', 'node')


def test_node_parameter_precedence(params_file, domain_env):
    from frf_ident.middleware import dds_backend as dds
    dds.shutdown()
    dds.init(['prog', '--ros-args', '--params-file', str(params_file), '-p', 'rate_hz:=250.0',
              '-p', 'label:=cli'])
    node = dds.create_node('frf_excitation', parameter_overrides={'label': 'code'},
                           use_sim_time=False)
    assert node.declare_parameter('rate_hz', 1.0).value == 250.0  # -p beats the file
    assert node.declare_parameter('controller_name', 'x').value == 'forward_velocity_controller'
    assert node.declare_parameter('label', 'default').value == 'code'  # overrides beat -p
    assert node.declare_parameter('absent', 7).value == 7
    assert node.get_parameter('use_sim_time').value is False  # explicit argument wins
    assert node.get_parameter('rate_hz').value == 250.0
    with pytest.raises(LookupError, match='not_declared'):
        node.get_parameter('not_declared')
    with pytest.raises(ValueError, match='already declared'):
        node.declare_parameter('absent', 8)
    node.destroy_node()
    dds.shutdown()
