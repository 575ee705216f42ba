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
"""`diagnose --no-fd-fit` reaches the diagnosis as ``fd_fit=False``; stage 0 runs by default."""
import argparse

from frf_ident.cli import diagnose as cli
import pytest


class _Called(Exception):
    pass


@pytest.mark.parametrize('flag, expected', [([], True), (['--no-fd-fit'], False)])
def test_the_flag_is_passed_to_the_diagnosis(flag, expected, tmp_path, monkeypatch):
    import frf_ident.app.diagnose as app

    def fake(*_a, **kw):
        raise _Called(kw)
    monkeypatch.setattr(app, 'diagnose', fake)
    p = argparse.ArgumentParser()
    cli.add_arguments(p)
    args = p.parse_args([str(tmp_path / 'bag'), '--model', 'm.yaml', '--out',
                         str(tmp_path / 'out')] + flag)
    with pytest.raises(_Called) as got:
        cli.run(args)
    assert got.value.args[0]['fd_fit'] is expected
