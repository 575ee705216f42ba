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
A joint refit steps back from a model no robot holds instead of ending the diagnosis.

``demo --plant mujoco --max-iterations 2`` on the elastic iiwa (issue 50) ended in the
diagnosis' joint refit of joint4 with "link inertia matrix without the second modes' inertia
must be positive definite": the simplex lowered the link inertia of an axis whose kept
second mode carries most of it. Here the misfit is an analytic function of the link inertia
(its minimum where no model exists: below the mode's inertia), so the refit must end on the
models that exist, at the lightest link that still holds its mode.
"""
import math

from frf_ident.core.diagnosis.common import Effect
from frf_ident.core.diagnosis.experiments.refit import refit_jointly
from frf_ident.core.model.schema import default_model_dict, robot_from_dict
import numpy as np


class _Analytic:
    """An evaluator whose misfit of axis 0 is (log(link_inertia / TARGET))^2 + 1."""

    def __init__(self, target: float) -> None:
        self.target, self.seen = target, []

    def terms(self, robot):
        x = math.log(robot.axes[0].link_inertia / self.target) ** 2 + 1.0
        self.seen.append(robot.axes[0].link_inertia)
        return {'fit': np.array([x] + [1.0] * (robot.n_axes - 1))}

    def misfit(self, terms):
        return terms['fit']

    def loss(self, robot, axis):
        return float(self.misfit(self.terms(robot))[axis])

    def prefetch(self, robots):
        list(robots)


def test_joint_refit_ends_on_a_model_that_exists():
    base = robot_from_dict(default_model_dict())
    link = base.axes[0].link_inertia
    mode = {'frequency_hz': 40.0, 'damping_ratio': 0.05, 'inertia': 0.9 * link}
    kept = [Effect('second_mode', base.axes[0].name, 1.0, {'second_mode': mode}, '', 0),
            Effect('parameter_mismatch', base.axes[0].name, 1.0, {'link_inertia': link}, '', 0)]
    ev = _Analytic(target=0.5 * link)          # the misfit pulls the link below its mode
    cur = ev.misfit(ev.terms(base))
    ext, new = refit_jointly(ev, base, kept, 0, cur, lambda line: None)
    got = ext.axes[0].link_inertia
    print(f'link inertia {link:.4g} -> {got:.4g} (mode {mode["inertia"]:.4g}); '
          f'{len(ev.seen)} models evaluated, lightest {min(ev.seen):.4g}')
    assert mode['inertia'] < got < link
    assert new[0] < cur[0]
    assert min(ev.seen) > mode['inertia']          # no model below the mode was evaluated
