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
"""Recording: restriction to named joints (what diagnose does to fit a model's axes)."""
from frf_ident.core.recording import Recording, Segment
import numpy as np
import pytest


def test_select_joints_keeps_order_samples_segments_and_meta():
    t = np.arange(5) * 0.01
    sig = np.arange(15, dtype=float).reshape(5, 3)
    seg = Segment(0.0, 0.04, {'design': 'multisine'})
    rec = Recording(t, ['a', 'b', 'c'], sig, sig + 100, sig + 200, reference=sig + 300,
                    segments=[seg], meta={'source': 'x'})
    sub = rec.select_joints(['c', 'a'])
    assert sub.joint_names == ['c', 'a']
    np.testing.assert_array_equal(sub.position, sig[:, [2, 0]])
    np.testing.assert_array_equal(sub.effort, sig[:, [2, 0]] + 200)
    np.testing.assert_array_equal(sub.reference, sig[:, [2, 0]] + 300)
    assert sub.excitation is None
    assert sub.segments == [seg] and sub.meta == {'source': 'x'}
    sub.meta['source'] = 'y'       # a copy: the original keeps its meta
    assert rec.meta == {'source': 'x'}
    with pytest.raises(ValueError):
        rec.select_joints(['d'])
