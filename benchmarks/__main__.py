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
`make bench`: speed and accuracy figures, each beside a baseline measured in the same run.

Sections (run all, or name some: ``python -m benchmarks simulation estimation``; with
``--markdown`` the runs also go to docs/BENCHMARKS.md, see benchmarks/markdown.py):

- simulation — closed-loop 3-axis plant at 1 kHz (PI in the loop, Coulomb friction, ripple,
  gravity): simulated seconds per wall second, against real time (goal >= 1000x).
- estimation — multisine BLA (eq. 14) vs a plain scipy.signal.csd/welch H1 estimate on the same
  3x3 data: wall time and error against the analytic FRF.
- stream — a bag without descriptors estimated in 60 s blocks vs read into memory: peak
  memory for 5 and 20 min of data (bounded memory for bags larger than RAM).
Further sections register themselves in SECTIONS (closed-loop procedures, node graph, bags).
"""
from __future__ import annotations

import sys
import time
from typing import Callable

import numpy as np

SECTIONS: dict[str, Callable[[], list[tuple[str, str, str, str]]]] = {}


def section(name: str):
    def register(fn):
        SECTIONS[name] = fn
        return fn
    return register


def _timeit(fn: Callable[[], object], repeat: int = 3) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def bench_robot():
    """Return the default 3-axis model with the effects a real robot has (friction, ripple)."""
    from frf_ident.core.model.schema import default_robot
    rob = default_robot().with_axes(coulomb_friction=15.0)
    for a in rob.axes:
        a.torque_ripple = [{'amplitude': 3.0, 'spatial_frequency': 60.0, 'phase': 0.0}]
    return rob


@section('simulation')
def bench_simulation() -> list[tuple[str, str, str, str]]:
    """Simulate the 3-axis closed loop at 1 kHz (PI, friction, ripple) against real time."""
    from frf_ident.core.model.schema import default_model_dict
    from frf_ident.core.simulation.controller import controller_from_dict
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    rows = []
    for substeps in (1, 2):
        rob = bench_robot()
        rob.substeps = substeps
        plant = FlexibleJointPlant(rob)
        ctrl = controller_from_dict(default_model_dict(), rob)
        n = 200_000
        t = np.arange(n) * rob.dt
        r = 0.05 + 0.02 * np.sin(2 * np.pi * 3 * t)[:, None] * np.ones(3)
        plant.simulate(reference=r[:10], controller=ctrl)            # compile
        wall, _ = _timeit(lambda: plant.simulate(reference=r, controller=ctrl.copy()), 3)
        rows.append((f'closed loop 3 axes 1 kHz, substeps={substeps}',
                     f'{n * rob.dt / wall:,.0f}x real time', '1x (real time)',
                     f'{n * rob.dt / wall:,.0f}'))
    return rows


@section('layout')
def bench_layout() -> list[tuple[str, str, str, str]]:
    """Count cycles, upward arrows, long modules and functions, dicts and meta keys; before."""
    from benchmarks.layout import rows
    return rows()


@section('discretisation')
def bench_discretisation() -> list[tuple[str, str, str, str]]:
    """
    Measure the plant's discretisation error per effect against a converged simulation.

    The linear part is integrated exactly (the baseline column); each nonlinear effect adds an
    error that falls with the substeps as its order says (log2 of the error ratio from m to
    2 m, the last column).
    """
    from benchmarks.discretisation import rows
    return rows()


@section('ripple_threshold')
def bench_ripple_threshold() -> list[tuple[str, str, str, str]]:
    """Measure the ripple scan's false-alarm rate on white noise, calibrated vs ln(M / alpha)."""
    from benchmarks.ripple_threshold import rows
    return rows()


