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
Bad map and model files: one line naming the file, field and value (CLI exit status 2).

Non-UTF-8 files, quoted booleans, negative or fractional indices and integers, duplicate axis
names, unknown keys and units, and the wording of time, scale, symmetry and struct errors.
"""
from pathlib import Path

from frf_ident.cli.main import main
from frf_ident.errors import FrfIdentInputError, ModelFileError
from frf_ident.io.import_map import load_map
from frf_ident.io.importer import import_table
from frf_ident.io.model_file import load_model
import numpy as np
import pytest
from scipy.io import savemat

ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / 'config' / 'model_3axis.yaml'

CSV = 't,q,tau\n' + ''.join(f'{k * 0.001:.3f},{k},{2 * k}\n' for k in range(8))
MAP = ('frf_ident_map: 1\ntime: {column: t}\njoints:\n  - name: j\n'
       '    position: {column: q}\n    effort: {column: tau}\n')


def _one_line(exc: pytest.ExceptionInfo, *needles: str) -> str:
    msg = str(exc.value)
    assert '\n' not in msg, msg
    for needle in needles:
        assert needle in msg, msg
    return msg


def _files(tmp_path, map_text: str, csv_text: str = CSV) -> tuple[Path, Path]:
    (tmp_path / 'd.csv').write_text(csv_text, encoding='utf-8')
    (tmp_path / 'm.yaml').write_text(map_text, encoding='utf-8')
    return tmp_path / 'd.csv', tmp_path / 'm.yaml'


def _mat_refused(tmp_path, variables: dict, map_spec, *needles: str) -> str:
    """Import a MAT file of ``variables`` with ``map_spec`` (text or dict): one-line refusal."""
    savemat(tmp_path / 'd.mat', variables)
    if isinstance(map_spec, str):
        (tmp_path / 'm.yaml').write_text(map_spec, encoding='utf-8')
        map_spec = tmp_path / 'm.yaml'
    with pytest.raises(FrfIdentInputError) as exc:
        import_table(tmp_path / 'd.mat', map_spec)
    return _one_line(exc, *needles)


def _model(tmp_path, old: str, new: str) -> Path:
    text = MODEL.read_text(encoding='utf-8')
    assert old in text
    p = tmp_path / 'model.yaml'
    p.write_text(text.replace(old, new, 1), encoding='utf-8')
    return p


# ------------------------------------------------------------------ 1: not UTF-8

@pytest.mark.parametrize('blob, byte', [(b'# angle in \xb0 (Latin-1)\n', '0xb0'),
                                        (b'\x89PNG\r\n\x1a\n\xff\xfe\x00', '0x89')])
def test_map_not_utf8_is_one_line_exit_2(tmp_path, capsys, blob, byte):
    data, mp = _files(tmp_path, MAP)
    mp.write_bytes(blob + MAP.encode())
    assert main(['import', str(data), '--map', str(mp), '--out', str(tmp_path / 'b')]) == 2
    err = capsys.readouterr().err.strip()
    assert '\n' not in err and 'm.yaml' in err and 'not UTF-8' in err and byte in err, err
    assert 'UnicodeDecodeError' not in err and not (tmp_path / 'b').exists()


def test_model_not_utf8_names_file(tmp_path):
    p = tmp_path / 'model.yaml'
    p.write_bytes(b'# stiffness in N m/\xb0\n' + MODEL.read_bytes())
    with pytest.raises(ModelFileError) as exc:
        load_model(p)
    _one_line(exc, 'model.yaml', 'not UTF-8', '0xb0', 'offset 19')


def test_model_binary_control_characters_one_line(tmp_path):
    p = tmp_path / 'model.yaml'
    p.write_bytes(b'frf_ident_model: 1\x00\x01\n')
    with pytest.raises(ModelFileError) as exc:
        load_model(p)
    _one_line(exc, 'model.yaml', 'not valid YAML')


# ------------------------------------------------------------------ 2: booleans

def test_map_quoted_derivative_refused(tmp_path):
    data, mp = _files(tmp_path, MAP.replace('{column: q}', '{column: q, derivative: "false"}'))
    with pytest.raises(FrfIdentInputError) as exc:
        import_table(data, mp)
    _one_line(exc, 'm.yaml', 'position.derivative', "'false'", 'expected true or false')


def test_map_real_boolean_derivative_accepted(tmp_path):
    data, mp = _files(tmp_path, MAP.replace('{column: q}', '{column: q, derivative: false}'))
    rec = import_table(data, mp)
    assert 'j.position' not in rec.meta['import']['derived']


def test_map_quoted_csv_header_refused(tmp_path):
    data, mp = _files(tmp_path, 'csv: {header: "no"}\n' + MAP)
    with pytest.raises(FrfIdentInputError) as exc:
        import_table(data, mp)
    _one_line(exc, 'm.yaml', 'csv.header', "'no'", 'expected true or false')


def test_model_quoted_velocity_from_encoder_refused(tmp_path):
    p = _model(tmp_path, 'velocity_from_encoder: false', 'velocity_from_encoder: "false"')
    with pytest.raises(ModelFileError) as exc:
        load_model(p)
    _one_line(exc, 'model.yaml', 'simulation.velocity_from_encoder', "'false'",
              'expected true or false')


# ------------------------------------------------------------------ 3: negative row/col

def test_map_negative_row_refused(tmp_path):
    _mat_refused(tmp_path, {'t': np.arange(50) * 0.01, 'm': np.ones((6, 50))},
                 'frf_ident_map: 1\ntime: {variable: t}\njoints:\n  - name: a\n'
                 '    position: {variable: m, row: 0}\n    effort: {variable: m, row: -6}\n',
                 'm.yaml', 'effort.row', '-6', '>= 0')


def test_map_negative_col_refused_in_dict_map(tmp_path):
    mp = {'frf_ident_map': 1, 'time': {'variable': 't'},
          'joints': [{'name': 'a', 'position': {'variable': 'm', 'col': 0},
                      'effort': {'variable': 'm', 'col': -1}}]}
    _mat_refused(tmp_path, {'t': np.arange(50) * 0.01, 'm': np.ones((50, 3))}, mp,
                 'effort.col', '-1')


# ------------------------------------------------------------------ 4: duplicate axes

def test_model_duplicate_axis_name_refused(tmp_path):
    p = _model(tmp_path, 'name: joint_2', 'name: joint_1')
    with pytest.raises(ModelFileError) as exc:
        load_model(p)
    _one_line(exc, 'model.yaml', "'joint_1'", 'twice')


# ------------------------------------------------------------------ 5: integers, keys, units

def test_model_negative_seed_refused_at_load(tmp_path, capsys):
    p = _model(tmp_path, 'seed: 0', 'seed: -4')
    with pytest.raises(ModelFileError) as exc:
        load_model(p)
    _one_line(exc, 'model.yaml', 'simulation.seed', '-4')
    assert main(['identify', '--model', str(p), '--out', str(tmp_path / 'b')]) == 2
    err = capsys.readouterr().err.strip()
    assert '\n' not in err and 'simulation.seed' in err and 'ValueError' not in err, err


@pytest.mark.parametrize('value, shown', [('1.7', '1.7'), ('"2"', "'2'"), ('true', 'True'),
                                          ('0', '0')])
def test_model_substeps_must_be_a_positive_integer(tmp_path, value, shown):
    p = _model(tmp_path, 'substeps: 1', f'substeps: {value}')
    with pytest.raises(ModelFileError) as exc:
        load_model(p)
    _one_line(exc, 'model.yaml', 'simulation.substeps', f'got {shown}', 'integer >= 1')


def test_model_unknown_simulation_key_refused(tmp_path):
    p = _model(tmp_path, 'seed: 0', 'seed: 0, sed: 3')
    with pytest.raises(ModelFileError) as exc:
        load_model(p)
    _one_line(exc, 'model.yaml', 'simulation', "'sed'")


def test_map_unknown_csv_key_refused(tmp_path):
    data, mp = _files(tmp_path, 'csv: {delimiter: ",", heder: true}\n' + MAP)
    with pytest.raises(FrfIdentInputError) as exc:
        load_map(mp)
    _one_line(exc, 'm.yaml', 'csv', "'heder'")


def test_map_unknown_unit_refused(tmp_path):
    data, mp = _files(tmp_path, MAP + '    units: {effort: parsecs}\n')
    with pytest.raises(FrfIdentInputError) as exc:
        load_map(mp)
    _one_line(exc, 'm.yaml', 'units.effort', "'parsecs'", 'N m')
    data, mp = _files(tmp_path, MAP + '    units: {torque: N m}\n')
    with pytest.raises(FrfIdentInputError) as exc:
        load_map(mp)
    _one_line(exc, 'm.yaml', 'units', "'torque'")
    data, mp = _files(tmp_path, MAP + '    units: {position: rad, velocity: rad/s, '
                                      'effort: N m}\n')
    assert import_table(data, mp).meta['units'] == {
        'j': {'position': 'rad', 'velocity': 'rad/s', 'effort': 'N m'}}


# ------------------------------------------------------------------ 6: messages

def test_non_increasing_time_plain_numbers_and_field(tmp_path):
    csv_text = 't,q,tau\n0,0,0\n0.001,1,1\n0.002,2,2\n0.0015,3,3\n0.004,4,4\n'
    data, mp = _files(tmp_path, MAP, csv_text)
    with pytest.raises(FrfIdentInputError) as exc:
        import_table(data, mp)
    msg = _one_line(exc, 'm.yaml', "column 't'", 'does not increase at sample 3',
                    '0.002', '0.0015')
    assert 'np.float64' not in msg


def test_nan_scale_variable_says_not_finite(tmp_path):
    mp = {'frf_ident_map': 1, 'time': {'variable': 't'},
          'joints': [{'name': 'a', 'position': 'x',
                      'effort': {'variable': 'x', 'scale': 'gain'}}]}
    msg = _mat_refused(tmp_path, {'t': np.arange(50) * 0.01, 'x': np.ones(50), 'gain': np.nan},
                       mp, "'gain'", 'not finite', 'nan')
    assert 'shape' not in msg


def test_link_coupling_not_symmetric_says_so(tmp_path):
    p = _model(tmp_path, '[12.0, 0.0, 35.0]', '[12.5, 0.0, 35.0]')
    with pytest.raises(ModelFileError) as exc:
        load_model(p)
    msg = _one_line(exc, 'model.yaml', 'link_coupling', 'not symmetric', '12.5')
    assert 'shape' not in msg


def test_csv_with_utf8_bom_reads(tmp_path):
    data, mp = _files(tmp_path, MAP)
    data.write_bytes(b'\xef\xbb\xbf' + CSV.encode())
    rec = import_table(data, mp)
    assert rec.t.size == 8 and rec.effort[-1, 0] == 14


def test_path_into_non_struct_says_not_a_struct(tmp_path):
    mp = {'frf_ident_map': 1, 'time': {'variable': 'rec.t'},
          'joints': [{'name': 'a', 'position': {'variable': 'rec.m', 'row': 0},
                      'effort': {'variable': 'rec.m.foo', 'row': 0}}]}
    msg = _mat_refused(tmp_path, {'rec': {'t': np.arange(50) * 0.01, 'm': np.ones((2, 50))}},
                       mp, "'rec.m.foo'", 'rec.m is not a struct', "'foo'")
    assert 'it has )' not in msg


# ------------------------------------------------------------------ 7: 1 x N MAT variables

def test_row_0_of_a_1xn_and_col_0_of_an_nx1_variable(tmp_path):
    n = 64
    savemat(tmp_path / 'd.mat', {'V1': np.sin(np.arange(n))[None, :],
                                 'V2': np.cos(np.arange(n))[:, None]})
    mp = {'frf_ident_map': 1, 'time': {'sample_time': 0.01},
          'joints': [{'name': 'a', 'effort': {'variable': 'V1', 'row': 0},
                      'velocity': {'variable': 'V2', 'col': 0}}]}
    rec = import_table(tmp_path / 'd.mat', mp)
    np.testing.assert_allclose(rec.effort[:, 0], np.sin(np.arange(n)))
    np.testing.assert_allclose(rec.velocity[:, 0], np.cos(np.arange(n)))
    mp['joints'][0]['effort']['row'] = 1
    with pytest.raises(FrfIdentInputError) as exc:
        import_table(tmp_path / 'd.mat', mp)
    _one_line(exc, 'row=1', 'out of range')


@pytest.mark.parametrize('args, match', [
    (['identify', '--seed', '-1', '--procedures', 'multisine'], 'seed=-1 must be at least 0'),
    (['reproduce', 'paper', '--seed', '-1'], '--seed -1: expected an integer >= 0'),
    (['identify', '--plant', 'os:path'], "'path' is a module, not a class taking the model"),
    (['estimate', 'any_bag', '--window', '0'], '--window 0.0: expected a block length in s > 0'),
])
def test_cli_values_a_user_could_type_are_refused_with_one_line(args, match, tmp_path, capsys):
    """A negative seed and a --plant that is no class exited 1 (ValueError, TypeError)."""
    assert main(args + ['--out', str(tmp_path / 'o')]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and match in err[0], err
    assert not (tmp_path / 'o').exists()


def test_every_option_has_help_and_validate_takes_several_records():
    """--help showed bare options; ``--validate a b`` was refused as an unknown argument."""
    import argparse

    from frf_ident.cli.main import build_parser
    p = build_parser()
    sub = next(a for a in p._actions if isinstance(a, argparse._SubParsersAction))
    bare = [f'{name} {a.option_strings[0]}' for name, sp in sub.choices.items()
            for a in sp._actions if a.option_strings and a.help is None]
    assert bare == [], bare
    args = p.parse_args(['diagnose', 'D', '--model', 'm', '--out', 'o', '--validate', 'a', 'b',
                         '--validate', 'c'])
    assert [str(v) for v in args.validate] == ['a', 'b', 'c']


def test_complex_mat_variable_refused(tmp_path):
    """Its imaginary part was dropped with a numpy ComplexWarning and exit 0."""
    _mat_refused(tmp_path, {'t': np.arange(50) * 0.01, 'q': np.ones(50) * (1 + 2j),
                            'u': np.ones(50)},
                 'frf_ident_map: 1\ntime: {variable: t}\njoints:\n  - name: a\n'
                 '    position: {variable: q}\n    effort: {variable: u}\n',
                 'm.yaml', 'position', "variable='q'", 'is complex')
