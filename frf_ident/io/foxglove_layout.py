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
A Foxglove layout of the live graph or a bag: live Bode with its sd band, joint signals, progress.

The Bode panels plot, per diagonal channel, the magnitude and its -/+ 2 sd band against the
frequency of the same /frf/live/frf message ("Path (current)" x axis, the
slices of frf_ident/io/live_frame.py); the phase and coherence alike. config/foxglove_layout.json
is :func:`layout` of the 3-axis models' joints (test/io/test_foxglove_layout.py keeps it so).
"""
from __future__ import annotations

import json
from typing import Any

from frf_ident.io.live_frame import FRF_QUANTITIES, LINE_SLOTS, SUMMARY_FIELDS

__all__ = ['frf_slice', 'layout', 'layout_json']


def frf_slice(channel: int, quantity: str, topic: str = '/frf/live/frf') -> str:
    """
    Return the Foxglove message path of one channel's quantity (slices include their end).

    Parameters
    ----------
    channel : int
        Index of the channel (output-major over the inputs).
    quantity : str
        One of ``FRF_QUANTITIES``.
    topic : str, optional
        The live FRF topic.

    Returns
    -------
    str

    """
    a = (channel * len(FRF_QUANTITIES) + FRF_QUANTITIES.index(quantity)) * LINE_SLOTS
    return f'{topic}.data[{a}:{a + LINE_SLOTS - 1}]'


def _xy(title: str, joints: list[str], quantities: list[str], x: str = 'freq_hz') -> dict:
    n = len(joints)
    paths = []
    for i, j in enumerate(joints):
        c = i * n + i                                  # the diagonal channel j <- j
        for q in quantities:
            paths.append({'value': frf_slice(c, q), 'enabled': True, 'label': f'{j} {q}',
                          'timestampMethod': 'receiveTime', 'showLine': True})
    return {'title': title, 'paths': paths, 'xAxisVal': 'currentCustom',
            'xAxisPath': {'value': frf_slice(0, x), 'enabled': True},
            'showLegend': True, 'legendDisplay': 'floating', 'showXAxisLabels': True,
            'showYAxisLabels': True, 'isSynced': False}


def _time(title: str, paths: list[tuple[str, str]]) -> dict:
    return {'title': title, 'paths': [{'value': v, 'enabled': True, 'label': lab,
                                       'timestampMethod': 'receiveTime'} for v, lab in paths],
            'xAxisVal': 'timestamp', 'showLegend': True, 'legendDisplay': 'floating',
            'showXAxisLabels': True, 'showYAxisLabels': True, 'isSynced': True,
            'followingViewWidth': 30}


def layout(joints: list[str]) -> dict[str, Any]:
    """
    Return the layout for a robot with these joints (in /frf/live/frf channel order).

    Parameters
    ----------
    joints : list of str
        The robot's joints, in model order.

    Returns
    -------
    dict
        Foxglove layout JSON (configById, layout tree, no variables).

    """
    worst = SUMMARY_FIELDS.index('worst_sd_db')
    cfg = {
        'Plot!bodemag': _xy('live Bode: magnitude [dB] with -/+ 2 sd vs frequency [Hz]', joints,
                            ['magnitude_db', 'band_low_db', 'band_high_db']),
        'Plot!bodephase': _xy('live Bode: phase [deg] vs frequency [Hz]', joints,
                              ['phase_deg']),
        'Plot!coherence': _xy('coherence vs frequency [Hz]', joints, ['coherence']),
        'Plot!joints': _time('joint velocity [rad/s] and torque [N m]',
                             [(f'/joint_states.velocity[{i}]', f'{j} velocity')
                              for i, j in enumerate(joints)]
                             + [(f'/joint_states.effort[{i}]', f'{j} torque')
                                for i, j in enumerate(joints)]),
        'Plot!worst': _time('worst sd [dB] per estimate',
                            [(f'/frf/live/summary.data[{worst}]', 'worst sd'),
                             (f'/frf/live/summary.data[{SUMMARY_FIELDS.index("target_sd_db")}]',
                              'target')]),
        'RawMessages!progress': {'topicPath': '/frf/progress.data', 'diffEnabled': False,
                                 'expansion': 'all'},
        'RawMessages!warnings': {'topicPath': '/frf/warnings.data', 'diffEnabled': False,
                                 'expansion': 'all'},
    }
    tree = {'direction': 'row', 'splitPercentage': 60,
            'first': {'direction': 'column', 'first': 'Plot!bodemag',
                      'second': {'direction': 'row', 'first': 'Plot!bodephase',
                                 'second': 'Plot!coherence'}},
            'second': {'direction': 'column', 'first': 'Plot!joints',
                       'second': {'direction': 'column', 'first': 'Plot!worst',
                                  'second': {'direction': 'row',
                                             'first': 'RawMessages!progress',
                                             'second': 'RawMessages!warnings'}}}}
    return {'configById': cfg, 'globalVariables': {}, 'userNodes': {},
            'playbackConfig': {'speed': 1.0}, 'layout': tree}


def layout_json(joints: list[str]) -> str:
    """Return :func:`layout` as the text of config/foxglove_layout.json."""
    return json.dumps(layout(joints), indent=2, sort_keys=True) + '\n'
