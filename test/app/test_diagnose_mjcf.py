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
Diagnosis against an MJCF, written back as MJCF (issue 50 phase B), on MuJoCo's own truth.

Two robots: the KUKA iiwa 14 of the shared data and a Universal Robots UR5e
(test/plants/mujoco_ur5e.py: the rigid-body data of MuJoCo Menagerie's
``universal_robots_ur5e/ur5e.xml``, github.com/google-deepmind/mujoco_menagerie, BSD 3-Clause,
its drive guesses removed). The truth is the plain MJCF with drive terms a real arm could have,
added by this test's own XML edits (test/plants/mujoco_iiwa.py, without frf_ident.io.mjcf):
on one joint rotor inertia (``armature``), viscous (``damping``) and dry friction
(``frictionloss``); on another the series-elastic hinge pair (rotor, spring, link damping: a
resonance near 22 Hz) with motor damping and dry friction; the third untouched. It is
recorded by MuJoCo (``identify --plant mujoco:truth.xml``, noise on velocity and torque) and
diagnosed against the plain MJCF (``diagnose`` with a model file naming it). Checked against
what the code under test did not produce: the truth's own terms, and MuJoCo's linearisation
of the truth, the nominal and the written extended_model.xml (mjd_transitionFD, here):

- every added term named on its axis, its value in extended_model.xml within 20 %;
- nothing named and no MJCF term changed on the untouched axis;
- the extended MJCF's linearised FRF within 1 dB median of the truth's on every axis where
  the nominal's is off by more;
- the held-out time NRMSE of extended_model.xml simulated by MuJoCo at least 3x below the
  nominal MJCF's.
"""
from dataclasses import dataclass
import json
import os
from pathlib import Path

import numpy as np
from plants.mujoco_iiwa import (elastic_xml, home, KI, KP, linear_frf, SHARED_IIWA,
                                with_drives)
from plants.mujoco_ur5e import write_ur5e
import pytest
import yaml

mujoco = pytest.importorskip('mujoco')

#: the two scenes took 10 min each on a quiet 2-core PC (30 min at load 15) in one xdist group:
#: beyond `make test`'s 20 minutes, they run with FRF_MJCF_DIAGNOSIS=1 (as the sweeps of
#: test_diagnose_sensor_scenes.py and test_diagnose_modes.py run with their variables)
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group('mujoco_diagnosis'),
              pytest.mark.skipif(os.environ.get('FRF_MJCF_DIAGNOSIS') != '1',
                                 reason='FRF_MJCF_DIAGNOSIS=1 runs the MJCF diagnosis scenes')]

#: the terms within 20 % (issue 50)
TOLERANCE = 0.2
#: velocity measurement noise [rad/s] (a filtered encoder velocity at 1 kHz): with 2e-3 the
#: noise alone put the truth itself at a held-out time NRMSE of 0.26 against 0.38 of the
#: nominal (velocity RMS 0.01 rad/s at a 1 deg position bound), no model could show 3x
VELOCITY_NOISE = 5e-4
#: the lines the linearisations are compared on [Hz] (the band the experiments excite)
FREQ_HZ = np.geomspace(2.5, 60.0, 80)


@dataclass
class Scene:
    """A robot, its truth's added terms per axis (MJCF attributes), pose, gains, noise."""

    name: str
    axes: list[str]
    pose: dict[str, float]
    kp: list[float]
    ki: list[float]
    torque_noise: float
    #: axis -> {MJCF term: value}: what the truth adds (``stiffness`` etc.: the link hinge)
    added: dict[str, dict[str, float]]
    #: the chirp's desired torque amplitudes per axis [N m] (None: the paper's Table 1)
    u_des: list[list[float]] | None = None

    def truth_args(self) -> dict:
        """Return the drive edits as elastic_xml/with_drives take them."""
        el, rig, fl = {}, {}, {}
        for ax, t in self.added.items():
            if 'stiffness' in t:
                el[ax] = (t['armature'], t['damping'], t['stiffness'], t['link_damping'])
            elif 'armature' in t:
                rig[ax] = (t['armature'], t['damping'])
            if 'frictionloss' in t:
                fl[ax] = t['frictionloss']
        return {'elastic': el, 'rigid': rig, 'frictionloss': fl}


