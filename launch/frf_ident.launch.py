"""Launch the frf_ident node suite on real ROS 2 (rclpy): plant, controller, excitation with the
chirp iteration service, estimator; parameters from config/frf_ident.yaml, use_sim_time.

    ros2 launch frf_ident frf_ident.launch.py model:=/path/model.yaml bag:=/tmp/run1
    ros2 service call /frf/run_multisine std_srvs/srv/Trigger
    ros2 service call /frf/run_iteration std_srvs/srv/Trigger

On a real robot leave out the plant (``sim:=false``): the robot's joint_state_broadcaster and
effort/velocity controllers take its place.
"""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    params = os.path.join(get_package_share_directory('frf_ident'), 'config', 'frf_ident.yaml')
    model = LaunchConfiguration('model')
    sim = LaunchConfiguration('sim')
    bag = LaunchConfiguration('bag')
    common = [params, {'use_sim_time': LaunchConfiguration('use_sim_time'), 'model': model}]
    return LaunchDescription([
        DeclareLaunchArgument('model', default_value=''),
        DeclareLaunchArgument('sim', default_value='true'),
        DeclareLaunchArgument('use_sim_time', default_value='true'),
        DeclareLaunchArgument('bag', default_value=''),
        Node(package='frf_ident', executable='plant_node', name='plant_node',
             parameters=common, output='screen', condition=IfCondition(sim)),
        Node(package='frf_ident', executable='controller_node', name='controller_node',
             parameters=common, output='screen', condition=IfCondition(sim)),
        Node(package='frf_ident', executable='excitation_node', name='excitation_node',
             parameters=common, output='screen'),
        Node(package='frf_ident', executable='estimator_node', name='estimator_node',
             parameters=common + [{'bag': bag}], output='screen'),
    ])
