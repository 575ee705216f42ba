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
The one pairing rule of state and effort (docs/CONTRACT.md §3; frf_ident/bag/pairing.py).

Issue 44: a lockstep run recorded with ``ros2 bag record`` gave phase = true + 360 f dt, and
``ros2 bag play`` into the estimator with ``--clock`` the opposite, without a word. Now the
bag holds joint states as published and the descriptors declare ``effort_lag``: here joint
state k carries the analytic torque of sample k - 1 (the lockstep plant's report) and the
reader must give back the analytic torque at t_k; descriptors that disagree, or declare a lag
the rule does not know, are refused with one line naming the bag and the lags.
"""
from __future__ import annotations

from bag_synth import make_recording, truth
from frf_ident.bag import read_recording, write_recording
from frf_ident.core.recording import Recording, Segment
from frf_ident.errors import BagError
import numpy as np
import pytest


def _published(lags: list) -> Recording:
    """make_recording with joint state k's effort = torque of t_(k-1), segments with ``lags``."""
    rec = make_recording(seconds=3.0)
    eff = truth(rec.t - (rec.t[1] - rec.t[0]))[2]       # the torque applied over [t_k-1, t_k)
    segs = [Segment(s.t_start, s.t_end, dict(s.info) if lag is None else
                    {**s.info, 'effort_lag': lag}) for s, lag in zip(rec.segments, lags)]
    return Recording(rec.t, list(rec.joint_names), rec.position, rec.velocity, eff,
                     rec.reference, rec.excitation, segs, dict(rec.meta))


def test_declared_lag_1_pairs_state_k_with_the_torque_applied_from_t_k(tmp_path):
    got, _ = read_recording(write_recording(_published([1, 1]), tmp_path / 'lag1'))
    want = truth(got.t)[2]
    np.testing.assert_allclose(got.effort[:-1], want[:-1], atol=1e-9)
    # the last sample keeps its own (there is no joint state k + 1 to take it from)
    np.testing.assert_allclose(got.effort[-1], truth(got.t[-2:-1])[2][0], atol=1e-9)


def test_undeclared_lag_is_0_so_the_published_effort_stays_a_sample_late(tmp_path):
    got, _ = read_recording(write_recording(_published([None, None]), tmp_path / 'lag0'))
    dt = got.t[1] - got.t[0]
    np.testing.assert_allclose(got.effort, truth(got.t - dt)[2], atol=1e-9)
    assert np.max(np.abs(got.effort - truth(got.t)[2])) > 1e-2    # the test can tell them apart


@pytest.mark.parametrize('lags, shown', [([0, 1], '[0, 1]'), ([2, 2], '[2]')])
def test_descriptors_that_disagree_or_declare_an_unknown_lag_are_refused(tmp_path, lags, shown):
    bag = write_recording(_published(lags), tmp_path / 'odd')
    with pytest.raises(BagError) as err:
        read_recording(bag)
    msg = str(err.value)
    assert '\n' not in msg and 'odd' in msg and f'effort_lag={shown}' in msg, msg
