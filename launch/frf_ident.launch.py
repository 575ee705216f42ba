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
Launch the frf_ident nodes: plant with its velocity PI (sim only), excitation, estimator.

    ros2 launch frf_ident frf_ident.launch.py model:=/path/model.yaml bag:=/tmp/run1
    ros2 service call /frf/run_multisine std_srvs/srv/Trigger     # answers after planning
    ros2 topic echo /frf/progress                                 # progress and the end

Arguments: ``model`` (model file; '' = the package's default), ``bag`` (bag directory the
estimator creates; '' = ./frf_bag_<date>_<time>), ``sim`` (true: simulated plant and
its PI in lockstep on sim time; false: a real robot, the nodes run free on wall time and the
robot's joint_state_broadcaster and velocity controller take the plant's place),
``use_sim_time`` (default: the value of ``sim``), ``params_file`` (default: the package's
config/frf_ident.yaml; a copy of it with your settings), ``arming`` ('' = by ``sim``: 'off' in
simulation, 'token' on a robot, whose excitation node then refuses runs until the operator's
console arms it, docs/ros2.md "Arming"). ``lockstep`` always equals ``sim``.
Parameters are read at start-up and read-only afterwards. When a node exits (it refused its
parameters, or crashed) the launch shuts down: no half graph accepts runs it cannot record;
a node that exited non-zero makes ``ros2 launch`` exit 1 (scripts can tell). ``sim:=false``
with ``use_sim_time:=true`` is refused (a real robot publishes no /clock), and so is
``sim:=false`` with ``arming:=off`` (anyone on the domain could start the robot).

Each node starts with SIGINT and SIGTERM blocked (``env --block-signal``, GNU coreutils >= 8.31)
and unblocks them once its handlers are in place (frf_ident/nodes/__init__.py): a Ctrl-C during
the Python interpreter's own start-up (site.py, .pth files: up to ~0.2 s on a busy PC) is held
pending instead of ending the node with a KeyboardInterrupt traceback, and then ends it with
exit 0. A ``--launch-prefix`` (gdb, valgrind) goes before it.
"""
import os
import shutil
import subprocess

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction, Shutdown
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration

from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue


def _block_signals_prefix():
    """Return the prefix that starts a node with SIGINT/SIGTERM blocked ('' if unsupported)."""
    env = shutil.which('env')
    cmd = [env, '--block-signal=INT', '--block-signal=TERM']
    if env is None or subprocess.run(cmd + ['true'], capture_output=True).returncode != 0:
        return ''   # not GNU env (or older than 8.31): Ctrl-C in start-up may show a traceback
    return ' ' + ' '.join(cmd)


class NodeFailed(RuntimeError):
    """A node exited non-zero: launch logs this one line, shuts down and exits 1."""


def _node_exited(event, context):
    """Shut the launch down when a node exits; non-zero (it refused, or crashed): exit 1."""
    name = str(event.action.process_details['name']).rsplit('-', 1)[0]   # 'plant_node-1'
    if event.returncode != 0:
        raise NodeFailed(f'{name} exited with code {event.returncode} (see its log above)')
    return [Shutdown(reason=f'{name} exited')]


def _check_time_source(context):
    """Refuse sim:=false use_sim_time:=true: no /clock on a real robot, every node would wait."""
    sim = LaunchConfiguration('sim').perform(context).lower() in ('true', '1', 'yes')
    sim_time = LaunchConfiguration('use_sim_time').perform(context).lower() in ('true', '1',
                                                                                'yes')
    if sim_time and not sim:
        raise NodeFailed('sim:=false with use_sim_time:=true: a real robot publishes no /clock;'
                         ' leave use_sim_time at its default (the value of sim)')
    if not sim and LaunchConfiguration('arming').perform(context).lower() == 'off':
        raise NodeFailed('sim:=false with arming:=off: any participant of the domain could '
                         "start the robot; leave arming at its default ('token')")
    return []


def generate_launch_description():
    """Return plant (sim only), excitation and estimator, one per process and name."""
    params = os.path.join(get_package_share_directory('frf_ident'), 'config', 'frf_ident.yaml')
    sim = LaunchConfiguration('sim')
    common = [LaunchConfiguration('params_file'), {
        'use_sim_time': ParameterValue(LaunchConfiguration('use_sim_time'), value_type=bool),
        'lockstep': ParameterValue(sim, value_type=bool),
        'model': ParameterValue(LaunchConfiguration('model'), value_type=str)}]
    arming = {'arming': ParameterValue(LaunchConfiguration('arming'), value_type=str)}
    bag = {'bag': ParameterValue(LaunchConfiguration('bag'), value_type=str)}
    prefix = [LaunchConfiguration('launch-prefix', default=''), _block_signals_prefix()]

    def node(executable, extra=(), condition=None):
        """Launch one node of the package under its own name."""
        # exec_name: the log label stays 'plant_node-1' (the prefix's 'env' otherwise)
        return Node(package='frf_ident', executable=executable, name=executable,
                    exec_name=executable,
                    parameters=common + list(extra), output='screen', condition=condition,
                    on_exit=_node_exited, prefix=prefix)

    return LaunchDescription([
        DeclareLaunchArgument('model', default_value='', description='model file'),
        DeclareLaunchArgument('sim', default_value='true',
                              description='simulated robot (lockstep) or a real one'),
        DeclareLaunchArgument('use_sim_time', default_value=sim,
                              description='default: the value of sim'),
        DeclareLaunchArgument('bag', default_value='', description='bag directory'),
        DeclareLaunchArgument('arming', default_value='',
                              description="'' (by sim), 'token' or 'off' (refused on a robot)"),
        DeclareLaunchArgument('params_file', default_value=params,
                              description="node parameters (default: the package's)"),
        OpaqueFunction(function=_check_time_source),
        # simulation: the plant hosts the velocity PI (as ros2_control hosts its controllers)
        node('plant_node', [{'velocity_control': True}], condition=IfCondition(sim)),
        node('excitation_node', [arming]),
        node('estimator_node', [bag]),
    ])
