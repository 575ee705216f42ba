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
ROS 2 node suite of frf_ident (plant, controller, excitation + iteration service, estimator).

Thin nodes: they wire topics and parameters to the core objects (plant, PI, procedure phases,
ChirpIteration, BagRecorder, estimate_recording). See README_nodes.md.
"""
import os
import signal
import sys
import threading

#: the node executables (console scripts and ``python -m frf_ident.nodes.<name>``)
NODE_NAMES = ('plant_node', 'controller_node', 'excitation_node', 'estimator_node')


def _stop_at_once(signum: int, frame: object) -> None:
    """SIGINT/SIGTERM while a node process is still importing: nothing is open yet, exit 0."""
    os._exit(0)       # at once: the interpreter's teardown of half-imported numba takes seconds


def is_node_process() -> bool:
    """Return whether this process runs a node (``--ros-args`` or a node executable)."""
    return '--ros-args' in sys.argv or os.path.basename(sys.argv[0]) in NODE_NAMES


# Ctrl-C at any moment ends a node with exit 0 and no KeyboardInterrupt traceback: from here
# (before numpy, numba and rclpy load) until ``common.StopOnSignal`` takes over
if threading.current_thread() is threading.main_thread() and is_node_process():
    signal.signal(signal.SIGINT, _stop_at_once)
    signal.signal(signal.SIGTERM, _stop_at_once)
    # started with both blocked (launch/frf_ident.launch.py): a Ctrl-C that came
    # during the interpreter's own start-up is pending and handled now
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
