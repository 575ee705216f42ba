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
"""The diagnosis summary a person reads: sensible precision, no dict reprs."""
from pathlib import Path

from frf_ident.app.diagnosis_summary import diagnosis_summary

REPORT = {
    'effects': [
        {'name': 'torque_ripple', 'axis': 'joint_1', 'score': 0.812345,
         'parameters': {'torque_ripple': [{'amplitude': 4.0123456, 'spatial_frequency': 122.34567,
                                           'phase': 0.4}]}},
        {'name': 'viscous_friction', 'axis': 'joint_2', 'score': 0.5,
         'parameters': {'viscous_friction': 51.07537008091924},
         'standard_error': {'viscous_friction': 1.234567}}],
    'unexplained': [{'axis': 'joint_3', 'misfit_share': 0.314,
                     'signature': {'band_hz': [34.28, 38.74], 'correlates_with': 'velocity'}}],
    'metrics': {'baseline': {'frf_error_db': 2.0612, 'time_nrmse': 0.15712},
                'extended': {'frf_error_db': 0.1512, 'time_nrmse': 0.0056123},
                'validation': 'held-out realisation',
                'validation_records': [{'record': 'b.mat', 'baseline': {'time_nrmse': 2.0312},
                                        'extended': {'time_nrmse': 0.6012}}]}}


def test_summary_lines_read_as_sentences_with_four_digits():
    lines = diagnosis_summary(REPORT, Path('D'))
    assert lines == [
        '1. torque_ripple on joint_1: torque_ripple amplitude 4.012, spatial_frequency 122.3, '
        'phase 0.4; score 0.81',
        '2. viscous_friction on joint_2: viscous_friction 51.08 (standard error viscous_friction '
        '1.235); score 0.50',
        'unexplained on joint_3: 31 % of the nominal misfit left, strongest misfit 34.3-38.7 Hz',
        'held-out error: nominal FRF 2.06 dB, time NRMSE 0.157 -> extended FRF 0.151 dB, '
        'time NRMSE 0.00561 (held-out realisation)',
        'on b.mat: nominal time NRMSE 2.03 -> extended time NRMSE 0.601',
        'wrote D/report.json, D/extended_model.yaml, D/report.html']
    assert not any(c in line for line in lines for c in ('{', '}', "'"))


def test_no_effects_is_said_in_words():
    lines = diagnosis_summary(dict(REPORT, effects=[], unexplained=[]), Path('D'))
    assert lines[0] == 'no effects: none of the candidates improves the held-out data'


def test_band_and_a_resonance_above_it_are_said_in_words():
    """A time-series report: its analysis band and the scan's resonance, one line each."""
    report = dict(REPORT, analysis_band={'fc_hz': 20.0, 'motion_hz': [13.7], 'limit_hz': 250.0,
                                         'set_by': 'calibrated minimum'},
                  unexplained=[{'axis': 'emps', 'kind': 'resonance above the analysis band',
                                'signature': {'band_hz': [435.0, 450.0], 'peak_hz': 445.0,
                                              'half_power_width_hz': 2.56,
                                              'peak_over_floor': 16.93, 'threshold': 1.9,
                                              'false_alarm': 0.001}}])
    lines = diagnosis_summary(report, Path('D'))
    assert lines[2:4] == [
        'analysis band 0-20 Hz (set by the calibrated minimum); residual above it scanned for '
        'resonances',
        'unexplained on emps: resonance above the analysis band, 435-450 Hz (peak 445 Hz, 16.9x '
        'the local noise floor)']
