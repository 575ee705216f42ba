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
"""The fitted model exported to python-control and .mat gives the analytic robot back."""
from __future__ import annotations

import control
from frf_ident.core.fit.rational import fit_rational
from frf_ident.core.model.schema import default_robot
from frf_ident.core.simulation.analytic import robot_frf
from frf_ident.io.lti import to_state_space, to_transfer_function, write_lti_mat
import numpy as np
from scipy.io import loadmat


def test_exports_reproduce_the_analytic_robot(tmp_path):
    robot = default_robot()
    f = np.geomspace(0.5, 60.0, 80)
    p = robot_frf(robot, f)
    fit = fit_rational(f, p, None, 9, 8, inputs=robot.joint_names, outputs=robot.joint_names)
    w = 2 * np.pi * f
    for sys in (to_transfer_function(fit), to_state_space(fit)):
        resp = sys.frequency_response(w).complex
        assert np.max(np.abs(resp - p) / np.abs(p)) < 1e-5
        assert list(sys.input_labels) == robot.joint_names
    m = loadmat(write_lti_mat(fit, tmp_path / 'model.mat'))
    sys = control.ss(m['A'], m['B'], m['C'], m['D'])
    assert np.max(np.abs(sys.frequency_response(w).complex - p) / np.abs(p)) < 1e-5
    assert [str(x[0]) for x in m['InputName'].ravel()] == robot.joint_names
