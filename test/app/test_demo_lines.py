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
The lines ``make demo`` prints after its run, read as a newcomer reads them (issue 53).

The demo's stages after the node graph (:func:`frf_ident.app.demo.estimate_and_diagnose`: the
estimate, the diagnosis and its summary) run on a bag of a scene of the independent reference
plant (test/plants/reference.py), with a friction, a ripple or a spring effect to name; the
lines they print (progress lines and the diagnosis' INFO log lines the console shows) must
give every effect parameter a unit, stay within 160 characters and never ask the user to edit
a shipped file.
"""
import logging
import re

from benchmarks.diagnosis_scene_run import identify_scene
from benchmarks.diagnosis_scenes import scene_of
from frf_ident.app.demo import DEMO_MODEL, estimate_and_diagnose
from frf_ident.app.diagnosis_summary import CONTINUED
from frf_ident.io.share import config_file
import pytest

#: the units a parameter may carry, written here, not taken from the code under test
UNITS = ('N m s/rad', 'N m/rad', 'N m', 'kg m^2', '1/rad', 'rad/s', 'rad', 's')
NUMBER = r'[-+]?\d[\d.]*(?:e[-+]?\d+)?'


def parameters_with_units(text: str) -> list[tuple[str, str, str]]:
    """Return (key, value, unit) of every 'key value [± se] unit' in an effect line's text."""
    unit = '|'.join(re.escape(u) for u in UNITS)
    return re.findall(rf'([a-z_0-9]+) ({NUMBER})(?: \u00b1 {NUMBER})? ({unit})(?=[,;]|$)', text)


def test_the_parameter_parser_sees_a_missing_unit():
    assert parameters_with_units('coulomb_friction 14.78 N m; stiffness_k2 4.4e+05 N m/rad') \
        == [('coulomb_friction', '14.78', 'N m'), ('stiffness_k2', '4.4e+05', 'N m/rad')]
    assert parameters_with_units('coulomb_friction 14.78') == []
    assert parameters_with_units('torque_ripple amplitude 3.8 N m, spatial_frequency 1453 '
                                 '1/rad') == [('amplitude', '3.8', 'N m'),
                                              ('spatial_frequency', '1453', '1/rad')]


@pytest.mark.slow
def test_demo_lines_have_units_fit_the_terminal_and_ask_no_edit(tmp_path, caplog):
    scene = scene_of(2026, 0, 'random')
    bag = identify_scene(scene, tmp_path / 'bag')
    lines: list[str] = []
    with caplog.at_level(logging.INFO, logger='frf_ident'):
        estimate_and_diagnose(bag, config_file(DEMO_MODEL), tmp_path / 'out', lines.append)
    # a message wrapped on continuation lines is read line by line, as the terminal shows it
    printed = [part for m in lines + [r.getMessage() for r in caplog.records
                                      if r.levelno >= logging.INFO]
               for part in m.split('\n')]
    print('\n'.join(printed))
    assert all(len(line) <= 160 for line in printed), max(printed, key=len)
    # an effect wrapped between its values (app/diagnosis_summary.py) is read whole
    joined = []
    for line in printed:
        if line.startswith(CONTINUED) and joined:
            joined[-1] += line[len(CONTINUED) - 1:]
        else:
            joined.append(line)
    effects = [line for line in joined if re.match(r'\d+\. \w+ \([^)]+\) on \w+: ', line)]
    assert effects, printed
    for line in effects:
        text = line.split(': ', 1)[1].rsplit('; score', 1)[0]
        found = parameters_with_units(text)
        # a unit's own digit (the 1 of 1/rad) is not a number of the line
        numbers = re.findall(rf'(?<![\w.]){NUMBER}(?!/)', text)
        # every number of the line is a parameter with its unit or its standard error
        assert found and len(found) + text.count('\u00b1') == len(numbers), line
    assert not any(re.search(r'(raise|edit|change) .*(model file|\.yaml)', line)
                   for line in printed), printed
