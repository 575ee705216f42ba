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
A segment the record covers only in part is left out, named; the rest is estimated.

Issue 44: ``ros2 bag record`` started while a run was under way (the transient-local
descriptors still arrive) and ``--t-range`` on the package's own bag both cut a segment, and
the whole estimate failed (``excerpt for f_x=2.376 Hz ... outside the record``, exit 2). Here
a two-realisation multisine of the simulated robot is cut inside realisation 0: the estimate
of realisation 1 must equal the estimate of a range that starts with realisation 1 (no cut
segment) and match the robot's exact sampled FRF, the cut segment named. The uncompensated
two-period multisine on the default model (with its friction) is 4.5 % off the exact FRF at
worst with both realisations, 5.4 % with one: the bound is 8 %.
"""
from __future__ import annotations

import json

from frf_ident.bag import write_recording
from frf_ident.cli import main
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.model.schema import default_model_dict, robot_from_dict
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.analytic import robot_frf_sampled
from frf_ident.core.simulation.runner import IdentificationConfig, run_identification
from frf_ident.io.model_file import load_model, load_plant
import numpy as np
import pytest

#: max relative error to the exact FRF of one uncompensated realisation (measured 5.4 %)
EXACT = 0.08
MS = MultisineConfig(n_realisations=2, n_periods=2, resolution_hz=2.0, compensate=False,
                     return_s=1.0, settle_s=0.3)


@pytest.fixture(scope='module')
def run(tmp_path_factory):
    model, _, ctrl = load_model(None)
    rec = run_identification(load_plant(None, model), ctrl, IdentificationConfig(MS, None))
    bag = write_recording(rec, tmp_path_factory.mktemp('partial') / 'bag')
    return rec, bag


def _frf(out):
    frf = json.loads((out / 'frf.json').read_text())
    return frf, np.asarray(frf['re']) + 1j * np.asarray(frf['im'])


def _exact_error(out):
    frf, g = _frf(out)
    truth = robot_frf_sampled(robot_from_dict(default_model_dict()).linear(),
                              np.asarray(frf['freq_hz']))
    d = np.arange(3)
    return frf, np.max(np.abs(g[d, d] / truth[d, d] - 1))


def _inside(rec):
    """Return realisation 0's second segment and a time a third of the way into it."""
    seg = next(s for s in rec.segments if s.info.get('realisation') == 0
               and s.info.get('experiment') == 1)
    return seg, seg.t_start + (seg.t_end - seg.t_start) / 3


def test_t_range_starting_inside_a_segment_estimates_the_rest(run, tmp_path, capsys):
    rec, bag = run
    seg, t0 = _inside(rec)
    out = tmp_path / 'e'
    assert main(['estimate', str(bag), '--out', str(out), '--t-range', str(t0),
                 str(rec.t[-1] + 1)]) == 0, capsys.readouterr().err
    said = capsys.readouterr().out
    assert f'segment {seg.t_start:.3f}..{seg.t_end:.3f} s (multisine, realisation 0, ' \
           'experiment 1) is only partly in the record' in said, said
    assert 'realisation(s) [0] cut short' in said and 'dropped for gaps ()' not in said, said
    frf, err = _exact_error(out)
    assert frf['meta']['n_p'] == 1
    assert err < EXACT, f'max relative error to the exact FRF {err:.4f}'
    r1 = min(s.t_start for s in rec.segments if s.info.get('realisation') == 1)
    clean = tmp_path / 'clean'
    assert main(['estimate', str(bag), '--out', str(clean), '--t-range', str(r1 - 0.5),
                 str(rec.t[-1] + 1)]) == 0
    np.testing.assert_allclose(_frf(out)[1], _frf(clean)[1], rtol=1e-9, atol=0)


def test_recording_started_inside_a_segment_estimates_the_rest(run, tmp_path, capsys):
    """The recorder came up late: the samples begin inside a segment whose start was sent."""
    rec, _bag = run
    seg, t0 = _inside(rec)
    k = rec.slice(t0, rec.t[-1] + 1)
    late = Recording(t=rec.t[k], joint_names=rec.joint_names, position=rec.position[k],
                     velocity=rec.velocity[k], effort=rec.effort[k],
                     reference=rec.reference[k], excitation=rec.excitation[k],
                     segments=rec.segments, meta=dict(rec.meta))
    bag = write_recording(late, tmp_path / 'late')
    out = tmp_path / 'e'
    assert main(['estimate', str(bag), '--out', str(out)]) == 0, capsys.readouterr().err
    said = capsys.readouterr().out
    assert f'segment {seg.t_start:.3f}..{seg.t_end:.3f} s' in said and 'left out' in said
    frf, err = _exact_error(out)
    assert frf['meta']['n_p'] == 1 and err < EXACT, f'max relative error {err:.4f}'