@section('estimation')
def bench_estimation() -> list[tuple[str, str, str, str]]:
    """Estimate a 3x3 FRF by the multisine BLA and by scipy's csd H1 from the same periods."""
    from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
    from frf_ident.core.model.schema import default_robot
    from frf_ident.core.simulation.analytic import robot_frf
    from frf_ident.core.simulation.open_loop import stage_grid
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    from scipy import signal
    fs = 1000.0
    rob = default_robot().with_axes(viscous_friction=0.0, gravity_torque=0.0)
    d = design_odd_multisine(2.0, 60.0, bound=80.0, resolution_hz=0.25, fs=fs)
    n_p, n_q = 10, 5
    plant = FlexibleJointPlant(rob)
    rng = np.random.default_rng(0)
    truth = robot_frf(rob, d.freq_hz)
    # one simulation (per realisation and eq. 9 experiment: u, y after a transient period),
    # the same time series for both estimators
    n_per = d.period_samples(fs)
    us, ys = [], []
    for _ in range(n_p):
        real = multisine_realisation(d, 3, rng, fs=fs)
        sig = real.evaluate(stage_grid((n_q + 1) * n_per, fs, rob.substeps))
        for m in range(3):
            plant.reset()
            res = plant.simulate(torque_fine=sig[m])
            us.append(res.effort[n_per:])
            ys.append(res.velocity[n_per:])
    U = np.stack(us)            # (n_exp, N, 3)
    Y = np.stack(ys)

    def bla():
        from frf_ident.core.estimation.spectra import best_linear_approximation, periodic_spectra
        Ur = U.reshape(n_p, 3, n_q, n_per, 3)
        Yr = Y.reshape(n_p, 3, n_q, n_per, 3)
        Us = periodic_spectra(Ur, d.harmonics, axis=3)       # (p, m, q, f, ch)
        Ys = periodic_spectra(Yr, d.harmonics, axis=3)
        Us = np.moveaxis(Us, 1, -1)                          # (p, q, f, ch, m)
        Ys = np.moveaxis(Ys, 1, -1)
        return best_linear_approximation(Ys, Us).response

    def h1():
        # the same averaging as the BLA: one rectangular segment per steady-state period of
        # every realisation and experiment (no overlap), cross spectra summed, H1 = Syu Suu^-1
        f, _ = signal.welch(U[0, :n_per, 0], fs=fs, nperseg=n_per, window='boxcar')
        Suu = np.zeros((f.size, 3, 3), complex)
        Syu = np.zeros((f.size, 3, 3), complex)
        kw = {'fs': fs, 'nperseg': n_per, 'noverlap': 0, 'window': 'boxcar', 'detrend': False}
        for e in range(U.shape[0]):
            for i in range(3):
                for j in range(3):
                    Suu[:, i, j] += signal.csd(U[e, :, i], U[e, :, j], **kw)[1]
                    Syu[:, i, j] += signal.csd(U[e, :, j], Y[e, :, i], **kw)[1]
        H = Syu @ np.linalg.inv(Suu)
        return f, np.moveaxis(H, 0, -1)

    t_bla, P_bla = _timeit(bla, 3)
    t_h1, (f_h1, P_h1) = _timeit(h1, 3)
    err_bla = np.median(np.abs(20 * np.log10(np.abs(P_bla / truth))))
    sel = d.harmonics                   # bin k of a one-period segment is k f0: the excited lines
    assert np.allclose(f_h1[sel], d.freq_hz)
    err_h1 = np.median(np.abs(20 * np.log10(np.abs(P_h1[:, :, sel] / truth))))
    return [
        (f'3x3 FRF, n_p={n_p} x n_q={n_q} x {n_per} samples, best of 3',
         f'BLA {t_bla * 1e3:.0f} ms', f'csd H1 same periods {t_h1 * 1e3:.0f} ms',
         f'{t_h1 / t_bla:.1f}x faster'),
        ('median |error| vs analytic, excited lines', f'BLA {err_bla:.2g} dB',
         f'H1 {err_h1:.2g} dB',
         f'{err_h1 / max(err_bla, 1e-12):.0f}x smaller'),
    ]


def _db_error(est, truth) -> float:
    """RMS over lines of the per-line MIMO error 20 log10(1 + ||P_hat - P|| / ||P||)."""
    n = truth.shape[0]
    e = np.linalg.norm((est - truth).reshape(n * n, -1), axis=0) / np.linalg.norm(
        truth.reshape(n * n, -1), axis=0)
    return float(np.sqrt(np.mean((20 * np.log10(1 + e)) ** 2)))


