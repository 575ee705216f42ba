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
"""Import of CSV/MAT tables with map files, incl. the real EMPS and KUKA KR300 data sets."""
from pathlib import Path
import subprocess
import sys

from frf_ident.bag import read_recording
from frf_ident.cli import main
from frf_ident.core.excitation.detect import detect_excitation
from frf_ident.errors import FrfIdentInputError
from frf_ident.io.import_map import load_map
from frf_ident.io.importer import import_table
import numpy as np
import pytest
from scipy import signal
from scipy.io import loadmat, savemat
import yaml

ROOT = Path(__file__).resolve().parents[2]
SHARED_DATA = ROOT.parent / 'shared' / 'data'

EMPS = SHARED_DATA / 'EMPS' / 'DATA_EMPS.mat'
KUKA = SHARED_DATA / 'KUKA_KR300_Weigand2021' / 'recorded_FF_A_2020-10-21.mat'
EMPS_MAP = ROOT / 'config' / 'map_emps.yaml'
KUKA_MAP = ROOT / 'config' / 'map_kuka_kr300.yaml'
needs_data = pytest.mark.skipif(not (EMPS.is_file() and KUKA.is_file()),
                                reason='shared data sets not available')


# --------------------------------------------------------------------------- real data

@needs_data
def test_emps_units_reproduce_authors_rigid_body_model():
    """IDIM-LS on the imported force and derived velocity gives the authors' M, Fv, Fc."""
    rec = import_table(EMPS, EMPS_MAP)
    raw = loadmat(EMPS)
    assert rec.joint_names == ['emps'] and rec.t.size == 24841
    assert rec.dt == pytest.approx(1e-3, rel=1e-12) and rec.t[-1] == pytest.approx(24.84)
    np.testing.assert_allclose(rec.effort[:, 0], 35.15065188 * raw['vir'][:, 0], rtol=1e-8)
    assert rec.meta['import']['derived']['emps.velocity'] == 'central differences of position'
    assert np.abs(rec.velocity).max() == pytest.approx(0.128, abs=0.001)   # SOURCE.md
    b, a = signal.butter(4, 100, fs=rec.fs)
    v = signal.filtfilt(b, a, rec.velocity[:, 0])
    x = np.column_stack([np.gradient(v, rec.dt), v, np.sign(v), np.ones_like(v)])
    b, a = signal.butter(4, 20, fs=rec.fs)
    xf = signal.filtfilt(b, a, x, axis=0)[::10]
    yf = signal.filtfilt(b, a, rec.effort[:, 0])[::10]
    m, fv, fc, off = np.linalg.lstsq(xf, yf, rcond=None)[0]
    assert m == pytest.approx(95.11, rel=0.03)        # authors: M = 95.11 kg
    assert fv == pytest.approx(203.5, rel=0.05)       # Fv = 203.5 N s/m
    assert fc == pytest.approx(20.39, rel=0.1)        # Fc = 20.39 N
    assert off == pytest.approx(-3.16, abs=0.3)       # offset = -3.16 N


@needs_data
def test_emps_reference_is_periodic():
    """The EMPS reference repeats every 6.24 s (3 whole periods, odd harmonics only)."""
    rec = import_table(EMPS, EMPS_MAP)
    det = detect_excitation(rec.reference[:, 0], rec.fs)
    assert det.kind == 'multisine' and det.period_samples == 6240 and det.n_periods == 3
    assert det.odd and det.start == 0


