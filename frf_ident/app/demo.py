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
The main job end to end: the node graph on the simulated robot, estimation, diagnosis.

Thin orchestration of :func:`frf_ident.app.graph.run_graph` (node processes on loopback: rclpy
when ROS 2 is sourced, else the DDS backend; on ROS_DOMAIN_ID when it is set, so ``ros2 topic
echo`` in the same shell sees the run), :func:`frf_ident.app.estimate.estimate_bag` and
:func:`frf_ident.app.diagnose.diagnose`.
"""
from __future__ import annotations

import logging
from pathlib import Path

from frf_ident.core.excitation.chirp_iteration import ChirpConfig
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.progress import Progress, sink
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.share import config_file

__all__ = ['DEMO_CHIRP', 'DEMO_MODEL', 'DEMO_MULTISINE', 'DEMO_ROBOT', 'estimate_and_diagnose',
           'run_demo']

_log = logging.getLogger(__name__)

#: the demo's short experiments (the identify defaults take minutes of simulated time)
DEMO_MULTISINE = MultisineConfig(n_realisations=4, n_periods=3, resolution_hz=0.5)
DEMO_CHIRP = ChirpConfig(duration=10.0, max_iterations=3)
#: nominal model for the diagnosis, and the simulated "real" robot (config/)
DEMO_MODEL = 'model_3axis.yaml'
DEMO_ROBOT = 'robot_3axis_demo.yaml'


def run_demo(out: Path, *, model: Path | None = None, robot: Path | None = None,
             multisine: MultisineConfig = DEMO_MULTISINE, chirp: ChirpConfig = DEMO_CHIRP,
             plant: str | None = None, progress: Progress | None = None) -> int:
    """
    Run the node graph, estimate from its bag and diagnose against the nominal model.

    Parameters
    ----------
    out
        Output directory (graph/bag, estimate/, diagnosis/ are created in it).
    model
        Nominal model file (default config/model_3axis.yaml).
    robot
        The simulated robot (default config/robot_3axis_demo.yaml).
    multisine, chirp
        The experiments.
    plant
        The plant node's ``plant`` (``mujoco``, ``mujoco:FILE.xml``, a plug-in); None: the
        robot model's own simulation.
    progress
        Called with one line per step; None: silent.

    Returns
    -------
    int
        0 on success.

    """
    progress = sink(progress)
    from frf_ident.app.graph import run_graph
    model = Path(model) if model else config_file(DEMO_MODEL)
    robot = Path(robot) if robot else (config_file(DEMO_ROBOT) or model)
    for p in (model, robot):
        if p is None or not Path(p).is_file():
            raise FrfIdentInputError(f'{p}: model file not found')
    out = Path(out)
    if (out / 'graph' / 'bag').exists():
        raise FrfIdentInputError(f'{out / "graph" / "bag"}: exists; choose a new --out')
    progress(f'demo: robot {robot}' + (f' simulated by {plant}' if plant else '')
             + f', nominal model {model}')
    bag, _ = run_graph(out / 'graph', robot=robot, multisine=multisine, chirp=chirp,
                       log=progress, params={'plant_node': {'plant': plant}} if plant else None)
    progress(f'demo: bag {bag}')
    estimate_and_diagnose(Path(bag), model, out, progress)
    return 0


def estimate_and_diagnose(bag: Path, model: Path, out: Path, progress: Progress) -> None:
    """
    Run the demo's stages after the run: estimate, diagnose, print the summary.

    Writes ``out/estimate`` and ``out/diagnosis``; the diagnosis' stages log their few INFO
    lines (the console shows them), its search trace goes to the log file.
    """
    from frf_ident.app.diagnose import diagnose
    from frf_ident.app.diagnosis_summary import diagnosis_summary
    from frf_ident.app.estimate import estimate_bag
    estimate_bag(bag, out / 'estimate', progress=progress)
    progress('demo: diagnosis against the nominal model (its search trace: -v, or demo.log)')
    res = diagnose(bag, model, out / 'diagnosis', progress=_log.debug)
    for line in diagnosis_summary(res, out / 'diagnosis'):
        progress(line)