@section('experiment_time')
def bench_experiment_time() -> list[tuple[str, str, str, str]]:
    """
    Measure the experiment time each procedure needs for a 3x3 FRF within 1 dB of truth.

    Nominal linear 3-axis model, 40 dB SNR output noise; compared with the paper's totals.
    """
    from frf_ident.core.estimation.chirp_estimate import chirp_frf
    from frf_ident.core.estimation.described import multisine_frf
    from frf_ident.core.excitation.chirp_iteration import ChirpConfig
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    from frf_ident.core.model.schema import default_model_dict, robot_from_dict
    from frf_ident.core.simulation.analytic import robot_frf_sampled
    from frf_ident.core.simulation.controller import controller_from_dict
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    from frf_ident.core.simulation.runner import IdentificationConfig, run_identification
    d = default_model_dict()
    rob = robot_from_dict(d)
    ctrl = controller_from_dict(d, rob)
    for a in rob.axes:
        a.velocity_noise = 4.5e-6          # 1 % of the multisine velocity rms: 40 dB SNR
    rows = []
    for resolution in (0.1, MultisineConfig.resolution_hz):
        found = None
        for n_p in range(1, 11):
            for n_q in (2, 3, 5):
                ms = MultisineConfig(n_realisations=n_p, n_periods=n_q, resolution_hz=resolution)
                rec = run_identification(FlexibleJointPlant(rob), ctrl.copy(),
                                         IdentificationConfig(ms, None))
                frf, _ = multisine_frf(rec)
                err = _db_error(frf.response, robot_frf_sampled(rob, frf.freq_hz))
                if err <= 1.0:
                    found = (n_p, n_q, rec.meta['summary']['multisine']['experiment_time_s'], err)
                    break
            if found:
                break
        which = "the paper's" if resolution == 0.1 else 'our default'
        if found:
            rows.append((f'multisine to 1 dB at {resolution:g} Hz ({which}; n_p={found[0]}, '
                         f'n_q={found[1]}, {found[3]:.2f} dB)', f'{found[2]:.0f} s',
                         'paper 1845 s at 0.1 Hz', f'{1845 / found[2]:.1f}x shorter'))
        else:
            rows.append((f'multisine to 1 dB at {resolution:g} Hz', 'not reached',
                         'paper 1845 s at 0.1 Hz', '-'))
    rows += _target_rows(rob, ctrl)
    for duration in (5.0, 10.0, 20.0):
        rec = run_identification(FlexibleJointPlant(rob), ctrl.copy(), IdentificationConfig(
            None, ChirpConfig(duration=duration)))
        frf = chirp_frf(rec)
        err = _db_error(frf.response, robot_frf_sampled(rob, frf.freq_hz))
        s = rec.meta['summary']['chirp']
        if err <= 1.0 and s['converged']:
            rows.append((f'chirp to 1 dB ({duration:.0f} s, {s["final_iteration"]} iterations, '
                         f'{err:.2f} dB)', f'{s["experiment_time_s"]:.0f} s', 'paper 720 s',
                         f'{720 / s["experiment_time_s"]:.1f}x shorter'))
            break
    else:
        rows.append(('chirp to 1 dB', 'not reached', 'paper 720 s', '-'))
    return rows


def _target_rows(rob, ctrl) -> list[tuple[str, str, str, str]]:
    """
    Experiment time of the default multisine design with and without a 1 dB sd target.

    The same model and noise as the rows above; without the target the design runs its 10 x 5
    periods; with it the run ends at the first period whose worst diagonal sd is <= 1 dB
    (docs/live.md). Both FRFs are judged against the exact sampled one (_db_error).
    """
    from frf_ident.core.estimation.described import multisine_frf
    from frf_ident.core.estimation.target import UncertaintyTarget
    from frf_ident.core.excitation.multisine_procedure import MultisineConfig
    from frf_ident.core.simulation.analytic import robot_frf_sampled
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    from frf_ident.core.simulation.runner import IdentificationConfig, run_identification
    out = {}
    for name, target in (('without', None), ('with', UncertaintyTarget(1.0))):
        rec = run_identification(FlexibleJointPlant(rob), ctrl.copy(), IdentificationConfig(
            MultisineConfig(), None, target))
        frf, _ = multisine_frf(rec)
        err = _db_error(frf.response, robot_frf_sampled(rob, frf.freq_hz))
        s = rec.meta['summary']['multisine']
        periods = (s['target'] or {}).get('periods') or 50
        out[name] = (s['experiment_time_s'], err, periods)
    (t1, e1, n1), (t0, e0, _) = out['with'], out['without']
    return [(f'multisine 0.25 Hz, target sd 1 dB (stopped after {n1} periods, {e1:.2f} dB)',
             f'{t1:.0f} s', f'no target: 10 x 5 periods {t0:.0f} s ({e0:.2f} dB)',
             f'{t0 / t1:.1f}x shorter')]


