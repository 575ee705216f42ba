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
Records the time-series diagnosis cannot judge are refused with one line (exit 2).

A robot that never moves gave "held-out NRMSE 0.0 -> 0.0" and a named load of 0.0, an
all-zero effort column an NRMSE of 3e153, a 0.1 s record a load "held out over 0.00 s", a
3-sample record a ValueError from scipy's filter (exit 1). The variants are cut from the
real EMPS record (../shared/data), whose full diagnosis is test_diagnose_real's.
"""
from __future__ import annotations

from pathlib import Path

from frf_ident.app.diagnose import load_data
from frf_ident.cli import main
from frf_ident.core.diagnosis.timeseries.diagnosable import check_diagnosable
from frf_ident.core.recording import Recording
from frf_ident.errors import EstimationError
from frf_ident.io.model_file import load_model
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]
EMPS = ROOT.parent / 'shared' / 'data' / 'EMPS' / 'DATA_EMPS.mat'
CFG = ROOT / 'config'

pytestmark = pytest.mark.skipif(not EMPS.is_file(), reason='shared EMPS data not present')


@pytest.fixture(scope='module')
def emps() -> Recording:
    return load_data(EMPS, CFG / 'map_emps.yaml')


def _variant(rec: Recording, n=None, position=None, effort=None) -> Recording:
    sl = slice(0, n or rec.t.size)
    return Recording(rec.t[sl], rec.joint_names,
                     rec.position[sl] if position is None else position[sl],
                     rec.velocity[sl] if position is None else np.zeros_like(rec.velocity[sl])
                     + np.random.default_rng(0).normal(0, 1e-4, rec.velocity[sl].shape),
                     rec.effort[sl] if effort is None else effort[sl], meta=dict(rec.meta))


def test_a_record_that_can_be_diagnosed_passes(emps):
    check_diagnosable(emps, ['emps'])
    check_diagnosable(_variant(emps, n=1500), ['emps'])          # exactly 1.5 s at 1 kHz


@pytest.mark.parametrize('kind, match', [
    ('short', r'the record holds 1499 samples \(1\.5 s\): the diagnosis needs at least 1500'),
    ('tiny', r'the record holds 3 samples'),
    ('zero effort', r'the effort of emps is 0 N m at every sample'),
    ('still', r'no axis moves in this record'),
])
def test_a_record_that_cannot_be_diagnosed_is_refused(emps, tmp_path, kind, match, capsys):
    from frf_ident.bag import write_recording
    from frf_ident.core.diagnosis.timeseries import diagnose_timeseries
    rec = {'short': lambda: _variant(emps, n=1499), 'tiny': lambda: _variant(emps, n=3),
           'zero effort': lambda: _variant(emps, effort=np.zeros_like(emps.effort)),
           'still': lambda: _variant(emps, position=0.1 + np.random.default_rng(1).normal(
               0, 1e-6, emps.position.shape))}[kind]()
    robot = load_model(CFG / 'model_emps.yaml')[1]
    with pytest.raises(EstimationError, match=match):
        diagnose_timeseries(rec, robot)
    bag = write_recording(rec, tmp_path / 'bag')
    assert main(['diagnose', str(bag), '--model', str(CFG / 'model_emps.yaml'),
                 '--out', str(tmp_path / 'd')]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'Traceback' not in err[0], err
    assert not (tmp_path / 'd' / 'report.json').exists()


def test_a_model_sampled_at_another_rate_is_named_and_the_record_rate_written(emps, tmp_path):
    """A model at 500 Hz on the 1 kHz record: a line says so; extended_model.yaml has 1000."""
    from frf_ident.app.diagnose import diagnose
    from frf_ident.bag import write_recording
    import yaml
    model = yaml.safe_load((CFG / 'model_emps.yaml').read_text())
    model['sample_rate'] = 500.0
    path = tmp_path / 'm500.yaml'
    path.write_text(yaml.safe_dump(model))
    bag = write_recording(_variant(emps, n=6000), tmp_path / 'bag')
    lines = []
    diagnose(bag, path, tmp_path / 'd', progress=lines.append)
    said = [t for t in lines if 'sample_rate 500 Hz' in t]
    assert len(said) == 1 and 'sampled at 1000 Hz' in said[0], lines
    written = yaml.safe_load((tmp_path / 'd' / 'extended_model.yaml').read_text())
    assert written['sample_rate'] == 1000.0
