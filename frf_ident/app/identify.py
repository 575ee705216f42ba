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
"""Identification on a plant: load the model and plant, run the experiments, record a bag."""
from __future__ import annotations

from pathlib import Path
from typing import Any

from frf_ident.app.outdir import check_out
from frf_ident.core.progress import Progress

__all__ = ['run_identify']


def run_identify(model_path: str | Path | None, plant_spec: str | None, config: Any,
                 out: str | Path, *, progress: Progress | None = None):
    """
    Run the identification experiments in closed loop and write the bag.

    Parameters
    ----------
    model_path : str or Path or None
        Model file, or None for the embedded 3-axis model.
    plant_spec : str or None
        Plant plug-in ``'package.module:Class'``, or None for the model's simulation.
    config : IdentificationConfig
        The procedures (:class:`~frf_ident.core.simulation.runner.IdentificationConfig`).
    out : str or Path
        Bag directory to create; an existing path, or one that cannot be created, is
        refused before anything runs (:func:`~frf_ident.app.outdir.check_out`).
    progress : callable, optional
        Called with one line per step; default None: silent.

    Returns
    -------
    Recording
        The recorded run (also written to ``out``).

    Raises
    ------
    FrfIdentInputError
        ``out`` exists, the model file is invalid (:class:`~frf_ident.errors.ModelFileError`)
        or the plant plug-in cannot be loaded; a plan beyond the position bound or predicted
        on the model to reach 0.95 of a torque limit (:class:`~frf_ident.errors.SafetyError`,
        nothing run).

    """
    from frf_ident.bag import write_recording
    from frf_ident.core.simulation.runner import run_identification
    from frf_ident.io.model_file import load_model, load_plant
    out = check_out(out, outputs=None, overwrite=False)
    model, robot, ctrl = load_model(model_path)
    plant = load_plant(plant_spec, model)
    rec = run_identification(plant, ctrl, config, progress=progress,
                             meta={'model': model, 'plant': plant_spec or 'model'}, model=robot)
    write_recording(rec, out)
    return rec
