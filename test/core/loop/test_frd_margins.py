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
The loop search's margins against python-control, and its Nyquist count against the roots.

Truth the code under test did not produce: python-control's ``stability_margins`` on the same
FRD data (what ``loop`` and ``tune`` report), and the closed-loop poles of discrete loops
given as polynomials (roots of D + N): stable iff all inside the unit circle.
"""
import warnings

import control
from frf_ident.core.loop.check import pi_response
from frf_ident.core.loop.frd_margins import frd_margins, mimo_encirclements
from frf_ident.core.loop.notch import design_notch
import numpy as np
from scipy import signal

FS = 1000.0
F = np.geomspace(1.0, 400.0, 3000)
#: down to where every loop below has |L| > 1, up to Nyquist
WIDE = np.geomspace(0.05, 499.0, 6000)


def _plant(delay_samples: int = 3):
    """ZOH two-mass motor velocity per torque with a delay, as discrete num/den in z^-1."""
    jm, jo, k, d, bv = 35.0, 150.0, 1.5e6, 130.0, 20.0
    num = [jo, d, k]
    den = [jm * jo, jm * d + jo * d + bv * jo, jm * k + jo * k + bv * d, bv * k]
    b, a, _ = signal.cont2discrete((num, den), 1 / FS, method='zoh')
    b = np.trim_zeros(np.ravel(b), 'f')
    return np.r_[np.zeros(delay_samples), b], np.asarray(a)


def _loop(kp, ki, notch=None, freq=F):
    """Return (num, den) in z^-1 of L = PI F P and L on ``freq``."""
    b, a = _plant()
    pb, pa = [kp + ki / FS, -kp], [1.0, -1.0]           # kp + ki dt z / (z - 1), in z^-1
    nb, na = np.convolve(b, pb), np.convolve(a, pa)
    if notch is not None:
        nb, na = np.convolve(nb, notch.sos[:3]), np.convolve(na, notch.sos[3:])
    w = 2 * np.pi * freq / FS
    return nb, na, signal.freqz(nb, na, worN=w)[1]


def _stable(nb, na) -> bool:
    n = max(len(nb), len(na))
    char = np.pad(na, (0, n - len(na))) + np.pad(nb, (0, n - len(nb)))
    return bool(np.all(np.abs(np.roots(char)) < 1.0))


def test_margins_agree_with_python_control():
    rows = []
    for kp, ki, with_notch in [(1500, 6000, False), (3000, 12000, False), (5000, 20000, True),
                               (8000, 1e5, True), (800, 3000, False)]:
        notch = design_notch(36.5, 36.7, 0.011, 0.5, FS) if with_notch else None
        _, _, lo = _loop(kp, ki, notch)
        m = frd_margins(lo, F)
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')
            gm, pm, sm, _, wgc, _ = control.stability_margins(
                control.frd(lo, 2 * np.pi * F, smooth=True), method='frd')
        gm_db = 20 * np.log10(gm) if np.isfinite(gm) else np.inf
        rows.append((kp, with_notch, float(m.phase_margin_deg), pm, float(m.gain_margin_db),
                     gm_db, float(m.modulus_margin), sm))
        assert abs(m.phase_margin_deg - pm) < 0.2, rows[-1]
        assert abs(m.crossover_hz - wgc / (2 * np.pi)) < 0.005 * m.crossover_hz, rows[-1]
        assert (np.isinf(gm_db) and np.isinf(m.gain_margin_db)) or \
            abs(m.gain_margin_db - gm_db) < 0.05, rows[-1]
        assert abs(m.modulus_margin - sm) < 0.01 * sm, rows[-1]
    print('kp, notch, PM (ours, python-control), GM dB, MM:', rows)


def test_nyquist_count_matches_the_closed_loop_poles():
    verdicts = []
    for kp in [500, 1500, 3000, 5000, 8000, 12000, 20000, 40000]:
        for notch in (None, design_notch(36.5, 36.7, 0.011, 0.35, FS)):
            nb, na, lo = _loop(kp, kp * 4, notch, WIDE)
            m = frd_margins(lo, WIDE)
            assert bool(m.in_band), kp
            verdicts.append((kp, notch is not None, _stable(nb, na), bool(m.stable)))
    print('kp, notch, stable (roots), stable (count):', verdicts)
    assert all(a == b for *_, a, b in verdicts)
    assert {a for *_, a, _ in verdicts} == {True, False}          # both kinds were tested


def test_a_crossover_outside_the_band_is_not_judged():
    lo = 0.1 * pi_response(F, 1.0, 1.0, 1 / FS) / (2j * np.pi * F)   # |L| < 1 at the first line
    m = frd_margins(lo, F)
    assert not m.in_band and np.isnan(m.phase_margin_deg)


def test_mimo_count_matches_the_closed_loop_poles_of_a_coupled_pair():
    """Two axes P = p [[1, k], [k, 1]] with the same PI: det(I + P C)'s roots against the count."""
    b, a = _plant()
    w = 2 * np.pi * WIDE / FS
    p = signal.freqz(b, a, worN=w)[1]
    verdicts = []
    for k in (0.0, 0.5, 0.9):
        for kp in (1500, 5000, 12000, 20000):
            pb, pa = [kp + 4 * kp / FS, -kp], [1.0, -1.0]
            cn, cd = np.convolve(b, pb), np.convolve(a, pa)          # p C = cn / cd
            # det(I + P C) cd^2 = (cd + cn)^2 - k^2 cn^2
            n = max(len(cn), len(cd))
            cn_, cd_ = np.pad(cn, (0, n - len(cn))), np.pad(cd, (0, n - len(cd)))
            char = np.convolve(cd_ + cn_, cd_ + cn_) - k ** 2 * np.convolve(cn_, cn_)
            truth = bool(np.all(np.abs(np.roots(char)) < 1.0))
            c = signal.freqz(pb, pa, worN=w)[1]
            loop = np.array([[p * c, k * p * c], [k * p * c, p * c]])
            count = int(mimo_encirclements(loop))
            verdicts.append((k, kp, truth, count))
    print('coupling, kp, stable (roots), encirclements (count):', verdicts)
    assert all(t == (c == 0) for _, _, t, c in verdicts)
    assert {t for _, _, t, _ in verdicts} == {True, False}
