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
Hidden effects in the independent reference plant, end to end.

Hidden effects in the independent reference plant (test/plants/reference.py), end to end:
``identify --plant plants.reference:ReferencePlant`` records a bag, ``diagnose`` compares it
with the nominal config/model_3axis.yaml. Two scenes are drawn at random on every run (a fresh
seed each, printed with the scene; FRF_DIAG_SEED=<seed> repeats one, FRF_DIAG_LOG=1 with
``pytest -s`` prints its diagnosis log), kinds as in the sweep;
the other scenes keep fixed seeds as regression checks. The rates over many scenes are
measured by the sweep (``make bench``, section diagnosis).
"""
import copy
from dataclasses import replace
import math
import os
from pathlib import Path
import sys

from benchmarks.diagnosis_scene_run import identification_config, PLANT, run_scene
from benchmarks.diagnosis_scenes import draw_scene, KINDS, MODEL, scene_of
from frf_ident.app.diagnose import load_data
from frf_ident.app.identify import run_identify
from frf_ident.core.diagnosis.experiments.candidates import (coupled_ripples, fit_ripple,
                                                             friction_regression)
from frf_ident.core.diagnosis.experiments.evaluator import Evaluator
from frf_ident.core.diagnosis.experiments.unexplained import discretisation_check
from frf_ident.io.model_file import load_model
import numpy as np
import pytest


def _seed() -> int:
    """Return FRF_DIAG_SEED when set (to repeat a scene), else a fresh random seed."""
    given = os.environ.get('FRF_DIAG_SEED', '')
    return int(given) if given else int.from_bytes(os.urandom(3), 'little')


def _check(r: dict, msg: str) -> None:
    """
    Assert the per-scene floors.

    Clean scenes name nothing; second-mode scenes name nothing else than the mode on its axis
    (issue 57), or, where it is not named, report it unexplained there with a band containing
    it; the others name at least half of the hidden (effect, axis) pairs with at most one
    false alarm, at least half of the found parameters within 20 % and at most one outside
    (floors all 96 scenes of the three README sweeps meet; the rates are measured by the
    sweep).
    """
    if r['kind'] == 'clean':
        assert r['n_found'] == 0, msg
        return
    if r['kind'] == 'second_mode':
        assert r['false_alarms'] == 0, msg
        assert r['mode_named'] or r['mode_unexplained'], msg
        return
    assert r['hits'] >= math.ceil(r['n_hidden'] / 2), msg
    assert r['false_alarms'] <= 1, msg
    errs = list(r['param_errors'].values())
    assert sum(e < 0.2 for e in errs) >= math.ceil(len(errs) / 2), msg
    assert sum(e < 0.2 for e in errs) >= len(errs) - 1, msg   # at most one outside 20 %


@pytest.mark.slow
@pytest.mark.parametrize('draw', [0, 1])
def test_scene_drawn_at_random(draw, tmp_path):
    # a fresh seed per run (printed; the failure message repeats it), kind cycled by seed
    seed = _seed()
    scene = draw_scene(np.random.default_rng(seed), KINDS[seed % len(KINDS)])
    print(f'FRF_DIAG_SEED={seed} kind={scene["kind"]} hidden={scene["truth"]}',
          file=sys.stderr)
    r = run_scene(scene, tmp_path)
    _check(r, f'FRF_DIAG_SEED={seed}: {r}')


@pytest.mark.slow
@pytest.mark.parametrize('kind, seed', [
    # a random draw that failed CI: joint_2 sticks, its regression reads Coulomb friction
    # twice too high, a viscous term and a damping mismatch took its place
    ('random', 7189810),
    ('clean', 2027)])
def test_scene_of_the_reference_plant(kind, seed, tmp_path):
    scene = draw_scene(np.random.default_rng(seed), kind)
    r = run_scene(scene, tmp_path)
    _check(r, f'seed {seed}: {r}')


@pytest.mark.slow
def test_unmodelled_second_mode_is_unexplained_on_its_axis(tmp_path):
    """
    Report an unmodelled second mode as such (or unexplained on its axis), not as a mismatch.

    Since issue 57 the mode may be named (``second_mode`` on its axis, the only effect); the
    history of the scene:

    A CI draw (seed 15626261): the mode at 23.7 Hz on joint_3 (resonance 31 Hz) was named a
    stiffness and damping mismatch that removed 93 % of the axis' misfit (left 220 floors,
    under 10 % of the nominal's, so the share rule passed it): the FRF no linear rescale of the
    axis fits is what shows the missing structure (``structure_missing``). Stage 0 (the
    frequency-domain fit) shifted joint_3's fitted stiffness at both loads too, and named it
    a mismatch that was withdrawn later, leaving a viscous term taken on top of it: the fit
    leaves the axis' own channel at 2,300 times its noise per degree of freedom (the right
    structure: 3-14), so stage 0 names nothing there (FD_STRUCTURE_RATIO).
    """
    seed = 15626261
    scene = draw_scene(np.random.default_rng(seed), 'second_mode')
    r = run_scene(scene, tmp_path)
    msg = f'seed {seed}: {r}'
    # nothing but the mode named (no mismatch, no friction for it); where it is not named, its
    # axis unexplained with a band around the resonance the extra mode adds (within 10 %)
    print(f'seed {seed}: found {r["found"]}, parameters {r["parameters"]}', file=sys.stderr)
    assert r['false_alarms'] == 0, msg
    assert r['mode_named'] or r['mode_unexplained'], msg


@pytest.mark.slow
def test_mismatched_axis_keeps_its_nominal_friction(tmp_path):
    """
    Name a stiffness mismatch next to another effect, and no friction change on its axis.

    Bench kind ``mismatch``, seed 9109: joint_1 9 % stiffer than nominal, Coulomb friction
    11 N m on joint_2. The joint refit of joint_1 settled on stiffness and damping next to a
    viscous friction of 1.02 (nominal 20), which the held-out check kept until the mismatch
    became the viscous term's partner, refitted without it (docs/diagnosis/experiments.md,
    acceptance): with its partners refitted the model without the viscous term fits even the fit
    part better (11.7 floors against 13.8 with it), while held out two misfits this far above the
    floor differ by chance (11.9 against 10.3), so both are asked (``held_out_check``).
    """
    scene = draw_scene(np.random.default_rng(9109), 'mismatch')
    r = run_scene(scene, tmp_path)
    assert sorted(r['found']) == sorted(r['hidden']), r
    assert all(e < 0.1 for e in r['param_errors'].values()), r


@pytest.mark.slow
def test_ripple_read_again_on_the_refitted_mismatch_is_named(tmp_path):
    """
    Name a ripple whose first readings a stiffness mismatch of its axis biased.

    Bench kind ``mismatch``, seed 9104: a stiffness mismatch and a torque ripple. Read
    against the mismatched stiffness, the ripple's amplitude and phase are biased; offered in
    the second pass, next to a mismatch still a few percent off, it worsened the axis (7.40
    N m at phase 1.38, 29.2 -> 31.2 floors) and was missed. Read again from the residual of
    the jointly refitted model (``late_ripples``) it is named, 6.86 N m at 1.42 for a true 6.91
    at 1.43.
    """
    scene = draw_scene(np.random.default_rng(9104), 'mismatch')
    r = run_scene(scene, tmp_path)
    assert 'torque_ripple@joint_1' in r['hidden'], r
    assert 'torque_ripple@joint_1' in r['found'], r
    assert r['param_errors']['torque_ripple@joint_1'] < 0.2, r


@pytest.mark.slow
@pytest.mark.parametrize('scale', [0.8, 1.2])
def test_stiffness_mismatch_is_named_with_its_value(scale, tmp_path):
    """
    Name a linear stiffness the nominal model gets wrong, with its value.

    The reference plant's joint_2 is 20 % softer / stiffer than the nominal model: a
    parameter_mismatch on joint_2 with the plant's stiffness (within 10 %), nothing else named,
    nothing unexplained (the structure is right, only a parameter is off). Next to another
    effect: :func:`test_mismatched_axis_keeps_its_nominal_friction`.
    """
    k = 3.0e5 * scale
    scene = {'scene': {'axes': {'1': {'stiffness': k}}, 'velocity_noise': 2e-5, 'seed': 7},
             'truth': [], 'mode': None, 'kind': 'mismatch'}
    r = run_scene(scene, tmp_path)
    assert r['found'] == ['parameter_mismatch@joint_2'], r
    assert r['parameters']['parameter_mismatch@joint_2']['stiffness'] == pytest.approx(k, rel=0.1)
    assert r['unexplained'] == [], r


def _evaluator(scene: dict, tmp_path) -> Evaluator:
    """Return the evaluator of the reference plant's identification record of ``scene``."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    import plants.reference as ref
    ref.SCENE = scene
    try:
        run_identify(MODEL, PLANT, identification_config(), tmp_path / 'bag',
                     progress=lambda _m: None)
    finally:
        ref.SCENE = {}
    return Evaluator(load_data(tmp_path / 'bag'), load_model(MODEL)[2])


