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
ChirpIteration, BagRecorder, estimate_recording). See docs/nodes.md.
"""
import os
import signal
import sys
import threading
import time

#: the node executables (console scripts and ``python -m frf_ident.nodes.<name>``)
NODE_NAMES = ('plant_node', 'controller_node', 'excitation_node', 'estimator_node',
              'operator', 'operator_node')


#: after a Ctrl-C in start-up, how long [s] a node waits for the SIGINT ``ros2 launch`` sends
#: it (launch signals every node within milliseconds of a Ctrl-C). A terminal's Ctrl-C reaches
#: the whole process group; a node that ended on it at once could end just before launch's
#: own SIGINT, whose Popen.send_signal polls the child first and so reaps it: asyncio's child
#: watcher then reports 'Unknown child process ... returncode 255' and launch exits 1 (1 run in
#: 3 of test_ctrl_c_at_start_up). Ending on launch's signal, after that poll, leaves the exit
#: status to the watcher. Under ``ros2 run`` no second signal comes: the node ends after this.
#: 0.5 s was too short beside the test suite's other worker: launch's SIGINT came later, one
#: node ended on its own, launch stopped the others as it does when a required node ends, and
#: lost one's status the same way (test_ctrl_c_at_start_up, 1 run in the session-33 CI).
PARENT_SIGNAL_WAIT_S = 2.0


def _exit_now(signum: int, frame: object) -> None:
    """Second SIGINT/SIGTERM in start-up (launch's own): exit 0 at once."""
    os._exit(0)       # at once: the interpreter's teardown of half-imported numba takes seconds


def _stop_at_once(signum: int, frame: object) -> None:
    """SIGINT/SIGTERM while a node process is still importing: nothing is open yet, exit 0."""
    signal.signal(signal.SIGINT, _exit_now)
    signal.signal(signal.SIGTERM, _exit_now)
    time.sleep(PARENT_SIGNAL_WAIT_S)       # launch's SIGINT ends it earlier (_exit_now)
    os._exit(0)


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
