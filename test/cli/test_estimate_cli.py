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
Test ``frf-ident estimate`` on bad input and with excitation options.

`frf-ident estimate` on bad input (one line, exit 2, nothing lost) and with the excitation
given as options for bags without /frf/experiment descriptors.
"""
import hashlib
import json
import re

from frf_ident.bag import write_recording
from frf_ident.cli import main
from frf_ident.core.excitation.chirp import chirp_phase
from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
from frf_ident.core.excitation.multisine_procedure import MultisineConfig
from frf_ident.core.model.schema import default_model_dict, robot_from_dict
from frf_ident.core.recording import Recording
from frf_ident.core.simulation.controller import controller_from_dict
from frf_ident.core.simulation.plant import FlexibleJointPlant
from frf_ident.core.simulation.runner import IdentificationConfig, run_identification
from frf_ident.io.model_file import load_model, load_plant
import numpy as np
import pytest

# module fixtures shared by the tests here: they run on one worker (make test, pytest-xdist)
pytestmark = pytest.mark.xdist_group('test_estimate_cli')

FS = 1000.0


def _digest(path):
    h = hashlib.sha256()
    for f in sorted(p for p in path.rglob('*') if p.is_file()):
        h.update(f.name.encode() + f.read_bytes())
    return h.hexdigest()


def refused(bag, capsys, *args, match=()):
    """Run estimate; it must exit 2 with one stderr line, leave the bag alone, write nothing."""
    out = bag.parent / f'out_{bag.name}'
    before = _digest(bag)
    assert main(['estimate', str(bag), '--out', str(out), *args]) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err, err
    assert err.startswith('frf-ident estimate: error: '), err
    for m in match:
        assert m in err, err
    assert _digest(bag) == before and not out.exists()
    return err


def _copy_rec(rec, **kw):
    d = {'t': rec.t, 'joint_names': rec.joint_names, 'position': rec.position,
         'velocity': rec.velocity, 'effort': rec.effort, 'reference': rec.reference,
         'excitation': rec.excitation, 'segments': rec.segments, 'meta': dict(rec.meta)}
    d.update(kw)
    return Recording(**d)


# --------------------------------------------------------------------------- descriptor bags

@pytest.fixture(scope='module')
def ms_rec():
    """Return a short frf_ident multisine run: 1 realisation x 2 periods of 1 s, uncompensated."""
    model, _, ctrl = load_model(None)
    cfg = IdentificationConfig(MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=1.0,
                                               compensate=False), None)
    return run_identification(load_plant(None, model), ctrl, cfg)


@pytest.fixture(scope='module')
def ms_bag(ms_rec, tmp_path_factory):
    return write_recording(ms_rec, tmp_path_factory.mktemp('ms') / 'ms')


def test_own_run_is_accepted(ms_bag, tmp_path, capsys):
    assert main(['estimate', str(ms_bag), '--out', str(tmp_path / 'e')]) == 0
    assert json.loads((tmp_path / 'e' / 'frf.json').read_text())['estimate'] == 'multisine'


STREAM = pytest.mark.parametrize('mode', [(), ('--stream',)], ids=['in_memory', 'streamed'])


@STREAM
def test_clipped_torque_refused(ms_rec, tmp_path, capsys, mode):
    """joint_2's torque cut at its 20/80 % quantiles in the multisine segments: a drive limit."""
    u = ms_rec.effort.copy()
    segs = [s for s in ms_rec.segments if s.info.get('design') == 'multisine']
    idx = np.concatenate([np.arange(ms_rec.slice(s.t_start, s.t_end).start,
                                    ms_rec.slice(s.t_start, s.t_end).stop) for s in segs])
    lo, hi = np.quantile(u[idx, 1], [0.2, 0.8])
    u[idx, 1] = np.clip(u[idx, 1], lo, hi)
    bag = write_recording(_copy_rec(ms_rec, effort=u), tmp_path / 'clipped')
    err = refused(bag, capsys, *mode,
                  match=(f'{bag}: /joint_states effort[joint_2] is clipped at ',
                         'of the samples of the multisine segments (runs up to',
                         'expected an unsaturated plant input'))
    pct = float(re.search(r'in ([0-9.]+) % of the samples', err).group(1))
    assert 30 <= pct <= 45     # 40 % cut, less what the transient periods hold