@section('chirp_iteration')
def bench_chirp_iteration() -> list[tuple[str, str, str, str]]:
    """
    Count the chirp iterations (Sec. 5.3) until the plant input is within 1 dB of U_des.

    The nominal 3-axis model, linear and with Coulomb friction of 15, 20 and 8 N m (the demo
    robot's), 20 s chirps; the error is the worst channel's RMS dB error to U_des.
    """
    from frf_ident.core.excitation.chirp_iteration import ChirpConfig
    from frf_ident.core.model.schema import default_model_dict, robot_from_dict
    from frf_ident.core.simulation.controller import controller_from_dict
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    from frf_ident.core.simulation.runner import IdentificationConfig, run_identification
    rows = []
    for label, friction in (('linear model', (0.0, 0.0, 0.0)),
                            ('Coulomb friction 15/20/8 N m', (15.0, 20.0, 8.0))):
        d = default_model_dict()
        rob = robot_from_dict(d)
        ctrl = controller_from_dict(d, rob)
        for a, fc in zip(rob.axes, friction):
            a.coulomb_friction = fc
        rec = run_identification(FlexibleJointPlant(rob), ctrl, IdentificationConfig(
            None, ChirpConfig()))
        c = rec.meta['summary']['chirp']
        errs = [it['max_abs_error_db'] for it in c['iterations']]
        done = '' if c['converged'] else ' (not converged)'
        rows.append((f'chirp iteration to +-1 dB, {label}',
                     f"{c['final_iteration']} iterations{done}",
                     f'first {errs[0]:.1f} dB', f'last {errs[-1]:.2f} dB'))
    return rows


@section('bag_read')
def bench_bag_read() -> list[tuple[str, str, str, str]]:
    """Read the joint states of a 2-minute 6-joint bag, against rosbags' AnyReader."""
    from pathlib import Path
    import tempfile

    from benchmarks.bag_read import bench_read
    from frf_ident.bag import write_recording
    from frf_ident.core.recording import Recording
    n, joints = 120_000, ['joint_1', 'joint_2', 'joint_3', 'joint_4', 'joint_5', 'joint_6']
    t = np.arange(n) * 1e-3
    x = np.sin(np.outer(t, np.arange(1, 7)))
    rec = Recording(t, joints, x, x, x, x, x)
    with tempfile.TemporaryDirectory() as tmp:
        path = write_recording(rec, Path(tmp) / 'bench_bag')
        r = bench_read(path)
    ours, base = r['frf_ident'], r['rosbags_anyreader']
    mb = 1024 ** 2
    return [(f"read {r['joint_state_messages']:,} JointState msgs (6 joints)",
             f"{ours['joint_states_per_s']:,.0f} msg/s",
             f"AnyReader {base['joint_states_per_s']:,.0f} msg/s", f"{r['speedup']:.1f}x"),
            ('peak memory while reading (ours builds the arrays)',
             f"{ours['peak_bytes'] / mb:.0f} MB", f"AnyReader {base['peak_bytes'] / mb:.0f} MB",
             f"{ours['peak_bytes'] / max(base['peak_bytes'], 1):.1f}x")]


def periodic_multisine_run(duration_s: float, seed: int = 0, fs: float = 1000.0):
    """
    Simulate a long run without descriptors, as a robot's own bag would be.

    The 3-axis model in closed loop, a periodic odd multisine velocity reference on joint_2
    (2-60 Hz, 0.5 Hz resolution), 1e-3 rad/s noise on the measured velocity.
    """
    from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
    from frf_ident.core.model.schema import default_model_dict, robot_from_dict
    from frf_ident.core.recording import Recording
    from frf_ident.core.simulation.controller import controller_from_dict
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    d = default_model_dict()
    rob = robot_from_dict(d)
    ctrl = controller_from_dict(d, rob)
    des = design_odd_multisine(2.0, 60.0, bound=0.01, resolution_hz=0.5, fs=fs)
    real = multisine_realisation(des, 1, np.random.default_rng(seed), fs=fs)
    n = des.period_samples(fs)
    reps = int(duration_s * fs) // n
    r = np.zeros((reps * n, 3))
    r[:, 1] = np.tile(real.evaluate(np.arange(n) / fs)[0][:, 0], reps)
    res = FlexibleJointPlant(rob).simulate(reference=r, controller=ctrl)
    noise = np.random.default_rng(seed + 1).normal(0.0, 1e-3, res.velocity.shape)
    return Recording(res.t, rob.joint_names, res.position, res.velocity + noise, res.effort,
                     reference=r)


