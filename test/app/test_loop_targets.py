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
`frf-ident loop --propose` on the demo robot's FRF: each printed verdict against margins.

The FRF is the demo's: the exact sampled FRF (zero-order hold, 1 kHz) of the linear part of
config/robot_3axis_demo.yaml on the lines of the demo's multisine (53 odd lines 2.28-60.2 Hz),
with 0.5 % noise and that variance (the demo's own estimate has 0.2-0.5 % on the diagonal).
For a grid of targets the command proposes PI gains per axis and prints per axis "targets met"
or what is missed. Independently of python-control and of the code under test, numpy reads the
margins of L = (kp + ki / s) P_ii off the measured lines (scipy's cubic spline of L between
them, crossings of |L| = 1 and the phase there, the crossing of least |phase margin| as
python-control reports it, |L| at the highest line), applies the targets' tolerances and must
reach the same verdict; where its numbers lie within a hair of a tolerance the two
computations may fairly disagree and the point is not counted (printed).
"""
from __future__ import annotations

import json
from pathlib import Path
import re

from frf_ident.cli.main import main
from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.excitation.multisine import design_odd_multisine
from frf_ident.core.loop.design import CROSSOVER_TOLERANCE, PM_TOLERANCE_DEG
from frf_ident.core.simulation.analytic import robot_frf_sampled
from frf_ident.io.export import write_frf
from frf_ident.io.model_file import load_model
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
GRID = [(bw, pm) for bw in (3.0, 5.0, 10.0, 20.0, 40.0) for pm in (30.0, 60.0)]


@pytest.fixture(scope='module')
def demo_frf(tmp_path_factory):
    """Return the folder of the demo robot's noisy FRF and the FRF itself."""
    _, robot, _ = load_model(ROOT / 'config' / 'robot_3axis_demo.yaml')
    f = design_odd_multisine(2.0, 60.0, bound=0.01, resolution_hz=0.5, fs=1000.0).freq_hz
    p = robot_frf_sampled(robot, f)
    var = (0.005 * np.abs(p)) ** 2
    rng = np.random.default_rng(54)
    pn = p + np.sqrt(var / 2) * (rng.standard_normal(p.shape) + 1j * rng.standard_normal(p.shape))
    names = robot.joint_names
    d = tmp_path_factory.mktemp('demo_frf')
    write_frf(FrequencyResponse(f, pn, [f'tau_m/{n}' for n in names],
                                [f'dq_m/{n}' for n in names], total_variance=var),
              d / 'frf.json')
    return d, f, pn


def numpy_margins(f, loop):
    """
    Return (phase margin [deg], crossover [Hz], |L| at the top line [dB], grazing) by numpy.

    The loop between the lines: a cubic spline of its real and imaginary parts over
    frequency (scipy's CubicSpline; between the lines next to an antiresonance the phase turns
    by 150 deg, which linear interpolation misses), sampled 50 times per line spacing;
    crossings of |L| = 1 linearly between those samples. Grazing: |L| turns within 0.4 dB
    of 1 somewhere (whether it crosses there depends on the interpolation).
    """
    from scipy.interpolate import CubicSpline
    fine = np.concatenate([np.linspace(a, b, 50, endpoint=False) for a, b in zip(f[:-1], f[1:])]
                          + [f[-1:]])
    lf = CubicSpline(f, loop.real)(fine) + 1j * CubicSpline(f, loop.imag)(fine)
    g = np.log(np.abs(lf))
    pms, fcs = [], []
    for k in np.flatnonzero(np.sign(g[:-1]) != np.sign(g[1:])):
        t = g[k] / (g[k] - g[k + 1])
        ph = np.degrees(np.angle(lf[k] + t * (lf[k + 1] - lf[k])))
        pms.append(ph % 360.0 - 180.0)           # as python-control: in [-180, 180)
        fcs.append(fine[k] + t * (fine[k + 1] - fine[k]))
    edge = 20 * np.log10(np.abs(loop[-1]))
    turns = np.flatnonzero(np.sign(np.diff(g[:-1])) != np.sign(np.diff(g[1:]))) + 1
    grazing = bool(np.any(np.abs(g[turns]) < 0.05))
    if not pms:
        return float('nan'), float('nan'), edge, grazing
    k = int(np.argmin(np.abs(pms)))
    return pms[k], fcs[k], edge, grazing


def verdict(pm, fc, edge, grazing, bw, target, feasible):
    """Return the set of missed targets, or None where a number sits on a tolerance."""
    missed, close = set(), grazing
    if not feasible:
        missed.add('no PI')
    if edge > 0:
        missed.add('band edge')
    close |= abs(edge) < 0.2
    if not np.isfinite(pm):
        missed.add('no crossover')
    else:
        if pm < target - PM_TOLERANCE_DEG:
            missed.add('phase margin')
        close |= abs(pm - (target - PM_TOLERANCE_DEG)) < 0.5
        off = abs(fc / bw - 1)
        if off > CROSSOVER_TOLERANCE:
            missed.add('crossover')
        close |= abs(off - CROSSOVER_TOLERANCE) < 0.01
    return None if close else missed


def printed_verdicts(text):
    """Return {axis: set of missed targets} from the printed verdict lines."""
    needles = {'no PI': r'no PI reaches', 'band edge': r'at the band edge',
               'no crossover': r'no gain crossover within',
               'phase margin': r'phase margin [-0-9.e+]+ deg, [0-9.e+]+ deg below',
               'crossover': r'crossover [0-9.e+]+ Hz, [-+]\d+ % off'}
    out = {}
    for axis, rest in re.findall(r'^\s+(joint_\d): (targets met|target missed: .*)$', text,
                                 re.M):
        out[axis] = {k for k, pattern in needles.items() if re.search(pattern, rest)}
    return out


def test_every_printed_verdict_matches_the_margins_of_the_measured_frf(
        demo_frf, tmp_path, capsys):
    folder, f, p = demo_frf
    agree, skipped, missed_any, met_any = 0, 0, False, False
    for k, (bw, target) in enumerate(GRID):
        out = tmp_path / f'loop_{k}'
        assert main(['loop', str(folder), '--out', str(out), '--propose', str(bw), str(target),
                     '--draws', '0']) == 0
        said = printed_verdicts(capsys.readouterr().out)
        doc = json.loads((out / 'loop.json').read_text())
        for i, g in enumerate(doc['proposal']['gains']):
            c = g['kp'] + g['ki'] / (2j * np.pi * f)
            pm, fc, edge, grazing = numpy_margins(f, c * p[i, i])
            mine = verdict(pm, fc, edge, grazing, bw, target, g['feasible'])
            printed_pm = doc['proposal']['check']['axes'][i]['phase_margin_deg']['value']
            with capsys.disabled():
                print(f'{bw:g} Hz {target:g} deg {g["axis"]}: numpy PM {pm:.3g} deg at {fc:.3g} '
                      f'Hz, edge {edge:+.1f} dB -> '
                      f'{sorted(mine) if mine is not None else "on a tolerance"}; printed '
                      f'{sorted(said[g["axis"]])} (PM {printed_pm})')
            # console and loop.json say the same
            assert g['targets_met'] == (not said[g['axis']]) and len(g['missed']) == len(
                said[g['axis']])
            if mine is None:
                skipped += 1
                continue
            assert said[g['axis']] == mine, (bw, target, g['axis'], said, mine)
            agree += 1
            missed_any |= bool(mine)
            met_any |= not mine
    with capsys.disabled():
        print(f'{agree} verdicts agree, {skipped} on a tolerance')
    assert agree >= 0.8 * len(GRID) * 3 and missed_any and met_any
