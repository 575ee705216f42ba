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
"""Report values for a person: what the HTML tables and the command line show."""
from frf_ident.report.text import plain


def test_plain_writes_names_and_four_digits_not_reprs():
    ripple = {'torque_ripple': [{'amplitude': 4.0123456, 'spatial_frequency': 122.34567,
                                 'phase': 0.324358}]}
    assert plain(ripple) == 'torque_ripple amplitude 4.012, spatial_frequency 122.3, phase 0.3244'
    assert plain({'stiffness_k2': 445094.0, 'stiffness_breakpoint': 0.000401141}) == \
        'stiffness_k2 4.451e+05, stiffness_breakpoint 0.0004011'
    assert plain([1.23456, 2.0]) == '[1.235, 2]'
    assert plain({'gravity': None, 'ok': True}) == 'gravity None, ok True'