@section('stream')
def bench_stream() -> list[tuple[str, str, str, str]]:
    """
    Compare peak memory of a streamed and an in-memory estimate of a descriptor-less bag.

    Peak traced memory for a 5 min and a 20 min bag (the streamed one must stay flat), at the
    block length `frf-ident estimate` uses by default.
    """
    from pathlib import Path
    import tempfile

    from benchmarks.bag_read import measure
    from frf_ident.app.stream_estimate import stream_estimate
    from frf_ident.bag import read_recording, write_recording
    from frf_ident.core.estimation.described import estimate_recording
    from frf_ident.core.estimation.detected import DEFAULT_WINDOW_S
    rows = []
    mb = 1024 ** 2
    with tempfile.TemporaryDirectory() as tmp:
        for minutes in (5, 20):
            path = write_recording(periodic_multisine_run(60.0 * minutes),
                                   Path(tmp) / f'long_{minutes}')
            size = sum(f.stat().st_size for f in path.glob('*.mcap'))
            s_sec, s_peak = measure(lambda: stream_estimate(path, window_s=DEFAULT_WINDOW_S))
            m_sec, m_peak = measure(lambda: estimate_recording(read_recording(path)[0]))
            rows.append((f'{minutes} min bag ({size / mb:.0f} MB): streamed '
                         f'({DEFAULT_WINDOW_S:.0f} s blocks, the CLI default) peak / time',
                         f'{s_peak / mb:.0f} MB / {s_sec:.1f} s',
                         f'in memory {m_peak / mb:.0f} MB / {m_sec:.1f} s',
                         f'{m_peak / max(s_peak, 1):.1f}x less'))
    return rows


@section('lpm')
def bench_lpm() -> list[tuple[str, str, str, str]]:
    """Time the LPM on a 3x3 record of 10^6 samples beside per-line np.linalg.lstsq."""
    from benchmarks.lpm import rows
    return rows()


@section('missing')
def bench_missing() -> list[tuple[str, str, str, str]]:
    """Time the LPM and the multisine with missing samples beside the records without gaps."""
    from benchmarks.missing import rows
    return rows()


@section('diagnosis')
def bench_diagnosis() -> list[tuple[str, str, str, str]]:
    """Run the diagnosis sweep over random 3-axis scenes of the independent plant."""
    from benchmarks.diagnosis import bench_rows
    return bench_rows()


@section('second_mode')
def bench_second_mode() -> list[tuple[str, str, str, str]]:
    """Second link-side modes found in reference-plant scenes, false alarms on clean ones."""
    from benchmarks.second_mode import bench_rows
    return bench_rows()


@section('diagnosis_uncertainty')
def bench_diagnosis_uncertainty() -> list[tuple[str, str, str, str]]:
    """Check diagnosed values against their standard errors: pair scenes, a Monte Carlo."""
    from benchmarks.diagnosis_uncertainty import rows
    return rows()


@section('diagnosis_demo')
def bench_diagnosis_demo() -> list[tuple[str, str, str, str]]:
    """Diagnose the demo bag with its simulations on 1 and on 2 processes: wall time."""
    from benchmarks.diagnosis_demo import rows
    return rows()


@section('diagnosis_sensor')
def bench_diagnosis_sensor() -> list[tuple[str, str, str, str]]:
    """Sweep scenes with a realistic sensor: nominal, and two small effects on two axes."""
    from benchmarks.diagnosis_sensor import rows
    return rows()


@section('diagnosis_real')
def bench_diagnosis_real() -> list[tuple[str, str, str, str]]:
    """Compare the KUKA KR300 diagnosis of the halves of trajectory A (and of A, B, C)."""
    from benchmarks.diagnosis_kuka import kuka_halves_rows, kuka_trajectories_rows
    from benchmarks.diagnosis_kuka_baseline import kuka_baseline_rows
    from benchmarks.diagnosis_kuka_synthetic import kuka_synthetic_halves_rows
    return (kuka_baseline_rows() + kuka_halves_rows() + kuka_synthetic_halves_rows()
            + kuka_trajectories_rows())


