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
The live estimate over the node graph (DDS on loopback, lockstep).

A multisine with an uncertainty target: the excitation node stops it after the first
realisation's third period (the target is loose), the bag holds the live stream, and the last
/frf/live/frf frame in the bag equals the offline estimate of that bag to 1e-9.
"""
from __future__ import annotations

import json
from pathlib import Path

from frf_ident.app.graph import Graph
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
import numpy as np
import pytest

pytestmark = pytest.mark.xdist_group('test_live_graph')
ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / 'config' / 'model_3axis.yaml'


def _frames(bag: Path, topic: str) -> list:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import get_typestore, Stores
    out = []
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as r:
        conns = [c for c in r.connections if c.topic == topic]
        for conn, t, raw in r.messages(connections=conns):
            m = r.deserialize(raw, conn.msgtype)
            dims = [(d.label, d.size, d.stride) for d in m.layout.dim]
            out.append((t, dims, np.asarray(m.data, float)))
    return out


def _texts(bag: Path, topic: str) -> list:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import get_typestore, Stores
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as r:
        conns = [c for c in r.connections if c.topic == topic]
        return [r.deserialize(raw, c.msgtype).data for c, _t, raw in r.messages(connections=conns)]


def test_live_stream_stops_at_target_and_equals_offline(tmp_path, new_domain):
    from frf_ident.bag import read_recording
    from frf_ident.core.estimation.described import estimate_recording
    from frf_ident.io.live_frame import decode_frf
    ms = MultisineConfig(n_realisations=2, n_periods=4, resolution_hz=1.0, return_s=2.0,
                         settle_s=0.3)
    g = Graph(tmp_path, model=MODEL, multisine=ms, domain_id=new_domain(),
              params={'excitation_node': {'target_sd_db': 20.0}})
    g.start()
    try:
        results = g.drive()
    finally:
        bag = g.stop()
    assert results['multisine']['success'], results
    rec, _ = read_recording(bag)
    seg = [s for s in rec.segments if s.info.get('design') == 'multisine']
    # stopped in realisation 0's last experiment after 3 periods: realisation 1 never ran
    assert [(s.info['realisation'], s.info['experiment'], s.info['periods']) for s in seg] \
        == [(0, 0, 4), (0, 1, 4), (0, 2, 3)]
    assert seg[-1].info['periods_planned'] == 4
    frames = _frames(bag, '/frf/live/frf')
    assert len(frames) == 2                      # after MIMO periods 2 and 3
    last = decode_frf(frames[-1][1], frames[-1][2])
    off = estimate_recording(rec)['multisine']
    mag = 20 * np.log10(np.abs(off.response)).reshape(9, -1)
    ph = np.degrees(np.unwrap(np.angle(off.response), axis=-1)).reshape(9, -1)
    assert np.allclose(last['freq_hz'][0], off.freq_hz, rtol=1e-12)
    assert np.max(np.abs(last['magnitude_db'] - mag) / np.abs(mag)) < 1e-9
    assert np.max(np.abs(last['phase_deg'] - ph)) < 1e-9 * 180
    summary = _frames(bag, '/frf/live/summary')
    assert len(summary) == 2 and summary[-1][2][1] == 3      # periods
    # the progress events with their status line are in the bag too (the layout shows them)
    estimates = [e for e in map(json.loads, _texts(bag, '/frf/progress'))
                 if e['event'] == 'estimate']
    assert [e['periods'] for e in estimates] == [2, 3]
    assert estimates[-1]['line'].startswith('multisine: 3 periods (1 realisation), worst sd ')