def _ripple_reads(scene: dict, tmp_path) -> tuple[list, list]:
    """Return each axis' stage-1 ripple reading of the reference plant and the coupled ones."""
    robot = load_model(MODEL)[1]
    ev = _evaluator(scene, tmp_path)
    regs = [friction_regression(ev, robot, i) for i in range(robot.n_axes)]
    reads = [r for r in (fit_ripple(g, robot, i) for i, g in enumerate(regs)) if r is not None]
    return reads, coupled_ripples(reads, robot.link_inertia_matrix(),
                                  np.array([g.ripple_resolution for g in regs]))


@pytest.mark.slow
@pytest.mark.parametrize('own', [None, 2.0])
def test_a_ripple_seen_through_the_link_coupling_is_not_the_axis_own(own, tmp_path):
    """
    Tell another axis' ripple seen through the links from an axis' own ripple.

    Bench seed 41017 (scene 17 of the sweep from 41000): joint_3's 6.1 N m ripple at 1024 /rad
    loads joint_1, whose backlash the nominal model lacks, through the link coupling at the
    same spatial frequency in joint_1's position (the axes move together on the
    constant-velocity run), and joint_1's scan reads it as its own. Here the independent
    reference plant runs that scene as drawn (joint_1's reading is the coupling), or with
    joint_1's own ripple of ``own`` N m (the low end of the bench's range) at 1060 /rad, inside
    the scan's resolution of joint_3's: that one is joint_1's.

    The same scene shaped two more stages (core/diagnosis/experiments/pipeline.py): joint_3's
    ripple, left out of stage 1 because the stiffening gear dominated the axis' misfit, is offered
    with the FRF-shape candidates (``frf_shape_candidates``); offered after them, a backlash
    and a viscous term took its torque and it then worsened the axis (3.22 -> 3.47 floors),
    while its coupling torque was named as joint_1's own ripple (0.15 N m at 1026 /rad). And a
    stiffening gear fitted next to a spurious viscous term left 6 floors, which a backlash and
    viscous friction then took: an FRF-shape effect is refitted jointly with what the axis
    took before it is read again (``frf_shape_effects``).
    """
    scene = copy.deepcopy(scene_of(41000, 17)['scene'])
    assert scene['axes']['2']['torque_ripple'][0]['amplitude'] == pytest.approx(6.1, abs=0.01)
    if own:
        scene['axes']['0']['torque_ripple'] = [{'amplitude': own, 'spatial_frequency': 1060.0,
                                                'phase': -1.0}]
    reads, coupled = _ripple_reads(scene, tmp_path)
    by_axis = {r.axis: r.parameters['torque_ripple'][-1] for r in reads}
    msg = f'{by_axis}, coupled: {[c.axis for c in coupled]}'
    # joint_3's reading is biased by its stiffening gear (6.90 N m as the bench logs it)
    assert abs(by_axis['joint_3']['amplitude'] / 6.1 - 1) < 0.2, msg
    assert 'joint_3' not in [c.axis for c in coupled], msg
    if own:
        # read at its own frequency (its amplitude, next to the backlash and the coupling
        # inside one resolution cell, 1.46 N m for 2) and kept a candidate
        assert abs(by_axis['joint_1']['spatial_frequency'] / 1060 - 1) < 0.01, msg
        assert 'joint_1' not in [c.axis for c in coupled], msg
    else:
        # the coupling is seen at joint_3's frequency (else the test shows nothing) and
        # recognised
        assert abs(by_axis['joint_1']['spatial_frequency'] / 1024.3 - 1) < 0.01, msg
        assert 'joint_1' in [c.axis for c in coupled], msg


