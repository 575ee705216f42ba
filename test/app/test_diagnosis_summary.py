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
"""The diagnosis summary a person reads: sensible precision, units, no dict reprs."""
from pathlib import Path

from frf_ident.app.diagnosis_summary import diagnosis_summary
from frf_ident.core.diagnosis import Diagnosis, DiagnosisResult, Effect
from frf_ident.core.diagnosis.band import AnalysisBand
from frf_ident.core.diagnosis.crosscheck.checks import CrossChecks
from frf_ident.core.diagnosis.crosscheck.validation import RecordCheck
from frf_ident.core.diagnosis.records import (NotDetermined, RouteMetrics, Scores,
                                              Signature, Unexplained)
from frf_ident.core.model.schema import default_robot
import numpy as np

EFFECTS = [
    Effect('torque_ripple', 'joint_1', 0.812345,
           {'torque_ripple': [{'amplitude': 4.0123456, 'spatial_frequency': 122.34567,
                               'phase': 0.4}]}, 'evidence'),
    Effect('viscous_friction', 'joint_2', 0.5, {'viscous_friction': 51.07537008091924},
           'evidence', standard_error={'viscous_friction': 1.234567})]
UNEXPLAINED = [Unexplained('joint_3', Signature(band_hz=[34.28, 38.74],
                                                correlates_with='velocity'), misfit_share=0.314)]
NAN = float('nan')
METRICS = RouteMetrics(Scores(2.0612, 0.15712, {}), Scores(0.1512, 0.0056123, {}),
                       'held-out realisation')
OTHER = RecordCheck('b.mat', Scores(NAN, 2.0312, {}), Scores(NAN, 0.6012, {}))


def diagnosis(effects=EFFECTS, unexplained=UNEXPLAINED, band=None):
    """Return a diagnosis with the given entries (the rest is not read by the summary)."""
    res = DiagnosisResult('experiments', effects, [], unexplained, METRICS, default_robot(),
                          None, np.ones(3, bool), np.ones(3, bool), band=band)
    return Diagnosis(res, CrossChecks(validation_records=[OTHER]), None)


def test_summary_lines_read_as_sentences_with_units_and_four_digits():
    """
    Each effect named as a drives engineer says it beside its key (issue 55), wrapped.

    A line runs to 150 characters at most and breaks only between values: the score of the
    ripple goes on a continuation line, no value parts from its unit.
    """
    lines = diagnosis_summary(diagnosis(), Path('D'))
    assert lines == [
        '1. torque_ripple (position-locked torque ripple) on joint_1: torque_ripple amplitude '
        '4.012 N m, spatial_frequency 122.3 1/rad, phase 0.4 rad;',
        '      score 0.81',
        '2. viscous_friction (viscous friction) on joint_2: viscous_friction 51.08 \u00b1 1.2 '
        'N m s/rad; score 0.50',
        'unexplained on joint_3: 31 % of the nominal misfit left, strongest misfit 34.3-38.7 Hz',
        'held-out error: nominal FRF 2.06 dB, time NRMSE 0.157 -> extended FRF 0.151 dB, '
        'time NRMSE 0.00561',
        '  held-out realisation',
        'on b.mat: nominal time NRMSE 2.03 -> extended time NRMSE 0.601',
        'wrote report.json, extended_model.yaml and report.html in D']
    assert not any(c in line for line in lines for c in ('{', '}', "'"))
    assert all(len(line) <= 160 for line in lines)


def test_no_effects_is_said_in_words():
    lines = diagnosis_summary(diagnosis(effects=[], unexplained=[]), Path('D'))
    assert lines[0] == 'no effects: none of the candidates improves the held-out data'


def test_band_and_a_resonance_above_it_are_said_in_words():
    """A time-series report: its analysis band and the scan's resonance, one line each."""
    peak = Unexplained('emps', Signature(band_hz=[435.0, 450.0], peak_hz=445.0,
                                         half_power_width_hz=2.56, peak_over_floor=16.93,
                                         threshold=1.9, false_alarm=0.001),
                       kind='resonance above the analysis band')
    band = AnalysisBand(20.0, (13.7,), 250.0, 'calibrated minimum')
    lines = diagnosis_summary(diagnosis(unexplained=[peak], band=band), Path('D'))
    assert lines[3:5] == [
        'analysis band 0-20 Hz (set by the calibrated minimum); residual above it scanned for '
        'resonances',
        'unexplained on emps: resonance above the analysis band, 435-450 Hz (peak 445 Hz, 16.9x '
        'the local noise floor)']


def test_second_mode_and_its_band_before_and_after_are_said_in_words():
    """A named second mode (issue 57): its values with units, its band's error before/after."""
    from frf_ident.core.diagnosis.records import ResonanceBand
    mode = Effect('second_mode', 'joint_3', 0.9,
                  {'second_mode': {'frequency_hz': 28.16, 'damping_ratio': 0.0058,
                                   'inertia': 8.939}}, 'evidence',
                  standard_error={'second_mode': {'frequency_hz': 0.012,
                                                  'damping_ratio': 0.0004, 'inertia': 0.05}})
    bands = [ResonanceBand('joint_3', [30.13, 31.45], 'second_mode', 0.6349, 0.0001, 0.6349,
                           0.0001, 1),
             ResonanceBand('joint_1', [12.0, 14.0], 'unexplained', 0.5, 0.9, 0.7, 1.2, 3)]
    metrics = RouteMetrics(METRICS.baseline, METRICS.extended, 'held-out realisation', bands)
    res = DiagnosisResult('experiments', [mode], [], [], metrics, default_robot(), None,
                          np.ones(3, bool), np.ones(3, bool))
    diag = Diagnosis(res, CrossChecks(), None)
    lines = diagnosis_summary(diag, Path('D'))
    assert lines[0].startswith('1. second_mode (a second, link-side resonance) on joint_3: '
                               'second_mode frequency_hz 28.16')
    assert ('held-out FRF error in the band of joint_3 30.13-31.45 Hz (second_mode): 0.635 dB '
            '(95th percentile 0.635) -> 0.0001 dB (0.0001)') in lines
    assert any('joint_1 12-14 Hz (unexplained)' in x and 'worse with the extension' in x
               for x in lines)
    assert 'not an improvement: the extension is worse in a resonance band' in lines
    assert not metrics.improved and metrics.to_dict()['improved'] is False


def test_a_value_not_determined_is_said_with_its_range_unit_and_the_experiment():
    """Issue 58: a viscous friction of 334 for a true 45 is not printed as a finding."""
    loose = Effect('viscous_friction', 'joint_2', 0.0, {'viscous_friction': 333.7}, 'evidence',
                   standard_error={'viscous_friction': 180.2},
                   not_determined=[NotDetermined('viscous_friction', [0.0, 1146.0],
                                                 'standard error 180, 54 % of the value',
                                                 'a slower multisine or constant-velocity runs '
                                                 'at several speeds')])
    lines = diagnosis_summary(diagnosis(effects=[loose]), Path('D'))
    assert lines[:3] == [
        '1. viscous_friction (viscous friction) on joint_2: viscous_friction 333.7 \u00b1 '
        '1.8e+02 N m s/rad; score 0.00 (not counted as found)',
        '   viscous_friction not determined by this record: 0 to 1146 N m s/rad (standard '
        'error 180, 54 % of the value)',
        '   a slower multisine or constant-velocity runs at several speeds would determine it']
    assert all(len(line) <= 160 for line in lines)
