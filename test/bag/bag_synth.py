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
"""Synthetic recordings for the bag tests (3 joints of sines, built with numpy)."""
from __future__ import annotations

from frf_ident.core.recording import Recording, Segment
import numpy as np

JOINTS = ['joint_1', 'joint_2', 'joint_3']
FREQS = np.array([0.7, 1.3, 2.1])  # Hz


def make_recording(seconds: float = 5.0, fs: float = 1000.0, t0: float = 0.0) -> Recording:
    """3 joints of sines; reference NaN before 0.5 s and in a short idle block."""
    n = int(round(seconds * fs))
    t = t0 + np.arange(n) / fs
    w = 2 * np.pi * FREQS
    pos = np.sin(np.outer(t, w)) / w
    vel = np.cos(np.outer(t, w))
    eff = 3.0 * np.sin(np.outer(t, w) + 0.3)
    ref = vel * 1.01
    ref[: int(0.5 * fs)] = np.nan
    ref[int(2.0 * fs):int(2.1 * fs)] = np.nan
    exc = 0.2 * vel
    exc[: int(0.5 * fs)] = np.nan
    segs = [Segment(t0 + 0.5, t0 + 2.0, {'design': 'multisine', 'realisation': 0, 'experiment': 0,
                                         'freq_hz': [1.0, 2.0, 3.0]}),
            Segment(t0 + 2.1, t0 + seconds - 0.5, {'design': 'chirp', 'iteration': 1})]
    meta = {'seed': 7, 'model': {'axes': 3}, 'note': 'synthetic'}
    return Recording(t, list(JOINTS), pos, vel, eff, ref, exc, segs, meta)


def truth(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the clean (position, velocity, effort) of make_recording at arbitrary times t."""
    w = 2 * np.pi * FREQS
    return (np.sin(np.outer(t, w)) / w, np.cos(np.outer(t, w)),
            3.0 * np.sin(np.outer(t, w) + 0.3))


def write_robot_bag(path, *, seconds: float = 10.0, fs: float = 1000.0, jitter: float = 0.01,
                    drop: float = 0.005, gap: tuple[float, int] | None = None,
                    seed: int = 1, effort: bool = True, extra=None):
    """
    Return a /joint_states-only bag as a real robot records it, written with rosbags.

    Timing model (documented in docs/bag_format.md): the controller samples at
    s_k = t0 + k*dt + u_k with u_k ~ U(-jitter*dt, +jitter*dt) (scheduling jitter) and stamps
    each JointState with that instant, so the values are the true signals at s_k. A fraction
    ``drop`` of the messages is lost at random (never the first/last); ``gap`` = (t, n) removes
    n consecutive samples starting at time t. Receive (log) time = s_k + 250 us + Exp(50 us)
    transport latency. The joint order is shuffled in every message.
    """
    from frf_ident.bag.topics import QOS_DEFAULT
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores

    store = get_typestore(Stores.ROS2_JAZZY)
    js_t = store.types['sensor_msgs/msg/JointState']
    hdr_t, time_t = store.types['std_msgs/msg/Header'], store.types['builtin_interfaces/msg/Time']
    rng = np.random.default_rng(seed)
    n = int(round(seconds * fs))
    dt = 1.0 / fs
    t0 = 100.0
    s = t0 + np.arange(n) * dt + rng.uniform(-jitter * dt, jitter * dt, n)
    keep = rng.random(n) >= drop
    keep[[0, -1]] = True
    if gap is not None:
        i = int(round(gap[0] * fs))
        keep[i:i + gap[1]] = False
    pos, vel, eff = truth(s)
    stamps = np.round(s * 1e9).astype(np.int64)
    logs = stamps + 250_000 + rng.exponential(50_000, n).astype(np.int64)
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection('/joint_states', 'sensor_msgs/msg/JointState', typestore=store,
                                offered_qos_profiles=[QOS_DEFAULT])
        for k in np.flatnonzero(keep):
            perm = rng.permutation(len(JOINTS))
            sec, nsec = divmod(int(stamps[k]), 10**9)
            msg = js_t(header=hdr_t(stamp=time_t(sec=sec, nanosec=nsec), frame_id=''),
                       name=[JOINTS[j] for j in perm], position=pos[k, perm],
                       velocity=vel[k, perm],
                       effort=eff[k, perm] if effort else np.empty(0))
            w.write(conn, int(logs[k]), store.serialize_cdr(msg, msg.__msgtype__))
        if extra is not None:
            extra(w, store)
    return {'stamps': stamps, 'keep': keep, 't0': t0, 'dt': dt}