#: joint1 a rigid drive (rotor 0.8 kg m^2 through a harmonic drive, viscous 6 N m s/rad, dry
#: 8 N m), joint2 elastic (its torque sensor and flexspline: 1.5e4 N m/rad against a 1 kg m^2
#: rotor, antiresonance 11 Hz, resonance 22 Hz) with friction, joint4 untouched
IIWA = Scene('iiwa14', ['joint1', 'joint2', 'joint4'], {}, KP, KI, 0.2, {
    'joint1': {'armature': 0.8, 'damping': 6.0, 'frictionloss': 8.0},
    'joint2': {'armature': 1.0, 'damping': 5.0, 'stiffness': 1.5e4, 'link_damping': 10.0,
               'frictionloss': 6.0}})
#: a UR5e (link-side inertias 1.8, 2.3, 0.5 kg m^2 at the pose): shoulder_pan rotor
#: 0.5 kg m^2 with viscous 4 N m s/rad and dry 6 N m friction; shoulder_lift elastic (rotor
#: 0.6 kg m^2, 1.2e4 N m/rad: antiresonance near 12 Hz, resonance near 26 Hz, link damping
#: about 5 % of critical) with friction; elbow untouched; PI gains for a ~5 Hz velocity loop
UR5E = Scene('ur5e', ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint'],
             {'shoulder_pan_joint': 0.0, 'shoulder_lift_joint': -1.0, 'elbow_joint': 1.2},
             [80.0, 100.0, 25.0], [800.0, 1000.0, 250.0], 0.1, {
                 'shoulder_pan_joint': {'armature': 0.5, 'damping': 4.0, 'frictionloss': 6.0},
                 'shoulder_lift_joint': {'armature': 0.6, 'damping': 4.0, 'stiffness': 1.2e4,
                                         'link_damping': 8.0, 'frictionloss': 5.0}},
             [[40.0, 20.0], [60.0, 30.0], [25.0, 12.0]])


def _files(scene: Scene, tmp: Path) -> tuple[Path, str]:
    """Write the nominal MJCF's model file and the truth MJCF; return (model file, truth)."""
    if scene is IIWA:
        nominal, pose = SHARED_IIWA, 'home'
        truth = elastic_xml(**scene.truth_args())
    else:
        nominal = write_ur5e(tmp / 'ur5e.xml')
        pose = dict(scene.pose)
        truth = with_drives(nominal.read_text(), **scene.truth_args())
    (tmp / 'truth.xml').write_text(truth)
    model = {'frf_ident_model': 1, 'sample_rate': 1000.0, 'mjcf': str(nominal), 'pose': pose,
             'axes': [{'name': a, 'velocity_noise': VELOCITY_NOISE,
                       'torque_noise': scene.torque_noise} for a in scene.axes],
             'controller': {'kind': 'pi_velocity', 'kp': scene.kp, 'ki': scene.ki}}
    (tmp / 'nominal.yaml').write_text(yaml.safe_dump(model))
    return tmp / 'nominal.yaml', truth


def _chirp(scene: Scene):
    """Return the chirp of a scene: 10 s, two iterations, its torque amplitudes."""
    from frf_ident.core.excitation.chirp_iteration import ChirpConfig
    if scene.u_des is None:
        return ChirpConfig(duration=10.0, max_iterations=2)
    return ChirpConfig(duration=10.0, max_iterations=2, u_des=np.array(scene.u_des))


