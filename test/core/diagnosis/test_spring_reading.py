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
A bent joint spring read both ways: a stiffening gear from nominal, or a stiffness with a gap.

The truth is the spring law itself (eq. 2 behind a dead zone, written out here as the
reference plant test/plants/reference.py has it): beyond its breakpoint the stiffening gear of
:func:`as_stiffening` carries the same torque as the spring it replaces, within it less; beyond
the bends the stiffer spring behind a gap of :func:`as_backlash` carries the gear's.
"""
from frf_ident.core.diagnosis.experiments.spring_reading import as_backlash, as_stiffening
from hypothesis import given, settings, strategies as st
import numpy as np


def spring(e, k1, k2=None, bs=0.0, gap=0.0):
    """Return the torque of a spring k1 (k2 beyond bs) behind a dead zone of total ``gap``."""
    x = np.sign(e) * np.maximum(np.abs(e) - gap / 2, 0.0)
    k2 = k1 if k2 is None else k2
    ax = np.abs(x)
    return np.sign(x) * np.where(ax > bs, k1 * bs + k2 * (ax - bs), k1 * ax)


@settings(max_examples=60, deadline=None)
@given(k1=st.floats(5e4, 5e5), stiffer=st.floats(1.05, 3.0),
       gap=st.one_of(st.just(0.0), st.floats(1e-7, 5e-4)),
       shaped=st.booleans(), bs=st.floats(1e-5, 5e-4), rise=st.floats(1.05, 2.0))
def test_the_gear_carries_the_same_torque_beyond_its_breakpoint(k1, stiffer, gap, shaped, bs,
                                                                rise):
    k_a = k1 * stiffer
    k2 = k_a * rise if shaped else None
    if not shaped and gap == 0.0:
        assert as_stiffening(k1, k_a, gap) is None      # a linear spring has no bend
        return
    k2n, bsn = as_stiffening(k1, k_a, gap, k2, bs if shaped else 0.0)
    reach = max(bsn, gap / 2 + (bs if shaped else 0.0))
    e = np.linspace(1.01, 4.0, 40) * reach
    was = spring(e, k_a, k2, bs if shaped else 0.0, gap)
    now = spring(e, k1, k2n, bsn)
    assert np.allclose(now, was, rtol=1e-9, atol=1e-9 * abs(was).max())
    # within the breakpoint the nominal stiffness carries more than the dead zone
    if gap > 0 and not shaped:
        inner = np.linspace(0.05, 0.45, 5) * gap
        assert np.all(spring(inner, k1, k2n, bsn) > spring(inner, k_a, gap=gap))


def test_a_softer_line_is_no_stiffening_gear():
    # a stiffness mismatched below nominal with a dead zone: no gear from k1 bends it so
    assert as_stiffening(1.2e5, 1.0e5, 1e-4) is None


@settings(max_examples=40, deadline=None)
@given(k1=st.floats(5e4, 5e5), stiffer=st.floats(1.05, 3.0), bs=st.floats(1e-5, 5e-4))
def test_the_gap_carries_the_same_torque_beyond_the_bends(k1, stiffer, bs):
    k2 = k1 * stiffer
    k, gap = as_backlash(k1, k2, bs)
    e = np.linspace(1.01, 4.0, 40) * max(bs, gap / 2)
    was = spring(e, k1, k2, bs)
    assert np.allclose(spring(e, k, gap=gap), was, rtol=1e-9, atol=1e-9 * abs(was).max())
    # and read back as a stiffening gear from k1 it is the gear it came from
    assert np.allclose(as_stiffening(k1, k, gap), (k2, bs), rtol=1e-9)


def test_a_softer_gear_is_no_gap():
    # a stiffening gear that softens beyond its breakpoint: no stiffer spring behind a gap
    assert as_backlash(3e5, 2.5e5, 1e-4) is None