@section('band')
def bench_band() -> list[tuple[str, str, str, str]]:
    """Show the analysis band and the residual scan above it on EMPS and KUKA A (figure)."""
    from benchmarks.band import rows
    return rows()


@section('nodes')
def bench_nodes() -> list[tuple[str, str, str, str]]:
    """Measure the node graph's lockstep steps/s beside the same backend's ping-pong."""
    from benchmarks.graph import rows
    return rows()


@section('live_graph')
def bench_live_graph() -> list[tuple[str, str, str, str]]:
    """Run the lockstep graph with the live estimate on and off, alternating, same run."""
    from benchmarks.live_graph import rows
    return rows()


@section('campaign')
def bench_campaign() -> list[tuple[str, str, str, str]]:
    """Estimate 8 demo bags serially and with --jobs 2: speed-up, identity, peak memory."""
    from benchmarks.campaign import rows
    return rows()


@section('busy_graph')
def bench_busy_graph() -> list[tuple[str, str, str, str]]:
    """Run the lockstep graph (multisine + 3 chirp iterations) beside two busy loops."""
    from benchmarks.busy_graph import rows
    return rows()


@section('replay')
def bench_replay() -> list[tuple[str, str, str, str]]:
    """Run the longer hypothesis search over bag imperfections."""
    from benchmarks.replay_properties import bench_replay as rows
    return rows()


@section('fit')
def bench_fit() -> list[tuple[str, str, str, str]]:
    """Time the rational and physical fits of a 3x3 FRF of 100 lines beside baselines."""
    from benchmarks.fit import rows
    return rows()


@section('fit_trust')
def bench_fit_trust() -> list[tuple[str, str, str, str]]:
    """Errors under a missing mode and the stable order choice, beside the old fits."""
    from benchmarks.fit_trust import rows
    return rows()


@section('real_data')
def bench_real_data() -> list[tuple[str, str, str, str]]:
    """Estimate the real data sets of ../shared/data through their maps, with figures."""
    from benchmarks.real_data import rows
    return rows()


@section('poses')
def bench_poses() -> list[tuple[str, str, str, str]]:
    """Run the 9-pose simulated campaign: one bag, estimate, fit, held-out pose model."""
    from benchmarks.poses import rows
    return rows()


@section('mujoco')
def bench_mujoco() -> list[tuple[str, str, str, str]]:
    """Run the iiwa 14 closed loop (3 axes, 1 kHz) in MuJoCo beside our own plant."""
    from benchmarks.mujoco_plant import rows
    return rows()


@section('tune')
def bench_tune() -> list[tuple[str, str, str, str]]:
    """Time ``frf-ident tune`` on a 3x3 FRF campaign of 9 poses beside ``loop --propose``."""
    from benchmarks.tune import rows
    return rows()


def main(argv: list[str] | None = None) -> int:
    """
    Run the named sections (all without names) and print their rows.

    With ``--markdown`` each section's run is also stored under docs/benchmarks/ and
    docs/BENCHMARKS.md is rendered again from every stored run (benchmarks/markdown.py).
    """
    args = list(argv if argv is not None else sys.argv[1:])
    markdown = '--markdown' in args
    args_names = [a for a in args if a != '--markdown']
    names = args_names or list(SECTIONS)
    unknown = [n for n in names if n not in SECTIONS]
    if unknown:
        print(f'unknown section {unknown[0]!r}; have {sorted(SECTIONS)}', file=sys.stderr)
        return 2
    from benchmarks import markdown as md
    print(f"{'measurement':48s} {'frf_ident':>26s} {'baseline (same run)':>26s} {'ratio':>18s}")
    for name in names:
        started, t0 = md.machine(), time.perf_counter()
        rows = []
        for row in SECTIONS[name]():
            rows.append(row)
            print(f'{row[0]:48s} {row[1]:>26s} {row[2]:>26s} {row[3]:>18s}', flush=True)
        if markdown:
            md.store(name, rows, wall_s=time.perf_counter() - t0, cmd=md.command(args_names),
                     started=started)
    if markdown:
        md.write_page(SECTIONS)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