@STREAM
def test_decimated_recording_refused_for_band_above_nyquist(ms_rec, tmp_path, capsys, mode):
    """/joint_states kept at 100 Hz: the 2-60 Hz lines reach above its 50 Hz Nyquist."""
    k = slice(None, None, 10)
    dec = _copy_rec(ms_rec, t=ms_rec.t[k], position=ms_rec.position[k],
                    velocity=ms_rec.velocity[k], effort=ms_rec.effort[k],
                    reference=ms_rec.reference[k], excitation=ms_rec.excitation[k])
    bag = write_recording(dec, tmp_path / 'dec')
    refused(bag, capsys, *mode,
            match=(f'{bag}: /frf/experiment multisine design: band 1.953-60.55 Hz',
                   'reaches the Nyquist frequency 50 Hz of the recording (sampled at 100 Hz'))


@STREAM
def test_t_range_cutting_the_only_realisation_says_it_was_left_out(ms_rec, ms_bag, capsys, mode):
    """
    A range ending inside realisation 0's first experiment: that segment is left out, named.

    The one realisation is then incomplete, so no multisine remains: one line saying why
    (issue 44: the cut segment used to fail the whole estimate with "outside the record").
    """
    seg = next(s for s in ms_rec.segments if s.info.get('design') == 'multisine')
    period = seg.info['period_samples'] / FS        # 1 transient + 1.5 of the 2 periods
    t_end = seg.t_start + 2.5 * period
    err = refused(ms_bag, capsys, *mode, '--t-range', str(seg.t_start - 1), str(t_end),
                  match=('every experiment of the recording was cut short',
                         'a time range cutting one'))
    assert str(ms_bag) in err


def test_excitation_options_refused_with_descriptors(ms_bag, capsys):
    refused(ms_bag, capsys, '--multisine-period', '1.0',
            match=('multisine_period=1.0: the recording has experiment descriptors',))


# --------------------------------------------------------------------------- foreign bags

@pytest.fixture(scope='module')
def plant_loop():
    d = default_model_dict()
    rob = robot_from_dict(d)
    return rob, controller_from_dict(d, rob)


def _closed_loop(plant_loop, r2):
    """Closed-loop run with velocity reference r2 on joint_2, recorded without descriptors."""
    rob, ctrl = plant_loop
    r = np.zeros((r2.size, 3))
    r[:, 1] = r2
    res = FlexibleJointPlant(rob).simulate(reference=r, controller=ctrl)
    return Recording(res.t, rob.joint_names, res.position, res.velocity, res.effort)


@pytest.fixture(scope='module')
def ms_unit():
    des = design_odd_multisine(2.0, 60.0, bound=0.01, resolution_hz=0.5, fs=FS)
    real = multisine_realisation(des, 1, np.random.default_rng(0), fs=FS)
    n = des.period_samples(FS)
    return real.evaluate(np.arange(n) / FS)[0][:, 0]


@pytest.fixture(scope='module')
def foreign_ms_bag(plant_loop, ms_unit, tmp_path_factory):
    rec = _closed_loop(plant_loop, np.tile(ms_unit, 5))
    return write_recording(rec, tmp_path_factory.mktemp('fm') / 'robot')


def _frf(out):
    d = json.loads((out / 'frf.json').read_text())
    return np.asarray(d['freq_hz']), np.asarray(d['re']) + 1j * np.asarray(d['im']), d


