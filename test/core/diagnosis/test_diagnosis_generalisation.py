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
Keep a position-dependent term only where it generalises to another record.

Rigid 3-axis arm records written here (axis 1 vertical; equations of motion with friction and
inertia), axis 2 loaded by a torque of its own angle; the fit record moves axis 2 around 0,
the other record around 0.6 rad, mostly beyond the fitted range.
"""
from dataclasses import replace

from frf_ident.core.diagnosis.crosscheck.generalisation import drop_terms_not_generalising
from frf_ident.core.diagnosis.timeseries import diagnose_timeseries
from frf_ident.core.model.schema import robot_from_dict
from frf_ident.core.recording import Recording
import numpy as np
import pytest

RIGID = {'frf_ident_model': 1, 'sample_rate': 250.0, 'axes': [
    {'name': f'joint_{k + 1}', 'motor_inertia': j, 'link_inertia': 1e-3, 'stiffness': 1e9,
     'damping': 0.0} for k, j in enumerate((6.0, 4.0, 1.5))]}


def _arm(seed: int, centre: float, load, fs: float = 250.0, T: float = 20.0) -> Recording:
    """Return an arm record whose axis 2 moves around ``centre`` carrying ``load(q2)``."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(T * fs)) / fs
    q = np.zeros((t.size, 3))
    for i in range(3):
        for _ in range(4):
            q[:, i] += rng.uniform(0.05, 0.12) * np.sin(
                2 * np.pi * rng.uniform(0.05, 0.6) * t + rng.uniform(0, 6))
    q[:, 1] += centre
    v = np.gradient(q, 1 / fs, axis=0)
    # torque held over each sample interval: the equations of motion at its middle
    qh, vh = 0.5 * (q[1:] + q[:-1]), 0.5 * (v[1:] + v[:-1])
    u = np.array([6.0, 4.0, 1.5]) * np.diff(v, axis=0) * fs \
        + np.array([3.0, 4.0, 2.0]) * np.sign(vh)
    u[:, 1] += load(qh[:, 1])
    u = np.vstack([u, u[-1:]]) + 0.2 * rng.standard_normal((t.size, 3))
    return Recording(t, ['joint_1', 'joint_2', 'joint_3'], q,
                     v + 1e-4 * rng.standard_normal(v.shape), u)


@pytest.mark.parametrize('load, kept', [
    (lambda x: 60.0 * np.sin(x + 0.4), True),        # a link's weight: extrapolates
    (lambda x: 100.0 * np.abs(x), False),            # a V-shaped spring load: does not
])
def test_a_position_term_is_kept_only_if_it_predicts_the_other_record(load, kept):
    fit, other = _arm(1, 0.0, load), _arm(2, 0.6, load)
    robot = replace(robot_from_dict(RIGID), sample_rate=fit.fs)
    res = diagnose_timeseries(fit, robot)
    # both loads are taken for gravity on the fit record alone
    assert ('gravity', 'joint_2') in {(e.name, e.axis) for e in res.effects}
    out, verdict = drop_terms_not_generalising(res, fit, robot, [('other', other)])
    names = {(e.name, e.axis) for e in out.effects}
    assert (('gravity', 'joint_2') in names) == kept, verdict
    assert verdict['joint_2'].dropped == (not kept)
    # the friction of every axis stays whatever happens to the position term
    assert {('coulomb_friction', f'joint_{k}') for k in (1, 2, 3)} <= names
    if kept:
        # 0.017 with the weight's sinusoid, 6.1 with a constant in its place
        assert verdict['joint_2'].with_terms[0] < 0.1 < verdict['joint_2'].without_terms[0]
        assert out is res
    else:
        # 9.0 with the sinusoid (amplitude 816 N m), 4.6 refitted without it
        (why,) = [r for r in out.rejected if r.name == 'gravity' and 'other' in
                  (r.reason or '')]
        assert 'does not generalise' in why.reason
        assert out.extended.axes[1].gravity == []
        assert out.metrics.extended.per_axis['joint_2'].time_nrmse > 0