@pytest.mark.slow
def test_friction_fitted_next_to_a_coupled_axis_misfit_is_refitted(tmp_path):
    """
    Name a viscous friction whose regression reads it with the wrong sign, with its value.

    Bench seed 51009 (scene 9 of the sweep from 51000): joint_2's viscous friction is 58.2
    (nominal 25) beside its 7.9 N m ripple, joint_1 has a backlash and joint_3 a stiffening
    gear 1.2e4 noise floors off. joint_2's residual regression reads the viscous correction
    as -239 (t = 4.8): floored at 0 it made the axis worse, and a Coulomb friction of 0.77 was
    named in its place. A clear reading that fails is refitted by simulation over the whole
    range (42.8), and, fitted while joint_3 was so far off, refitted once joint_3's
    stiffening is in the model.
    """
    r = run_scene(scene_of(51000, 9), tmp_path)
    assert sorted(r['found']) == sorted(r['hidden']), r
    assert all(e < 0.2 for e in r['param_errors'].values()), r


@pytest.mark.slow
def test_stiffening_gear_that_lost_to_a_mismatch_next_to_a_coupled_one_is_named(tmp_path):
    """
    Name a stiffening gear whose axis a coupled axis' stiffening misled.

    Bench seed 83008 (scene 8 of the sweep from 83000, fresh at 401c3d2): stiffening gears on
    joint_2 (k2 = 1.43 k1 beyond 1.8e-4 rad) and joint_3. While joint_3 still lacked its
    own, joint_2's stiffness and damping mismatch beat its stiffening on the held-out data;
    a backlash took the rest, the mismatch was then not named (216 floors left) and a
    backlash was. The lost rival, refitted in the mismatch's place, explains the axis.
    """
    r = run_scene(scene_of(83000, 8), tmp_path)
    assert {'stiffness_nonlinearity@joint_2', 'stiffness_nonlinearity@joint_3'} <= set(
        r['found']), r
    assert 'backlash@joint_2' not in r['found'], r
    assert not any(u['axis'] == 'joint_2' for u in r['unexplained']), r
    assert all(e < 0.2 for e in r['param_errors'].values()), r