def test_printed_detection_given_back_gives_the_same_frf(foreign_ms_bag, tmp_path, capsys):
    assert main(['estimate', str(foreign_ms_bag), '--out', str(tmp_path / 'auto')]) == 0
    said = capsys.readouterr().out
    m = re.search(r'detected: (\w+) \(torque\): (?:odd )?multisine: period \d+ samples '
                  r'\(([0-9.]+) s', said)
    assert m, said
    assert main(['estimate', str(foreign_ms_bag), '--out', str(tmp_path / 'given'),
                 '--input', m.group(1), '--multisine-period', m.group(2)]) == 0
    assert '(period given: 3.072 s)' in capsys.readouterr().out
    f_a, p_a, _ = _frf(tmp_path / 'auto')
    f_g, p_g, _ = _frf(tmp_path / 'given')
    np.testing.assert_array_equal(f_a, f_g)
    np.testing.assert_allclose(p_g, p_a, rtol=1e-9)
    # a band keeps only the lines inside it (weak ones the whole band's median dropped may
    # come back), with the same values at the lines both analyse
    assert main(['estimate', str(foreign_ms_bag), '--out', str(tmp_path / 'band'),
                 '--band', '5', '20']) == 0
    f_b, p_b, _ = _frf(tmp_path / 'band')
    assert f_b.min() >= 5 and f_b.max() <= 20
    inside = (f_a >= 5) & (f_a <= 20)
    assert np.all(np.isin(f_a[inside], f_b))
    np.testing.assert_allclose(p_b[..., np.isin(f_b, f_a)], p_a[..., inside], rtol=1e-9)


def test_narrow_chirp_needs_its_band_given(plant_loop, foreign_ms_bag, tmp_path, capsys):
    """
    Test that a narrow chirp needs its band given.

    A 10-14 Hz exponential chirp spans a frequency ratio of 1.4, below the chirp detector's
    1.5: detection takes it for a 2-line periodic signal whose period is not a whole number
    of samples, which is refused. Given band and times fix that.
    """
    t = np.arange(int(12 * FS)) / FS
    a0 = np.log(14.0 / 10.0) / 10.0
    r2 = 0.01 * np.sin(chirp_phase(t, a0, np.log(10.0) - a0 * 1.0, 1.0))
    r2[(t < 1.0) | (t > 11.0)] = 0.0
    bag = write_recording(_closed_loop(plant_loop, r2), tmp_path / 'chirp')
    # taken for a 2-line multisine its 'period' is not a whole number of samples: refused
    refused(bag, capsys, match=('detected multisine of joint_2', 'not a whole number',
                                '--chirp'))
    refused(bag, capsys, '--chirp', '10', '14', match=('expected both',))
    assert main(['estimate', str(bag), '--out', str(tmp_path / 'e'), '--input', 'joint_2',
                 '--chirp', '10', '14', '--chirp-time', '1', '11']) == 0
    assert 'exponential chirp 10-14 Hz from t0 = 1 s to t1 = 11 s' in capsys.readouterr().out
    f_c, p_c, d = _frf(tmp_path / 'e')
    assert f_c.min() >= 10 and f_c.max() <= 14 and f_c.size >= 3
    assert main(['estimate', str(foreign_ms_bag), '--out', str(tmp_path / 'ms')]) == 0
    f_m, p_m, _ = _frf(tmp_path / 'ms')
    o = d['outputs'].index('dq_m/joint_2')
    ref = np.interp(f_c, f_m, np.abs(p_m[o, 0]))   # between multisine lines 0.5 Hz apart
    assert np.max(np.abs(20 * np.log10(np.abs(p_c[o, 0]) / ref))) < 1.5


@pytest.mark.parametrize('args, match', [
    (['--input', 'joint_9'], "input='joint_9' is not a joint of the recording; expected one of"),
    (['--multisine-period', '30'], 'multisine_period=30 s in a recording of 15.36 s: 0 whole'),
    (['--band', '5', '600'], 'reaches the Nyquist frequency 500 Hz of the recording'),
    (['--chirp', '1', '700', '--chirp-time', '0', '5'], 'chirp=(1.0, 700.0): band 1-700 Hz'),
    (['--chirp', '1', '10', '--chirp-time', '3', '50'], 'chirp_time=(3.0, 50.0): expected'),
])
def test_bad_options_refused(foreign_ms_bag, capsys, args, match):
    refused(foreign_ms_bag, capsys, *args, match=(str(foreign_ms_bag), match))


