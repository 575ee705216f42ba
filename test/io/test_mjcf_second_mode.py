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
An axis' second mode written as MJCF: MuJoCo's linearisation against our analytic model.

Standalone: the default 3-axis robot with a mode on joint_2, MuJoCo's linearisation of the
written file against the exact zero-order-hold FRF of the same parameters
(frf_ident.core.simulation.analytic): both resonances and the FRF around them. On the shared
iiwa 14 (made elastic by text edits, test/plants/mujoco_iiwa.py; gravity off so that the
two-mass + mode model of frf_ident.core.simulation.linear is the whole linear dynamics at the
pose): the poles of the written MJCF against that model's, with the mode exact (taken from the
link body) and too large for the link body (kept; the Limitation says so). Without a mode the
file is what the edits before the mode existed write, byte for byte.
"""
from dataclasses import replace

from frf_ident.core.model.params import MjcfSource
from frf_ident.core.model.schema import default_robot
from frf_ident.core.simulation.analytic import robot_frf_sampled
from frf_ident.core.simulation.linear import state_space
import numpy as np
from plants.mujoco_iiwa import elastic_xml
import pytest
import yaml

mujoco = pytest.importorskip('mujoco')
export = pytest.importorskip('frf_ident.io.mjcf.export')
transition = pytest.importorskip('frf_ident.io.mjcf.linear').transition
load_robot = pytest.importorskip('frf_ident.io.mjcf.robot').load_robot

pytestmark = pytest.mark.xdist_group('mujoco_iiwa')

#: on joint_2 (Jm 40, link 250 kg m^2, k 3e5 N m/rad: the drive resonance near 15 Hz); a link
#: mode far above it hardly moves the motor (60 Hz: < 0.2 dB), so it sits just below
MODE = {'frequency_hz': 12.0, 'damping_ratio': 0.02, 'inertia': 75.0}


def _mujoco_hz(lin):
    """Return the natural frequencies [Hz] of the oscillatory poles of a linearisation."""
    s = np.log(np.linalg.eigvals(lin.A).astype(complex)) / lin.dt
    s = s[s.imag > 2 * np.pi * 1.0]
    return np.sort(np.abs(s)) / (2 * np.pi)


def _model_hz(rob):
    """Return the same of our linear model (frf_ident.core.simulation.linear.state_space)."""
    s = np.linalg.eigvals(state_space(rob)[0])
    s = s[s.imag > 2 * np.pi * 1.0]
    return np.sort(np.abs(s)) / (2 * np.pi)


def test_standalone_second_mode_linearises_to_our_frf(tmp_path):
    rob = replace(default_robot(), link_coupling=None).with_axes(gravity_torque=0.0)
    axes = list(rob.axes)
    axes[1] = replace(axes[1], second_mode=dict(MODE))      # 30 % of joint_2's 250 kg m^2
    rob = replace(rob, axes=axes)
    exp = export.write_mjcf(rob, tmp_path / 'model.xml')
    assert exp.limitations == []
    m = mujoco.MjModel.from_xml_path(str(exp.path))
    assert m.nv == 7 and m.nu == 3
    j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, 'joint_2_mode')
    w = 2 * np.pi * MODE['frequency_hz']  # to_xml writes 6 significant digits
    assert m.jnt_stiffness[j] == pytest.approx(75.0 * w * w, rel=1e-5)
    assert m.dof_damping[m.jnt_dofadr[j]] == pytest.approx(2 * 0.02 * 75.0 * w, rel=1e-5)
    lin = transition(load_robot(MjcfSource(str(exp.path)), rob.joint_names), rob.dt)
    # MuJoCo's poles of all three axes; ours of joint_2 (the others are two-mass, 1 pole each)
    got, want = _mujoco_hz(lin), _model_hz(rob)
    print(f'resonances: MuJoCo {np.round(got, 3)} Hz, ours {np.round(want, 3)} Hz')
    assert got.size == want.size == 4
    assert np.all(np.abs(got / want - 1) < 0.01)
    f = np.arange(5.0, 120.0, 0.01)
    mj, ours = lin.frf(f)[1, 1], robot_frf_sampled(rob, f)[1, 1]
    lo, hi = 0.7 * want.min(), 1.3 * want.max()
    band = (f > lo) & (f < hi)
    e = np.abs(20 * np.log10(np.abs(mj[band] / ours[band])))
    print(f'joint_2 FRF {f[band][0]:.1f}-{f[band][-1]:.1f} Hz: median {np.median(e):.3f} dB, '
          f'max {e.max():.3f} dB')
    assert np.median(e) < 0.2
    assert e.max() < 1.0
    # the mode is seen: without it our FRF misses MuJoCo's by far more in the band
    plain = robot_frf_sampled(rob.with_axes(second_mode=None), f)[1, 1]
    e0 = np.abs(20 * np.log10(np.abs(mj[band] / plain[band])))
    print(f'the same without the mode: median {np.median(e0):.3f} dB, max {e0.max():.3f} dB')
    assert e0.max() > 10 * e.max()


def _iiwa_model(tmp_path):
    from frf_ident.io.model_file import load_model
    xml = elastic_xml().replace('<option ', '<option gravity="0 0 0" ')
    (tmp_path / 'iiwa.xml').write_text(xml)
    d = {'frf_ident_model': 1, 'sample_rate': 1000.0, 'mjcf': str(tmp_path / 'iiwa.xml'),
         'pose': {'joint2': 0.785398, 'joint4': -1.5708}, 'axes': [{'name': 'joint4'}],
         'controller': {'kind': 'pi_velocity', 'kp': [50.0], 'ki': [500.0]}}
    (tmp_path / 'm.yaml').write_text(yaml.safe_dump(d))
    return load_model(tmp_path / 'm.yaml')[1]


@pytest.mark.parametrize('inertia, exact', [(0.004, True), (0.1, False)])
def test_iiwa_second_mode_poles_match_the_model(tmp_path, inertia, exact):
    """joint4's link body has 0.006 kg m^2 about its axis (centre of mass): 0.1 is too much."""
    rob = _iiwa_model(tmp_path)
    a = rob.axes[0]
    mode = {'frequency_hz': 45.0, 'damping_ratio': 0.02, 'inertia': inertia}
    rob = replace(rob, axes=[replace(a, second_mode=mode)])
    exp = export.write_mjcf(rob, tmp_path / 'out.xml')
    print('\n'.join(exp.lines()))
    mode_lines = [str(x) for x in exp.limitations if x.key == 'second_mode']
    assert bool(mode_lines) != exact
    if not exact:
        assert 'low-frequency inertia is 0.1 kg m^2 larger, 11.6 % of' in mode_lines[0]
    written = load_robot(MjcfSource(str(exp.path), None, rob.mjcf.pose), rob.joint_names)
    got = _mujoco_hz(transition(written, rob.dt))
    # the expectation: the two-mass + mode model at the pose; approximated, the link keeps its
    # inertia and the mode comes on top (what the Limitation says)
    truth = rob if exact else replace(rob, axes=[replace(
        rob.axes[0], link_inertia=a.link_inertia + inertia)])
    want = _model_hz(truth)
    print(f'joint4, J_e {inertia} kg m^2: MuJoCo poles {np.round(got, 3)} Hz, two-mass + '
          f'mode model {np.round(want, 3)} Hz')
    assert got.size == want.size == 2
    assert np.all(np.abs(got / want - 1) < 0.02)
    # the 45 Hz pole is the mode's: the model without it has none near
    plain = _model_hz(rob.with_axes(second_mode=None))
    assert np.abs(got - 45.0).min() < np.abs(plain - 45.0).min()


