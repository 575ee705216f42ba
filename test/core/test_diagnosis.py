"""Diagnosis on synthetic data: one hidden effect per seed (all seven), two at once, clean."""
import numpy as np
import pytest

from frf_ident.core.diagnosis import EFFECTS
from frf_ident.core.model.schema import robot_from_dict
from benchmarks.diagnosis import NOMINAL_1AXIS, draw_effect, param_error, run_case

AXIS = robot_from_dict(NOMINAL_1AXIS).axes[0]


@pytest.mark.parametrize('k, name', list(enumerate(EFFECTS)))
def test_hidden_effect_ranked_first(k, name):
    hidden = draw_effect(name, np.random.default_rng(2024 + k), AXIS)
    res = run_case(hidden, seed=k)
    eff = res['effects']
    assert eff and eff[0].name == name, (hidden, [(e.name, e.gain) for e in eff])
    assert param_error(name, hidden, eff[0].parameters) < 0.2, (hidden, eff[0].parameters)
    m = res['metrics']
    assert m['extended']['frf_error_db'] <= m['baseline']['frf_error_db'] + 1e-9
    assert (m['extended']['frf_error_db'] < m['baseline']['frf_error_db']
            or m['extended']['time_nrmse'] < m['baseline']['time_nrmse'])
    assert eff[0].evidence and 0 < eff[0].score <= 1


def test_clean_data_gives_no_effects():
    res = run_case({}, seed=11)
    assert res['effects'] == []


def test_two_effects_both_in_top_three():
    rng = np.random.default_rng(7)
    hidden = {**draw_effect('coulomb_friction', rng, AXIS), **draw_effect('time_delay', rng, AXIS)}
    names = [e.name for e in run_case(hidden, seed=5)['effects'][:3]]
    assert 'coulomb_friction' in names and 'time_delay' in names, names