@STREAM
def test_joints_pick_channels_of_the_estimate_with_every_excited_joint(ms_bag, tmp_path,
                                                                       mode):
    """
    --joints joint_1,joint_3 is the full estimate's [0, 2] x [0, 2] channels.

    It was estimated from those two inputs alone, the third joint's response taken for
    theirs: on this short run the median error to the analytic FRF is 0.029 dB so, 0.004 dB
    picked (printed).
    """
    from frf_ident.core.estimation.frd import FrequencyResponse
    full, sub = tmp_path / 'full', tmp_path / 'sub'
    assert main(['estimate', str(ms_bag), '--out', str(full)]) == 0
    assert main(['estimate', str(ms_bag), '--out', str(sub), '--joints', 'joint_1,joint_3',
                 *mode]) == 0
    a, b = (FrequencyResponse.from_dict(json.loads((d / 'frf.json').read_text()))
            for d in (full, sub))
    assert b.inputs == ['tau_m/joint_1', 'tau_m/joint_3'], b.inputs
    assert b.outputs == ['dq_m/joint_1', 'dq_m/joint_3'], b.outputs
    np.testing.assert_allclose(b.response, a.response[np.ix_([0, 2], [0, 2])], rtol=1e-12)
    # against the analytic FRF: the estimate from the two inputs alone (the old --joints)
    from frf_ident.bag import read_recording
    from frf_ident.core.estimation.described import estimate_recording
    from frf_ident.core.model.schema import default_model_dict, robot_from_dict
    from frf_ident.core.simulation.analytic import robot_frf_sampled
    truth = robot_frf_sampled(robot_from_dict(default_model_dict()).linear(),
                              b.freq_hz)[np.ix_([0, 2], [0, 2])]
    alone = estimate_recording(read_recording(ms_bag,
                                              joints=['joint_1', 'joint_3'])[0])['multisine']
    err = [float(np.median(np.abs(20 * np.log10(np.abs(e.response / truth)))))
           for e in (b, alone)]
    print(f'median error to the analytic FRF: picked {err[0]:.2g} dB, from the two inputs '
          f'alone {err[1]:.2g} dB')
    assert err[0] < 0.3 * err[1]
    lines_a, lines_b = (e.meta.get('detection_lines') for e in (a, b))
    # per output channel: those of joints 1 and 3
    assert lines_b['odd_db'] == [lines_a['odd_db'][i] for i in (0, 2)]
    assert main(['estimate', str(ms_bag), '--out', str(tmp_path / 'x'), '--joints',
                 'joint_1,joint_9', *mode]) == 2


@STREAM
def test_joints_leave_out_a_joint_the_experiment_never_drove(ms_rec, ms_bag, tmp_path, mode):
    """
    A fourth joint without excitation (a gripper) stays out of the estimate.

    Taking every joint of /joint_states, '4 inputs from 3 experiments' was refused.
    """
    from frf_ident.core.estimation.frd import FrequencyResponse
    n = ms_rec.t.size

    def add(a, fill):
        return None if a is None else np.c_[a, np.full(n, fill)]
    rec = _copy_rec(ms_rec, joint_names=list(ms_rec.joint_names) + ['gripper'],
                    position=add(ms_rec.position, 0.0), velocity=add(ms_rec.velocity, 0.0),
                    effort=add(ms_rec.effort, 0.0), reference=add(ms_rec.reference, np.nan),
                    excitation=add(ms_rec.excitation, np.nan))
    bag = write_recording(rec, tmp_path / 'four')
    full, sub = tmp_path / 'full', tmp_path / 'sub'
    assert main(['estimate', str(ms_bag), '--out', str(full)]) == 0
    assert main(['estimate', str(bag), '--out', str(sub), '--joints', 'joint_1,joint_3',
                 *mode]) == 0
    a, b = (FrequencyResponse.from_dict(json.loads((d / 'frf.json').read_text()))
            for d in (full, sub))
    np.testing.assert_allclose(b.response, a.response[np.ix_([0, 2], [0, 2])], rtol=1e-9)