def _main_pipeline(spec, drives):
    """Return the spec edited as before second modes existed (split, then each joint's terms)."""
    from frf_ident.io.mjcf.spec_edit import set_drive, split_elastic
    spec = split_elastic(spec, [d.joint for d in drives if d.elastic])
    for d in drives:
        set_drive(spec, d)
    return spec


def test_without_a_mode_the_file_is_unchanged(tmp_path):
    from frf_ident.io.mjcf.drive_map import drive_from_axis
    from frf_ident.io.mjcf.robot import load_spec
    rob = _iiwa_model(tmp_path)
    exp = export.write_mjcf(rob, tmp_path / 'out.xml')
    spec = _main_pipeline(load_spec(rob.mjcf.file), [drive_from_axis(a) for a in rob.axes])
    spec.compile()
    assert exp.path.read_text() == spec.to_xml()
    assert '_mode' not in exp.path.read_text()


def test_diagnosis_writes_and_simulates_the_mode(tmp_path):
    """extended_model.xml of a diagnosis against an MJCF: the mode in the file, in the terms."""
    from frf_ident.io.mjcf.candidate import MjcfModels, read_drives
    from frf_ident.io.mjcf.diagnosed import AxisTerms
    rob = _iiwa_model(tmp_path)
    models = MjcfModels(rob)
    mode = {'frequency_hz': 45.0, 'damping_ratio': 0.02, 'inertia': 0.004}
    ext = replace(rob, axes=[replace(rob.axes[0], second_mode=mode)])
    exp = models.write(ext, tmp_path / 'extended_model.xml')
    assert exp.limitations == []
    written = load_robot(MjcfSource(str(exp.path), None, rob.mjcf.pose), rob.joint_names)
    terms = AxisTerms('joint4', models.base[0], read_drives(written)[0])
    assert sorted(terms.changed()) == ['mode_damping', 'mode_inertia', 'mode_stiffness']
    assert terms.extended.mode_inertia == pytest.approx(0.004, rel=1e-5)
    # the model the diagnosis simulates is the file it writes
    sim = models.prepared(ext)
    assert sim.model.nv == written.model.nv == 3
    from frf_ident.io.mjcf.linear import axis_values
    back = axis_values(written, rob.sample_rate)[0][0]
    assert back['second_mode']['frequency_hz'] == pytest.approx(45.0, rel=1e-5)
    assert back['link_inertia'] == pytest.approx(rob.axes[0].link_inertia, rel=1e-5)


def test_a_mode_the_time_step_cannot_integrate_is_reported(tmp_path):
    rob = replace(default_robot(), link_coupling=None)
    mode = {'frequency_hz': 400.0, 'damping_ratio': 0.02, 'inertia': 10.0}    # w h = 2.5
    rob = replace(rob, axes=[replace(rob.axes[0], second_mode=mode)] + list(rob.axes[1:]))
    lines = [str(x) for x in export.write_mjcf(rob, tmp_path / 'model.xml').limitations]
    assert any('joint_1: second_mode' in x and 'cannot integrate' in x for x in lines), lines
