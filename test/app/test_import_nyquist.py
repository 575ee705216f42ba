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
"""`frf-ident import` says when a detected band reaches the Nyquist line (issue 39)."""
from frf_ident.cli import main
import numpy as np
import yaml


def test_import_warns_when_the_band_reaches_nyquist(tmp_path, capsys):
    """
    A multisine on lines 60..100 of a 200-sample period at 100 Hz: 30-50 Hz.

    Before, the import printed the detection and nothing else; `estimate` then refused the
    record for its band reaching the Nyquist frequency.
    """
    fs, p = 100.0, 200
    n = np.arange(10 * p)
    lines = np.arange(60, 101)
    phases = np.random.default_rng(0).uniform(0, 2 * np.pi, lines.size)
    phases[-1] = 0.0                                    # the Nyquist line is a cosine
    tau = sum(np.cos(2 * np.pi * k * n / p + ph) for k, ph in zip(lines, phases))
    q = np.cumsum(tau) / fs
    rows = '\n'.join(f'{a / fs!r},{b!r},{c!r}'
                     for a, b, c in zip(n.tolist(), q.tolist(), tau.tolist()))
    (tmp_path / 'd.csv').write_text('t,q,tau\n' + rows + '\n')
    mp = {'frf_ident_map': 1, 'time': {'column': 't'},
          'joints': [{'name': 'j', 'position': 'q', 'effort': 'tau'}]}
    (tmp_path / 'm.yaml').write_text(yaml.safe_dump(mp))
    assert main(['import', str(tmp_path / 'd.csv'), '--map', str(tmp_path / 'm.yaml'),
                 '--out', str(tmp_path / 'bag')]) == 0
    out = capsys.readouterr().out
    print(out)
    assert 'multisine' in out
    warning = [line for line in out.splitlines() if 'warning' in line]
    assert len(warning) == 1 and 'Nyquist' in warning[0] and '50 Hz' in warning[0]