@needs_data
def test_kuka_kr300_six_axes_consistent_units():
    rec = import_table(KUKA, KUKA_MAP)
    raw = loadmat(KUKA, squeeze_me=True, struct_as_record=False)['rec']
    assert rec.joint_names == ['a1', 'a2', 'a3', 'a4', 'a5', 'a6']
    assert rec.t.size == 2501 and rec.dt == pytest.approx(4e-3, rel=1e-12)
    assert rec.meta['import']['derived'] == {}
    np.testing.assert_allclose(rec.effort.T, raw.act_torque_abs_nm, rtol=1e-12)
    np.testing.assert_allclose(np.degrees(rec.position.T), raw.act_pos_mot_deg, rtol=1e-12)
    # the mapped velocity [rad/s] is the central difference of the mapped position [rad]
    # one sample (4 ms) late: v[k] = (q[k] - q[k-2]) / (2 dt)
    rms = lambda x: np.sqrt(np.mean(x ** 2, axis=0))  # noqa: E731
    late = (rec.position[2:] - rec.position[:-2]) / (2 * rec.dt)
    assert np.all(rms(late - rec.velocity[2:]) < 0.003 * rms(rec.velocity))
    central = np.gradient(rec.position, rec.dt, axis=0)
    assert np.all(rms(central - rec.velocity) < 0.02 * rms(rec.velocity))
    assert np.degrees(np.abs(rec.velocity[:, :3]).max()) == pytest.approx(25.3, abs=0.1)
    assert -19.6 < rec.effort[:, :3].min() < -19.4                           # SOURCE.md
    np.testing.assert_allclose(rec.reference, np.gradient(
        np.radians(raw.ref_pos_deg.T), rec.dt, axis=0), atol=1e-4)


@needs_data
@pytest.mark.parametrize('data, mp', [(EMPS, EMPS_MAP), (KUKA, KUKA_MAP)])
def test_cli_import_writes_bag_and_never_overwrites(tmp_path, capsys, data, mp):
    out = tmp_path / 'bag'
    argv = ['import', str(data), '--map', str(mp), '--out', str(out)]
    assert main(argv) == 0
    assert f'wrote {out}' in capsys.readouterr().out
    rec, timing = read_recording(out)
    ref = import_table(data, mp)
    assert timing.grid == 'exact' and np.array_equal(rec.t, ref.t)
    for name in ('position', 'velocity', 'effort', 'reference'):
        assert np.array_equal(getattr(rec, name), getattr(ref, name))
    assert rec.meta['import']['source'] == data.name
    before = sorted(p.stat().st_mtime_ns for p in out.iterdir())
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert 'already exists' in err and len(err.strip().splitlines()) == 1
    assert sorted(p.stat().st_mtime_ns for p in out.iterdir()) == before


def test_cli_bad_map_exit_2_one_line(tmp_path):
    """A real process: exit status 2, one line on stderr, no traceback, no bag."""
    mp = tmp_path / 'm.yaml'
    mp.write_text('frf_ident_map: 1\ntime: {sample_time: 0.001}\njoints:\n'
                  '  - {name: j, position: q, effort: nope}\n')
    (tmp_path / 'd.csv').write_text('q,tau\n0,1\n1,2\n2,3\n3,4\n')
    run = subprocess.run([sys.executable, '-m', 'frf_ident', 'import', str(tmp_path / 'd.csv'),
                          '--map', str(mp), '--out', str(tmp_path / 'bag')],
                         capture_output=True, text=True)
    assert run.returncode == 2 and 'Traceback' not in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1
    assert "column='nope' not found" in run.stderr and 'q, tau' in run.stderr
    assert not (tmp_path / 'bag').exists()


# --------------------------------------------------------------------------- CSV / MAT

def _sine_csv(path, n=2001, dt=0.002, sep=',', header=True):
    t = np.arange(n) * dt
    q = 3.0 * np.sin(2 * np.pi * 1.5 * t)          # degrees
    tau = 10 * np.cos(2 * np.pi * 0.5 * t)
    rows = [f'{1e3 * a!r}{sep}{b!r}{sep}{c!r}'
            for a, b, c in zip(t.tolist(), q.tolist(), tau.tolist())]
    path.write_text(('# exported by some tool\n' + f'time_ms{sep}q_deg{sep}tau\n' if header
                     else '') + '\n'.join(rows) + '\n')
    return t, q, tau


