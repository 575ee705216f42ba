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
Trust in the fits (section ``fit_trust``): errors under model error, stable order choice.

- model error: the independent reference plant (test/plants/reference.py) with a link-side
  mode the two-mass model lacks (20 Hz, 10 % of the link inertia), measured 10 times with new
  noise (test/core/fit/test_fit_physical.measure_reference); the share of the true parameters
  (five and the delay) inside 2 reported standard errors, beside the Cramer-Rao errors alone
  (the baseline: what the fit reported before the model-error bound).
- order choice: the Silverbox BLA (10 realisations) on 1-150 Hz, orders 1-12: the chosen order,
  its modes and the count of right-half-plane poles, beside the free ML fits chosen by the
  lowest AIC as before (the baseline), and its wall time beside the free fits'.
A data set missing from ../shared/data is a row saying so.
"""
from __future__ import annotations

from pathlib import Path
import sys
import time

import numpy as np

__all__ = ['rows']

ROOT = Path(__file__).resolve().parent.parent


def _model_error_row() -> tuple[str, str, str, str]:
    sys.path.insert(0, str(ROOT / 'test'))
    from core.fit.test_fit_physical import measure_reference, SECTION6
    from frf_ident.core.fit.physical import fit_two_mass, PARAMETERS
    true = np.array([SECTION6[k] for k in PARAMETERS] + [0.5e-3])
    rep, cr = [], []
    for seed in range(10):
        f, g, v = measure_reference({'frequency_hz': 20.0, 'mass_ratio': 0.1,
                                     'damping_ratio': 0.03}, seed=100 + seed)
        fit = fit_two_mass(f, g, v, delay_s=None)
        err = np.abs(np.append(fit.value, fit.delay_s) - true)
        rep.append(err <= 2 * np.append(fit.reported_std, fit.delay_reported_std_s))
        cr.append(err <= 2 * np.append(fit.std, fit.delay_std_s))
    a, b = 100 * np.mean(rep), 100 * np.mean(cr)
    return ('fit: two-mass errors under a missing mode (reference plant, 20 Hz, 10 runs x 6 '
            'parameters)', f'{a:.0f} % of true values inside 2 reported SE',
            f'Cramer-Rao alone {b:.0f} %', f'{a / max(b, 1e-9):.2g}x coverage')


def _order_row() -> tuple[str, str, str, str]:
    sys.path.insert(0, str(ROOT / 'test'))
    from core.fit.test_fit_rational import SILVERBOX, silverbox_bla
    from frf_ident.core.fit.rational import fit_rational, select_order
    if not (SILVERBOX / 'SNLS80mV.mat').is_file():
        return ('fit: Silverbox order choice', f'missing: {SILVERBOX}', '', '')
    f, g, var = silverbox_bla()
    k = (f >= 1.0) & (f <= 150.0)
    t0 = time.perf_counter()
    sel = select_order(f[k], g[k], var[k], range(1, 13))
    t1 = time.perf_counter()
    free = [fit_rational(f[k], g[k], var[k], o, stable=False) for o in range(1, 13)]
    t2 = time.perf_counter()
    old = free[int(np.argmin([x.aic for x in free]))]
    modes = ', '.join(f'{m.frequency_hz:.2f} Hz (damping {m.damping:.4f})'
                      for m in sel.best.modes() if m.damping < 1)
    return ('fit: Silverbox BLA 1-150 Hz, orders 1-12',
            f'order {sel.best.order} by the {sel.reason}: {modes}; '
            f'{int(np.sum(sel.best.poles().real >= 0))} unstable poles; {t1 - t0:.2f} s',
            f'free fits, lowest AIC: order {old.order}, '
            f'{int(np.sum(old.poles().real >= 0))} unstable poles; {t2 - t1:.2f} s',
            f'{(t1 - t0) / (t2 - t1):.2g}x time')


def rows() -> list[tuple[str, str, str, str]]:
    """Return the section's rows: model-error coverage, the Silverbox order choice."""
    return [_model_error_row(), _order_row()]
