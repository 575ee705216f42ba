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
Closed-loop runs and the bags a real robot would record of them (issue 12 tests).

:func:`multisine_run` simulates the default 3-axis plant under its PI velocity controller with
a periodic odd multisine velocity reference on joint_2 (no descriptors: a ros2_control-style
experiment). :func:`write_robot_bag` writes it as /joint_states plus
/velocity_controller/commands with the imperfections real recordings have, and returns what
it did so tests can compare with the truth (:func:`truth_frf`, the plant's exact sampled FRF).

Timing model: sample k is taken at s_k = t0 + k dt + U(+-jitter dt); the joint states carry
the true (spline-interpolated) signals at s_k and the header stamp s_k; the receive (log)
time is s_k + 250 us + Exp(50 us). Commands have no header: their log time is their stamp.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from frf_ident.core.recording import Recording
import numpy as np
from scipy.interpolate import CubicSpline

FS = 1000.0
T0 = 100.0                 # bag clock of the first sample [s]
EXCITED = 1                # joint_2


def multisine_run(n_periods: int = 6, f_high: float = 80.0, bound: float = 0.01,
                  seed: int = 0, lead_s: float = 0.0, tail_s: float = 0.0,
                  period_samples: int = 8192, period_scale: float = 1.0,
                  velocity_noise: float = 0.0, torque_noise: float = 0.0,
                  noise_seed: int = 0) -> Recording:
    """
    Simulate a closed-loop multisine run of the default plant.

    n_periods x ``period_samples`` at 1 kHz (f_high 80 Hz: Ts 2 ms) of the default plant
    in closed loop, the multisine on joint_2's velocity reference; ``lead_s`` / ``tail_s`` of
    a partial period before / after (the reference runs on periodically). ``period_scale``
    stretches the multisine's period in time (1.0002: 8193.6 samples, not a whole number).
    ``velocity_noise`` [rad/s] / ``torque_noise`` [N m]: standard deviations of white
    measurement noise on every axis (the velocity's fed back by the controller), drawn with
    ``noise_seed``.
    """
    from frf_ident.core.excitation.multisine import design_odd_multisine, multisine_realisation
    from frf_ident.core.model.schema import default_model_dict, robot_from_dict
    from frf_ident.core.simulation.controller import controller_from_dict
    from frf_ident.core.simulation.plant import FlexibleJointPlant
    d = default_model_dict()
    for axis in d['axes']:
        axis['velocity_noise'], axis['torque_noise'] = velocity_noise, torque_noise
    d['simulation']['seed'] = noise_seed
    rob = robot_from_dict(d)
    ctrl = controller_from_dict(d, rob)
    des = design_odd_multisine(2.0, f_high, bound=bound, resolution_hz=FS / period_samples,
                               fs=FS)
    real = multisine_realisation(des, 1, np.random.default_rng(seed), fs=FS)
    n = des.period_samples(FS)
    n_lead, n_tail = int(round(lead_s * FS)), int(round(tail_s * FS))
    total = n_lead + int(round(n_periods * n * period_scale)) + n_tail
    r = np.zeros((total, 3))
    t = (np.arange(total) - n_lead) / FS / period_scale
    r[:, EXCITED] = real.evaluate(t)[0][:, 0]
    res = FlexibleJointPlant(rob).simulate(reference=r, controller=ctrl)
    rec = Recording(res.t, rob.joint_names, res.position, res.velocity, res.effort, r)
    rec.meta['robot'] = rob
    rec.meta['period_samples'] = n * period_scale
    return rec


def truth_frf(rec: Recording, freq_hz: np.ndarray) -> np.ndarray:
    """Exact FRF column of joint_2 (outputs x lines) of the simulated plant."""
    from frf_ident.core.simulation.analytic import robot_frf_sampled
    return robot_frf_sampled(rec.meta['robot'], np.asarray(freq_hz))[:, EXCITED, :]


@dataclass
class Imperfections:
    """
    What a recording does to the messages (all optional).

    jitter : stamp jitter, fraction of dt (uniform +-).
    drop : fraction of single joint states lost at random (never first/last).
    bursts : (t_start [s from the first sample], duration [s]) lost on every topic.
    duplicates : fraction of joint states written twice (same stamp).
    reorder : fraction of joint states swapped with their successor in file order.
    head_cut / tail_cut : seconds cut from the start / end (partial periods).
    log_offset : receive time minus header stamp [s] (added to the 250 us latency).
    """

    jitter: float = 0.0
    drop: float = 0.0
    bursts: list[tuple[float, float]] = field(default_factory=list)
    duplicates: float = 0.0
    reorder: float = 0.0
    head_cut: float = 0.0
    tail_cut: float = 0.0
    log_offset: float = 0.0


def _sample_plan(rec: Recording, imp: Imperfections, rng: np.random.Generator):
    n = rec.t.size
    dt = 1.0 / FS
    s = rec.t + rng.uniform(-imp.jitter, imp.jitter, n) * dt
    s[0], s[-1] = rec.t[0], rec.t[-1]
    keep = rng.random(n) >= imp.drop
    keep[[0, -1]] = True
    lost = np.zeros(n, dtype=bool)
    for a, dur in imp.bursts:
        lost |= (rec.t - rec.t[0] >= a) & (rec.t - rec.t[0] < a + dur)
    keep &= ~lost
    span = (rec.t - rec.t[0] >= imp.head_cut) & (rec.t[-1] - rec.t >= imp.tail_cut)
    return s, keep & span, lost


def write_robot_bag(path, rec: Recording, imp: Imperfections | None = None, *, seed: int = 1,
                    commands: bool = True, shuffle: bool = False) -> dict:
    """
    Write ``rec`` as a robot's rosbag2 MCAP bag (rosbags writer; see the module docstring).

    The joint states name the joints in the controller's order (as joint_state_broadcaster
    does; the command arrays follow it), or in a new random order per message (``shuffle``).

    Returns the sample times, the kept mask and the burst mask (for the tests' truth).
    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores
    imp = imp or Imperfections()
    rng = np.random.default_rng(seed)
    ts = get_typestore(Stores.ROS2_JAZZY)
    JointState = ts.types['sensor_msgs/msg/JointState']
    Header = ts.types['std_msgs/msg/Header']
    Time = ts.types['builtin_interfaces/msg/Time']
    F64 = ts.types['std_msgs/msg/Float64MultiArray']
    Layout = ts.types['std_msgs/msg/MultiArrayLayout']
    s, keep, lost = _sample_plan(rec, imp, rng)
    vals = {k: CubicSpline(rec.t, getattr(rec, k), axis=0)(s)
            for k in ('position', 'velocity', 'effort')}
    stamps = np.round((s + T0) * 1e9).astype(np.int64)
    logs = stamps + int(round(imp.log_offset * 1e9)) + 250_000 \
        + rng.exponential(50_000, s.size).astype(np.int64)
    idx = list(np.flatnonzero(keep))
    dups = set(np.flatnonzero(rng.random(len(idx)) < imp.duplicates).tolist())
    order = []
    for i, k in enumerate(idx):
        order.append(k)
        if i in dups:
            order.append(k)
    for i in np.flatnonzero(rng.random(len(order) - 1) < imp.reorder):
        order[i], order[i + 1] = order[i + 1], order[i]
    names = list(rec.joint_names)
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        js = w.add_connection('/joint_states', JointState.__msgtype__, typestore=ts)
        cmd = w.add_connection('/velocity_controller/commands', F64.__msgtype__,
                               typestore=ts) if commands else None
        for k in order:
            perm = rng.permutation(len(names)) if shuffle else np.arange(len(names))
            sec, nsec = divmod(int(stamps[k]), 10 ** 9)
            msg = JointState(header=Header(stamp=Time(sec=sec, nanosec=nsec), frame_id=''),
                             name=[names[j] for j in perm],
                             **{f: v[k, perm] for f, v in vals.items()})
            w.write(js, int(logs[k]), ts.serialize_cdr(msg, JointState.__msgtype__))
            if cmd is not None:
                c = F64(layout=Layout(dim=[], data_offset=0),
                        data=np.asarray(rec.reference[k], dtype=float))
                w.write(cmd, int(stamps[k]) + 100_000, ts.serialize_cdr(c, F64.__msgtype__))
    return {'s': s, 'keep': keep, 'lost': lost, 'written': len(order)}


def drop_bursts(src, dst, bursts: list[tuple[float, float]], *,
                keep: tuple[str, ...] = ('/frf/experiment',)) -> int:
    """
    Copy a bag without the messages logged in bursts.

    Copy the bag ``src`` to ``dst`` without the messages whose log time falls in one of
    the ``bursts`` (t_start [s of the bag clock], duration [s]), on every topic but ``keep``
    (a recorder that stalls loses all streams alike). Returns how many were lost.
    """
    from frf_ident.bag import BagRecorder
    from frf_ident.bag.repair import iter_raw
    spans = [(int(round(a * 1e9)), int(round((a + d) * 1e9))) for a, d in bursts]
    lost = 0
    rec = BagRecorder(chunk_bytes=1 << 20, flush_period_s=1e9)
    rec.open(dst)
    try:
        for topic, msgtype, log, data in iter_raw(src):
            if topic not in keep and any(a <= log < b for a, b in spans):
                lost += 1
                continue
            rec.write(topic, msgtype, log, data)
    finally:
        rec.close()
    return lost


def write_rosbag2(path, rec: Recording, imp: Imperfections | None = None, *, seed: int = 1,
                  preset: str = '', config: str = '', max_size: int = 0,
                  max_duration_s: int = 0, compression_mode: str = '') -> dict:
    """
    Write a recording with rosbag2 itself.

    Write ``rec`` with rosbag2 itself (``rosbag2_py.SequentialWriter``, storage 'mcap'),
    as ``ros2 bag record`` stores what it receives: the log time is the receive time, the
    header stamp the sample time (they disagree by ``imp.log_offset`` + 250 us + Exp(50 us)).

    ``preset``: MCAP storage preset ('zstd_fast', 'zstd_small': chunk compression);
    ``config``: storage config file (e.g. ``compression: Lz4``); ``max_size`` [bytes] /
    ``max_duration_s``: split into several files; ``compression_mode``: rosbag2's own
    compression ('file' or 'message', zstd). Needs ROS 2 (rosbag2_py, rclpy) importable.
    """
    from rclpy.serialization import serialize_message
    import rosbag2_py
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray
    imp = imp or Imperfections()
    rng = np.random.default_rng(seed)
    s, keep, lost = _sample_plan(rec, imp, rng)
    vals = {k: CubicSpline(rec.t, getattr(rec, k), axis=0)(s)
            for k in ('position', 'velocity', 'effort')}
    stamps = np.round((s + T0) * 1e9).astype(np.int64)
    logs = stamps + int(round(imp.log_offset * 1e9)) + 250_000 \
        + rng.exponential(50_000, s.size).astype(np.int64)
    opts = rosbag2_py.StorageOptions(uri=str(path), storage_id='mcap',
                                     max_bagfile_size=int(max_size),
                                     max_bagfile_duration=int(max_duration_s),
                                     storage_preset_profile=preset,
                                     storage_config_uri=str(config))
    if compression_mode:
        copts = rosbag2_py.CompressionOptions()
        copts.compression_format = 'zstd'
        copts.compression_mode = rosbag2_py.compression_mode_from_string(compression_mode)
        writer = rosbag2_py.SequentialCompressionWriter(copts)
    else:
        writer = rosbag2_py.SequentialWriter()
    writer.open(opts, rosbag2_py.ConverterOptions('cdr', 'cdr'))
    writer.create_topic(rosbag2_py.TopicMetadata(0, '/joint_states', 'sensor_msgs/msg/JointState',
                                                 'cdr'))
    writer.create_topic(rosbag2_py.TopicMetadata(1, '/velocity_controller/commands',
                                                 'std_msgs/msg/Float64MultiArray', 'cdr'))
    names = list(rec.joint_names)
    for k in np.flatnonzero(keep):
        msg = JointState()
        sec, nsec = divmod(int(stamps[k]), 10 ** 9)
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nsec
        msg.name = names
        msg.position = vals['position'][k].tolist()
        msg.velocity = vals['velocity'][k].tolist()
        msg.effort = vals['effort'][k].tolist()
        writer.write('/joint_states', serialize_message(msg), int(logs[k]))
        cmd = Float64MultiArray()
        cmd.data = rec.reference[k].tolist()
        writer.write('/velocity_controller/commands', serialize_message(cmd),
                     int(stamps[k]) + 100_000)
    del writer                                       # closes the bag, writes metadata.yaml
    return {'s': s, 'keep': keep, 'lost': lost}