@pytest.mark.parametrize('sep', [',', ';', '\t', ' '])
def test_csv_degrees_ms_and_differentiated_velocity(tmp_path, sep):
    t, q, tau = _sine_csv(tmp_path / 'd.csv', sep=sep)
    mp = {'frf_ident_map': 1, 'time': {'column': 'time_ms', 'scale': 'ms', 'range': [0.5, 3.5]},
          'joints': [{'name': 'j1', 'position': {'column': 'q_deg', 'scale': 'deg'},
                      'effort': 'tau'}]}
    rec = import_table(tmp_path / 'd.csv', mp)
    keep = (t >= 0.5) & (t <= 3.5)
    assert rec.t.size == keep.sum() and rec.t[0] == pytest.approx(0.5)
    assert rec.dt == pytest.approx(0.002, rel=1e-12)
    np.testing.assert_allclose(rec.position[:, 0], np.radians(q[keep]), rtol=1e-12)
    w = 2 * np.pi * 1.5
    exact = np.radians(3.0) * w * np.cos(w * t[keep])
    err = np.abs(rec.velocity[:, 0] - exact)
    # central differences: error (w dt)^2 / 6 relative inside, second order at the ends
    assert err[1:-1].max() <= np.radians(3.0) * w * (w * 0.002) ** 2 / 6 * 1.01
    assert err.max() < 1e-3 * np.abs(exact).max()
    assert rec.meta['import']['derived'] == {'j1.velocity': 'central differences of position'}
    assert rec.reference is None


def test_csv_without_header_by_index_and_sample_time(tmp_path):
    t, q, tau = _sine_csv(tmp_path / 'd.csv', header=False)
    mp = {'frf_ident_map': 1, 'time': {'sample_time': 0.002, 'start': 1.0},
          'joints': [{'name': 'j', 'velocity': {'column': 1, 'scale': [2.0, 'deg']},
                      'effort': {'column': 2, 'offset': -1.0}}]}
    rec = import_table(tmp_path / 'd.csv', mp)
    assert rec.t[0] == 1.0 and rec.t.size == t.size
    np.testing.assert_allclose(rec.velocity[:, 0], 2 * np.radians(q))
    np.testing.assert_allclose(rec.effort[:, 0], tau - 1.0)
    assert rec.meta['import']['derived'] == {'j.position': 'trapezoidal integral of velocity '
                                                           'from 0'}


def test_mat_struct_rows_columns_and_scale_variable(tmp_path):
    n = 500
    t = np.arange(n) * 0.01 - 1.0                       # negative times are shifted
    m = np.vstack([np.sin(t), np.cos(t), t])           # (3, n): time along columns
    savemat(tmp_path / 'd.mat', {'s': {'time': t, 'm': m, 'k': m.T}, 'gain': 2.5})
    mp = {'frf_ident_map': 1, 'time': {'variable': 's.time'},
          'joints': [{'name': 'a', 'position': {'variable': 's.m', 'row': 0},
                      'velocity': {'variable': 's.m', 'row': 1},
                      'effort': {'variable': 's.k', 'col': 2, 'scale': 'gain'}}]}
    rec = import_table(tmp_path / 'd.mat', mp)
    assert rec.t[0] == 0.0 and rec.meta['import']['time_shift_s'] == pytest.approx(1.0)
    np.testing.assert_allclose(rec.position[:, 0], np.sin(t))
    np.testing.assert_allclose(rec.effort[:, 0], 2.5 * t)


def _write(tmp_path, text):
    (tmp_path / 'd.csv').write_text('t,q,tau,bad\n' + '\n'.join(
        f'{k * 0.001},{k},{2 * k},{"nan" if k == 5 else k}' for k in range(20)) + '\n')
    (tmp_path / 'm.yaml').write_text(text)
    return tmp_path / 'd.csv', tmp_path / 'm.yaml'