@pytest.mark.slow
def test_gravity_beside_a_stiffening_gear_on_its_axis_is_named(tmp_path):
    """
    Name a load the stiffening gear of its axis absorbed, with its value.

    Bench seed 51023 (scene 23 of the sweep from 51000): joint_2 carries 277 sin(q + 2.671)
    N m and a stiffening gear, joint_3 a ripple. The stage-1 reading of the load is right
    (279 at 2.664), but the stiffening fitted without it leaves joint_2 below its floor, and
    offered on top of that fit the load worsened the axis (0.66 -> 2.27 floors): the load
    was missed. Offered with the stiffening refitted beside it, it is named.
    """
    r = run_scene(scene_of(51000, 23), tmp_path)
    assert sorted(r['found']) == sorted(r['hidden']), r
    assert all(e < 0.2 for e in r['param_errors'].values()), r


@pytest.mark.slow
def test_a_simulation_too_coarse_for_the_record_is_reported(tmp_path):
    """
    Report the axes whose misfit the integrator's step changes.

    Bench seed 51007 (scene 7 of the sweep from 51000): backlash on joint_1, gravity and a
    ripple on joint_2, recorded from the reference plant (RK4, 8 steps per sample). The true
    model simulated at the nominal model file's 1 substep leaves joint_1's backlash contacts
    a first-order step error above the noise (the diagnosis then read a spurious viscous
    friction from it); at 8 substeps doubling them changes nothing that the noise shows.
    """
    scene = scene_of(51000, 7)
    robot = load_model(MODEL)[1]
    axes = list(robot.axes)
    for _name, ax, params in scene['truth']:
        axes[ax] = replace(axes[ax], **params)
    truth = replace(robot, axes=axes)
    ev = _evaluator(scene['scene'], tmp_path)
    coarse, fine = (replace(truth, substeps=m) for m in (1, 8))
    step = discretisation_check(ev, coarse, ev.misfit(ev.terms(coarse, held_out=True)))
    print(step)    # the figures docs/diagnosis/experiments.md quotes (pytest -s)
    assert step.axes == robot.joint_names, step
    assert step.substeps == 1 and 'joint_1' in step.too_coarse, step
    # the finer simulation is the closer one to the record
    j = step.axes.index('joint_1')
    assert step.held_out_misfit_double_substeps[j] < step.held_out_misfit[j], step
    step = discretisation_check(ev, fine, ev.misfit(ev.terms(fine, held_out=True)))
    print(step)
    assert step.too_coarse == [], step