@STREAM
def test_a_bag_whose_runs_were_all_cut_short_says_so(ms_rec, tmp_path, capsys, monkeypatch,
                                                     mode):
    """
    No end events, an abort: one line, exit 2, in memory and streamed alike.

    Streamed, it fell through to excitation detection ('no experiment descriptors'), or ended
    in a StopIteration (exit 1) when a segment that did end gave no estimate.
    """
    import frf_ident.bag.writer as writer
    events = writer._experiment_events

    def cut(rec, stamps):
        out = [e for e in events(rec, stamps) if json.loads(e[2]).get('event') != 'end']
        abort = {'event': 'aborted', 'procedure': 'multisine', 'reason': 'shutdown',
                 't_start': 0.0, 't_end': float(rec.t[-1])}
        return out + [(out[-1][0] + 1, 3, json.dumps(abort))]
    monkeypatch.setattr(writer, '_experiment_events', cut)
    bag = write_recording(ms_rec, tmp_path / 'cut')
    capsys.readouterr()
    assert main(['estimate', str(bag), '--out', str(tmp_path / 'e'), *mode]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'every experiment of the recording was cut short' in err[0], err


@STREAM
def test_a_realisation_cut_short_is_left_out_and_the_rest_estimated(tmp_path, capsys,
                                                                    monkeypatch, mode):
    """
    Abort in realisation 1's last experiment: realisation 0 is estimated, the cut one named.

    The estimate refused the whole design (then 'multisine segments incomplete').
    """
    import frf_ident.bag.writer as writer
    model, _, ctrl = load_model(None)
    cfg = IdentificationConfig(MultisineConfig(n_realisations=2, n_periods=2, resolution_hz=1.0,
                                               compensate=False), None)
    rec = run_identification(load_plant(None, model), ctrl, cfg)
    last = max((s for s in rec.segments if s.info.get('realisation') == 1),
               key=lambda s: s.t_start)
    events = writer._experiment_events

    def cut(r, stamps):
        out = [e for e in events(r, stamps)
               if not (json.loads(e[2]).get('event') == 'end'
                       and json.loads(e[2]).get('t_start') == last.t_start)]
        abort = {'event': 'aborted', 'procedure': 'multisine', 'reason': 'shutdown',
                 't_start': 0.0, 't_end': last.t_end}
        return out + [(out[-1][0] + 1, 3, json.dumps(abort))]
    monkeypatch.setattr(writer, '_experiment_events', cut)
    bag = write_recording(rec, tmp_path / 'cut')
    capsys.readouterr()
    assert main(['estimate', str(bag), '--out', str(tmp_path / 'e'), *mode]) == 0
    said = capsys.readouterr().out
    assert 'realisation(s) [1] cut short' in said, said
    frf = json.loads((tmp_path / 'e' / 'frf.json').read_text())
    assert frf['meta']['n_p'] == 1 and frf['meta']['dropped']['incomplete'] == [1]


@pytest.fixture(scope='module')
def ms_and_chirp_rec():
    """One multisine realisation (3 experiments) and two chirp iterations (3 experiments each)."""
    from frf_ident.core.excitation.chirp_iteration import ChirpConfig
    model, _, ctrl = load_model(None)
    cfg = IdentificationConfig(MultisineConfig(n_realisations=1, n_periods=2, resolution_hz=1.0,
                                               compensate=False),
                               ChirpConfig(duration=4.0, max_iterations=2))
    return run_identification(load_plant(None, model), ctrl, cfg)


def _never_ended(monkeypatch, segments):
    """Write bags as if ``segments`` never ended (their 'end' events lost: a run aborted)."""
    import frf_ident.bag.writer as writer
    events = writer._experiment_events
    starts = {s.t_start for s in segments}

    def cut(r, stamps):
        return [e for e in events(r, stamps)
                if not (json.loads(e[2]).get('event') == 'end'
                        and json.loads(e[2]).get('t_start') in starts)]
    monkeypatch.setattr(writer, '_experiment_events', cut)


@STREAM
def test_a_multisine_cut_in_its_last_experiment_takes_no_chirp_with_it(
        ms_and_chirp_rec, tmp_path, capsys, monkeypatch, mode):
    """
    The run aborted in the multisine's last experiment; the chirps after it completed.

    The bag was refused ('n_ex=2 experiments cannot identify n_u=3 inputs': the missing third
    experiment went unnoticed) and the chirp lost with it. The chirp estimate must equal that
    of the same bag with nothing cut; without the chirp the refusal names the missing
    experiment.
    """
    rec = ms_and_chirp_rec
    last = max((s for s in rec.segments if s.info.get('design') == 'multisine'),
               key=lambda s: s.t_start)
    whole = write_recording(rec, tmp_path / 'whole')
    _never_ended(monkeypatch, [last])
    bag = write_recording(rec, tmp_path / 'cut')
    capsys.readouterr()
    assert main(['estimate', str(bag), '--out', str(tmp_path / 'e'), *mode]) == 0
    said = capsys.readouterr().out
    assert 'left out: multisine: no realisation is complete' in said, said
    assert main(['estimate', str(whole), '--out', str(tmp_path / 'w'), *mode]) == 0
    cut_est, whole_est = (json.loads((d / 'estimates.json').read_text())
                          for d in (tmp_path / 'e', tmp_path / 'w'))
    assert sorted(cut_est) == ['chirp', 'chirp_reference']
    assert 'multisine' in whole_est
    for key in ('freq_hz', 're', 'im'):
        np.testing.assert_array_equal(cut_est['chirp'][key], whole_est['chirp'][key])
    no_chirp = Recording(rec.t, rec.joint_names, rec.position, rec.velocity, rec.effort,
                         reference=rec.reference, excitation=rec.excitation,
                         segments=[s for s in rec.segments if s.info.get('design') != 'chirp'],
                         meta=dict(rec.meta))
    only = write_recording(no_chirp, tmp_path / 'only')
    refused(only, capsys, *mode, match=('no multisine realisation is complete',
                                        '(realisation, experiment) = [(0, 2)]'))


@STREAM
def test_a_chirp_iteration_cut_short_leaves_the_last_complete_one(
        ms_and_chirp_rec, tmp_path, capsys, monkeypatch, mode):
    """
    Iteration 2 aborted in its last experiment: iteration 1 is the chirp estimate.

    Every iteration cut: the multisine alone, named; a chirp-only bag so cut is refused.
    The audit's bag with chirp iteration 1 aborted after its first experiment was refused
    with 'n_ex=1 experiments cannot identify n_u=3 inputs'.
    """
    from frf_ident.bag import read_recording
    from frf_ident.core.estimation.chirp_estimate import chirp_frf
    rec = ms_and_chirp_rec
    chirps = [s for s in rec.segments if s.info.get('design') == 'chirp']
    last_of = {it: max((s for s in chirps if s.info['iteration'] == it),
                       key=lambda s: s.t_start) for it in (1, 2)}
    whole = write_recording(rec, tmp_path / 'whole')
    with monkeypatch.context() as m:
        _never_ended(m, [last_of[2]])
        bag = write_recording(rec, tmp_path / 'cut2')
    capsys.readouterr()
    assert main(['estimate', str(bag), '--out', str(tmp_path / 'e'), *mode]) == 0
    said = capsys.readouterr().out
    assert 'left out: chirp: iteration 2 was cut short; iteration 1 is estimated' in said, said
    got = json.loads((tmp_path / 'e' / 'estimates.json').read_text())['chirp']
    want = chirp_frf(read_recording(whole)[0], iteration=1)
    assert got['meta']['iteration'] == 1
    np.testing.assert_allclose(np.asarray(got['re']) + 1j * np.asarray(got['im']),
                               want.response, rtol=1e-9)     # streamed: 5e-11
    with monkeypatch.context() as m:
        _never_ended(m, list(last_of.values()))
        both = write_recording(rec, tmp_path / 'cut12')
    capsys.readouterr()
    assert main(['estimate', str(both), '--out', str(tmp_path / 'b'), *mode]) == 0
    assert 'left out: chirp: no iteration is complete' in capsys.readouterr().out
    assert sorted(json.loads((tmp_path / 'b' / 'estimates.json').read_text())) == [
        'multisine', 'multisine_plain']
    only = Recording(rec.t, rec.joint_names, rec.position, rec.velocity, rec.effort,
                     reference=rec.reference, excitation=rec.excitation, segments=chirps,
                     meta=dict(rec.meta))
    with monkeypatch.context() as m:
        _never_ended(m, list(last_of.values()))
        chirp_only = write_recording(only, tmp_path / 'chirp_only')
    refused(chirp_only, capsys, *mode, match=('chirp iteration 2 is incomplete',
                                              'experiments [0, 1] of 3',
                                              'no chirp iteration is complete'))