@pytest.mark.parametrize('map_text, needle', [
    ('frf_ident_map: 2\n', 'frf_ident_map=2'),
    ('frf_ident_map: 1\ntime: {column: t}\njoints: []\n', 'joints=[]'),
    ('frf_ident_map: 1\ntime: {column: t, sample_time: 1}\njoints: [{name: j, position: q, '
     'effort: tau}]\n', 'exactly one of column'),
    ('frf_ident_map: 1\ntime: {column: t}\njoints: [{name: j, position: q}]\n',
     'effort is required'),
    ('frf_ident_map: 1\ntime: {column: t}\njoints: [{name: j, position: q, effort: tau, '
     'torque: q}]\n', "unknown field 'torque'"),
    ('frf_ident_map: 1\ntime: {column: t}\njoints: [{name: j, position: q, effort: '
     '{column: tau, scale: furlong}}]\n', "scale='furlong' is not a unit"),
    ('frf_ident_map: 1\ntime: {column: t}\njoints: [{name: j, position: q, effort: bad}]\n',
     '1 non-finite values (first at sample 5)'),
    ('frf_ident_map: 1\ntime: {column: t, range: [5, 6]}\njoints: [{name: j, position: q, '
     'effort: tau}]\n', 'keeps 0 samples'),
    ('frf_ident_map: 1\ntime: {column: q, scale: 0.001}\njoints: [{name: j, position: q, '
     'effort: tau}]\n', None),
    ('frf_ident_map: 1\ntime: {column: tau}\njoints: [{name: j, position: {column: q, '
     'row: 1}, effort: tau}]\n', 'row/col given'),
    ('frf_ident_map: 1\ntime: [\n', 'not valid YAML at line'),
])
def test_bad_maps_one_line(tmp_path, map_text, needle):
    data, mp = _write(tmp_path, map_text)
    if needle is None:                                  # a valid map for contrast
        assert import_table(data, mp).t.size == 20
        return
    with pytest.raises(FrfIdentInputError) as err:
        import_table(data, mp)
    msg = str(err.value)
    assert needle in msg and '\n' not in msg and 'm.yaml' in msg


def test_non_uniform_time_and_bad_files(tmp_path):
    (tmp_path / 'd.csv').write_text('t,q,tau\n0,0,0\n0.001,1,1\n0.002,2,2\n0.0035,3,3\n'
                                    '0.0045,4,4\n')
    mp = {'frf_ident_map': 1, 'time': {'column': 't'},
          'joints': [{'name': 'j', 'position': 'q', 'effort': 'tau'}]}
    with pytest.raises(FrfIdentInputError, match='not uniformly sampled'):
        import_table(tmp_path / 'd.csv', mp)
    with pytest.raises(FrfIdentInputError, match='does not exist'):
        import_table(tmp_path / 'missing.csv', mp)
    (tmp_path / 'x.xlsx').write_text('')
    with pytest.raises(FrfIdentInputError, match="unknown format '.xlsx'"):
        import_table(tmp_path / 'x.xlsx', mp)
    (tmp_path / 'e.csv').write_text('t,q,tau\n0,0,0\n0.001,1\n')
    with pytest.raises(FrfIdentInputError, match='data row 3: 2 fields'):
        import_table(tmp_path / 'e.csv', mp)


@needs_data
def test_mat_2d_without_row_names_shape():
    mp = yaml.safe_load(KUKA_MAP.read_text())
    del mp['joints'][0]['effort']['row']
    with pytest.raises(FrfIdentInputError, match=r'shape \(6, 2501\) is not a signal \(give row'):
        import_table(KUKA, mp)
    mp['joints'][0]['effort']['row'] = 6
    with pytest.raises(FrfIdentInputError, match=r'row=6 is out of range for shape \(6, 2501\)'):
        import_table(KUKA, mp)


@needs_data
def test_example_maps_load():
    for mp in (EMPS_MAP, KUKA_MAP):
        assert load_map(mp)['frf_ident_map'] == 1
