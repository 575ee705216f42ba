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
"""flake8 with the ROS 2 configuration: through ament where ROS 2 is present, else directly."""
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    main_with_errors = pytest.importorskip('ament_flake8.main').main_with_errors
    rc, errors = main_with_errors(argv=[])
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)


@pytest.mark.flake8
def test_flake8_with_the_ament_configuration():
    """Run flake8 with setup.cfg's [flake8] (the ament_flake8 settings) without ROS 2."""
    legacy = pytest.importorskip('flake8.api.legacy')
    guide = legacy.get_style_guide(config=str(ROOT / 'setup.cfg'), quiet=1)
    paths = [str(ROOT / d) for d in ('frf_ident', 'test', 'benchmarks', 'launch', 'setup.py')]
    report = guide.check_files(paths)
    assert report.total_errors == 0, f'{report.total_errors} flake8 errors (run flake8)'
