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
Real measured data through the user's commands: FRF, coherence and uncertainty, with figures.

Each data set of ../shared/data is imported with its map in config/ and estimated by
``frf-ident estimate`` as a user would (the command is in the row). Rows: the estimator the
route chose and its median relative standard deviation over the excited lines, beside the
Welch H1 baseline and its median multiple coherence there. The Bode figures (with the
coherence panel) are copied to docs/benchmarks/img/real_data_<set>.png, which the page shows
under the table. A data set missing from ../shared/data is a row saying so.
"""
from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path
import shutil
import tempfile

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT.parent / 'shared' / 'data'
#: (set, data file, map, estimate options): the commands of docs/LPM.md
SETS = (
    ('daisy_arm', 'DaISy_robot_arm/robot_arm.dat', 'config/map_daisy_arm.yaml',
     ['--window', '2000']),
    ('emps', 'EMPS/DATA_EMPS.mat', 'config/map_emps.yaml', []),
    ('kuka_kr300_A', 'KUKA_KR300_Weigand2021/recorded_FF_A_2020-10-21.mat',
     'config/map_kuka_kr300.yaml', ['--method', 'lpm-direct', '--joints', 'a1,a2,a3']),
)


def _run(argv: list[str]) -> None:
    from frf_ident.cli import main
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        rc = main(['-q', *argv])
    if rc != 0:
        raise RuntimeError(f'frf-ident {" ".join(argv)} exited {rc}')


def _relative_sd(est: dict) -> float:
    p = np.asarray(est['re']) + 1j * np.asarray(est['im'])
    var = np.asarray(est.get('noise_variance') or np.full(p.shape, np.nan))
    n = min(p.shape[0], p.shape[1])
    rel = [np.sqrt(var[k, k]) / np.abs(p[k, k]) for k in range(n)]   # driven channels
    return float(np.nanmedian(np.concatenate(rel)))


def one_set(name: str, data: Path, mapping: str, options: list[str], work: Path,
            img: Path) -> tuple[str, str, str, str]:
    """Import and estimate one data set; copy its Bode figure; return its row."""
    bag, out = work / f'{name}_bag', work / name
    cmd = (f'frf-ident import ../{data.relative_to(ROOT.parent)} --map {mapping} --out BAG && '
           f'frf-ident estimate BAG {" ".join(options)}'.rstrip())
    _run(['import', str(data), '--map', str(ROOT / mapping), '--out', str(bag)])
    _run(['estimate', str(bag), '--out', str(out), *options])
    est = json.loads((out / 'estimates.json').read_text())
    primary = json.loads((out / 'frf.json').read_text()).get('estimate', next(iter(est)))
    p = est[primary]
    rel = _relative_sd(p)
    h1 = est.get('lpm_h1')
    if h1 is not None:
        coh = np.asarray(h1['meta']['coherence'])[:, np.asarray(h1['meta']['excited'])]
        per = np.median(coh, axis=1)
        base = (f'Welch H1 median multiple coherence {np.median(coh):.2f} (per output '
                f'{per.min():.2f}-{per.max():.2f}) over its excited lines')
    else:
        base = 'no Welch H1 (periodic route)'
    img.mkdir(parents=True, exist_ok=True)
    shutil.copy(out / 'bode.png', img / f'real_data_{name}.png')
    shape = f"{len(p['outputs'])}x{len(p['inputs'])}"
    return (f'{name}: `{cmd}`',
            f'{primary} {shape}, {len(p["freq_hz"])} lines, median relative SD {100 * rel:.2g} %',
            base, '')


def rows(img: Path | None = None) -> list[tuple[str, str, str, str]]:
    """Run every data set of :data:`SETS` present in ../shared/data."""
    img = img or ROOT / 'docs' / 'benchmarks' / 'img'
    out = []
    with tempfile.TemporaryDirectory(prefix='frf_real_') as tmp:
        for name, rel, mapping, options in SETS:
            data = DATA / rel
            if not data.is_file():
                out.append((name, f'missing: {data}', '', ''))
                continue
            out.append(one_set(name, data, mapping, options, Path(tmp), img))
    return out
