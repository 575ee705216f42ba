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
from glob import glob
import os

from setuptools import find_packages, setup

package_name = 'frf_ident'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*', 'benchmarks', 'benchmarks.*']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        (os.path.join('share', package_name, 'launch'),
         glob(os.path.join('launch', '*launch.[pxy][yma]*'))),
        (os.path.join('share', package_name, 'config'),
         glob(os.path.join('config', '*.yaml')) + glob(os.path.join('config', '*.xml'))
         + glob(os.path.join('config', '*.json'))),
        (os.path.join('share', package_name, 'config', 'sros2'),
         glob(os.path.join('config', 'sros2', '*.xml'))),
        (os.path.join('share', package_name, 'urdf'), glob(os.path.join('urdf', '*.urdf'))),
    ],
    python_requires='>=3.10',
    install_requires=[
        'setuptools',
        'numpy>=1.24',
        'scipy>=1.10',
        'numba>=0.58',
        'pyyaml>=6.0',
        'matplotlib>=3.7',
        'tqdm>=4.65',
        'rosbags>=0.10.4',
        'mcap>=1.1',
        'mcap-ros2-support>=0.5',
        'cyclonedds>=0.10.5',
        'control>=0.10',     # fit export and the loop check (stability_margins on FRD)
        'threadpoolctl>=3.1',   # one BLAS thread per process where the diagnosis forks workers
    ],
    extras_require={
        'test': ['pytest>=7.4', 'pytest-xdist>=3.5', 'hypothesis>=6.80', 'control>=0.10',
                 'import-linter>=2.1',
                 # the linters as ROS 2 Jazzy (Ubuntu 24.04) ships them, for ament_flake8/pep257
                 'flake8==7.0.0', 'flake8-builtins==2.1.0', 'flake8-comprehensions==3.14.0',
                 'flake8-docstrings==1.6.0', 'flake8-import-order==0.18.2',
                 'flake8-quotes==3.3.2', 'pydocstyle==6.3.0',
                 'wheel',    # test/ros installs the package into a prefix as colcon would
                 # the campaign (Dask LocalCluster) and pose (pinocchio) tests run in CI too
                 'dask>=2023.1', 'distributed>=2023.1', 'pin>=2.7',
                 # MuJoCo as the plant and the nominal model (test/io/test_mjcf_*.py)
                 'mujoco>=4.0',
                 # the live stream's Foxglove WebSocket and a protocol client for its test
                 'foxglove-sdk>=0.30', 'websockets>=12'],
        'control': ['control>=0.10'],
        # campaigns on a Dask distributed cluster (`--scheduler`); the default needs neither
        'cluster': ['dask>=2023.1', 'distributed>=2023.1'],
        # pose-dependent link side of the simulated robot from its URDF (frf_ident.io.kinematics)
        'kinematics': ['pin>=2.7'],
        # an MJCF robot as the plant (--plant mujoco), as the nominal model (mjcf:) and the
        # fit's model.xml (frf_ident.io.mjcf; 4.0: mj_fullM(m, d, M), joint stiffness and damping
        # polynomials, actuator delay)
        'mujoco': ['mujoco>=4.0'],
        # the live stream on a Foxglove WebSocket without ROS (frf_ident.io.foxglove_server)
        'foxglove': ['foxglove-sdk>=0.30'],
    },
    zip_safe=True,
    maintainer='frf_ident developers',
    maintainer_email='dev@example.com',
    description='Closed-loop FRF identification of flexible-joint robots (Saupe & Knoblach 2015)',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'frf-ident = frf_ident.cli:main',
            'plant_node = frf_ident.nodes.plant_node:main',
            'controller_node = frf_ident.nodes.controller_node:main',
            'excitation_node = frf_ident.nodes.excitation_node:main',
            'estimator_node = frf_ident.nodes.estimator_node:main',
            'operator = frf_ident.nodes.operator_node:main',
        ],
    },
)
