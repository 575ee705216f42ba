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
"""config/foxglove_layout.json: valid JSON, up to date, naming only what the nodes publish."""
from __future__ import annotations

import json
from pathlib import Path
import re

from frf_ident.io.foxglove_layout import layout_json
from frf_ident.io.live_frame import FRF_QUANTITIES, LINE_SLOTS, SUMMARY_FIELDS
from frf_ident.nodes.common import LIVE_FRAMES, TOPICS

ROOT = Path(__file__).resolve().parents[2]
LAYOUT = ROOT / 'config' / 'foxglove_layout.json'
JOINTS = ['joint_1', 'joint_2', 'joint_3']
#: the fields of the message types the nodes publish on those topics (std_msgs, sensor_msgs)
FIELDS = {'std_msgs/msg/Float64MultiArray': {'data', 'layout'},
          'sensor_msgs/msg/JointState': {'header', 'name', 'position', 'velocity', 'effort'},
          'std_msgs/msg/String': {'data'}}


def _published() -> dict[str, str]:
    """Topic -> type of everything the nodes publish (their defaults)."""
    out = {TOPICS[k]: 'sensor_msgs/msg/JointState'
           for k in ('joint_states_topic', 'excitation_topic')}
    out.update({TOPICS[k]: 'std_msgs/msg/Float64MultiArray'
                for k in ('velocity_topic', 'effort_topic')})
    out.update({TOPICS[k]: 'std_msgs/msg/String'
                for k in ('experiment_topic', 'progress_topic', 'warnings_topic')})
    out.update({f'{TOPICS["live_topic"]}/{k}': 'std_msgs/msg/Float64MultiArray'
                for k in LIVE_FRAMES})
    return out


def _paths(node):
    if isinstance(node, dict):
        for k, v in node.items():
            if k in ('value', 'topicPath') and isinstance(v, str):
                yield v
            else:
                yield from _paths(v)
    elif isinstance(node, list):
        for v in node:
            yield from _paths(v)


def test_layout_is_valid_json_and_up_to_date():
    text = LAYOUT.read_text()
    json.loads(text)
    assert text == layout_json(JOINTS), 'regenerate with frf_ident.io.foxglove_layout'


def test_layout_names_only_published_topics_and_fields():
    pub = _published()
    paths = list(_paths(json.loads(LAYOUT.read_text())))
    assert len(paths) >= 10
    sizes = {'/frf/live/frf': 9 * len(FRF_QUANTITIES) * LINE_SLOTS,
             '/frf/live/summary': len(SUMMARY_FIELDS)}
    for p in paths:
        m = re.fullmatch(r'(/[\w/]+)\.(\w+)(?:\[(\d+)(?::(\d+))?\])?', p)
        assert m, p
        topic, field, a, b = m.groups()
        assert topic in pub, f'{p}: {topic} is not published'
        assert field in FIELDS[pub[topic]], f'{p}: {pub[topic]} has no {field}'
        if topic in sizes and a is not None:
            assert int(b or a) < sizes[topic], p
    # every live frame the Bode reads, and the joint signals and progress
    assert {'/frf/live/frf', '/joint_states', '/frf/progress', '/frf/warnings'} <= \
        {re.match(r'(/[\w/]+)', p).group(1) for p in paths}