@pytest.fixture(scope='module', params=[IIWA, UR5E], ids=lambda s: s.name)
def diagnosed(request, tmp_path_factory):
    """Identify the truth in MuJoCo, diagnose against the plain MJCF; the files and report."""
    from frf_ident.app.diagnose import diagnose
    from frf_ident.app.identify import run_identify
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    from frf_ident.core.simulation.runner import IdentificationConfig
    scene = request.param
    tmp = tmp_path_factory.mktemp(scene.name)
    model, truth = _files(scene, tmp)
    cfg = IdentificationConfig(MultisineConfig(n_realisations=3, n_periods=2,
                                               resolution_hz=0.5),
                               _chirp(scene))
    run_identify(model, f'mujoco:{tmp / "truth.xml"}', cfg, tmp / 'bag',
                 progress=lambda _m: None)
    lines: list[str] = []
    diagnose(tmp / 'bag', model, tmp / 'diag', progress=lines.append)
    print('\n'.join(lines))
    report = json.loads((tmp / 'diag' / 'report.json').read_text())
    return scene, tmp, truth, report


def test_every_added_term_is_named_on_its_axis_nothing_on_the_untouched_one(diagnosed):
    scene, _, _, report = diagnosed
    named = {e['axis'] for e in report['effects']}
    terms = report['mjcf']['axes']
    for axis in scene.axes:
        kinds = sorted(e['name'] for e in report['effects'] if e['axis'] == axis)
        print(f'{scene.name} {axis}: named {kinds}, MJCF terms changed {terms[axis]["changed"]}')
        if scene.added.get(axis):
            assert axis in named, (axis, report['effects'])
            assert set(scene.added[axis]) <= set(terms[axis]['changed']), terms[axis]
        else:       # untouched: nothing named, no MJCF term changed
            assert axis not in named, (axis, report['effects'])
            assert terms[axis]['changed'] == [], terms[axis]


def test_every_added_term_within_20_percent(diagnosed):
    scene, _, _, report = diagnosed
    terms = report['mjcf']['axes']
    bad = []
    for axis, added in scene.added.items():
        found = terms[axis]['extended']
        for key, truth in added.items():
            err = found[key] / truth - 1.0
            print(f'{scene.name} {axis} {key}: truth {truth:g}, extended_model.xml '
                  f'{found[key]:.4g} ({100 * err:+.1f} %)')
            if not abs(err) < TOLERANCE:
                bad.append((axis, key, found[key], truth))
    assert not bad, bad


def test_extended_mjcf_linearises_to_the_truth(diagnosed):
    scene, tmp, truth, _ = diagnosed
    xml = tmp / 'diag' / 'extended_model.xml'
    mujoco.MjModel.from_xml_path(str(xml))           # it loads
    pose = home() if scene is IIWA else scene.pose
    nominal_xml = Path(yaml.safe_load((tmp / 'nominal.yaml').read_text())['mjcf']).read_text()
    t = linear_frf(truth, FREQ_HZ, pose, scene.axes)
    n = linear_frf(nominal_xml, FREQ_HZ, pose, scene.axes)
    e = linear_frf(xml.read_text(), FREQ_HZ, pose, scene.axes)
    bad = []
    for i, axis in enumerate(scene.axes):
        nom = np.median(np.abs(20 * np.log10(np.abs(n[i, i] / t[i, i]))))
        ext = np.median(np.abs(20 * np.log10(np.abs(e[i, i] / t[i, i]))))
        print(f'{scene.name} {axis}: linearised FRF against the truth, median over '
              f'{FREQ_HZ.size} lines 2.5-60 Hz: nominal MJCF {nom:.3f} dB, extended MJCF '
              f'{ext:.3f} dB')
        if nom > 1.0 and not ext < 1.0:
            bad.append((axis, nom, ext))
    assert not bad, bad


def test_held_out_time_nrmse_of_the_written_mjcf_is_3x_lower(diagnosed):
    scene, _, _, report = diagnosed
    held = report['mjcf']['held_out']
    nom, ext = held['nominal']['time_nrmse'], held['extended']['time_nrmse']
    print(f'{scene.name}: held-out time NRMSE simulated by MuJoCo: nominal MJCF {nom:.4g}, '
          f'extended_model.xml {ext:.4g} ({nom / ext:.1f}x); FRF error '
          f'{held["nominal"]["frf_error_db"]:.3g} -> {held["extended"]["frf_error_db"]:.3g} '
          f'dB')
    assert nom >= 3.0 * ext
