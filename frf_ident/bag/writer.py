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
Write a finished frf_ident recording as a rosbag2 MCAP bag (metadata.yaml version 9).

:func:`write_recording` turns a finished (e.g. simulated) :class:`Recording` into a bag on
the docs/CONTRACT.md §3 topics, log time = header stamp. The bag is written beside the path
and moved there whole; its recording_meta descriptor carries the formula of the exact float
time grid (:func:`grid_times`).

It and :class:`~frf_ident.bag.recorder.BagRecorder` (recording from a running node) use
rosbags' ``Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)`` with the chunk CRC
filled in (:mod:`frf_ident.bag.mcap_storage`), the ROS2_JAZZY typestore (message definitions
and RIHS01 hashes, :mod:`frf_ident.bag.message_dict`) and always record
``offered_qos_profiles`` (docs/bag_format.md; ros2 bag play offers each topic
with them, e.g. /frf/experiment transient-local).
"""
from __future__ import annotations

import json
import os
from pathlib import Path
import shutil
import tempfile
from typing import Any

from frf_ident.core.jsonable import json_default
from frf_ident.core.recording import Recording
from frf_ident.errors import BagError
import numpy as np
from rosbags.interfaces import Connection
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys.store import Typestore

from . import cdr
from .mcap_storage import CrcWriter
from .message_dict import typestore
from .topics import BagTopics, FLOAT64_ARRAY, JOINT_STATE, STRING

__all__ = ['BAG_FORMAT', 'FRF_BAG_KEY', 'grid_times', 'write_recording']

#: key of the recording_meta event that lets the reader rebuild the exact float time grid.
FRF_BAG_KEY = '_frf_bag'
BAG_FORMAT = 1


# --------------------------------------------------------------------------- write_recording

def write_recording(rec: Recording, path: str | os.PathLike[str], *,
                    topics: BagTopics | None = None, overwrite: bool = False) -> Path:
    """
    Write ``rec`` as a rosbag2 MCAP bag directory at ``path`` and return the path.

    Topics (names from ``topics``): joint states per sample, velocity commands (finite
    reference rows only), effort commands, the excitation as JointState.velocity, experiment
    descriptors at segment start/end, and one ``recording_meta`` descriptor at the first stamp.
    An existing ``path`` is refused unless ``overwrite``; even then the old bag is only
    replaced after the new one has been written completely.
    """
    topics = topics or BagTopics()
    path = Path(path)
    if path.exists() and not overwrite:
        raise BagError(f'bag path {str(path)!r} exists; refusing to overwrite recorded data '
                       f'(pass overwrite=True or choose another path)')
    stamps = _stamps_ns(rec)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp_root = Path(tempfile.mkdtemp(prefix=f'.{path.name}.', dir=path.parent))
    try:
        tmp = tmp_root / path.name
        _write_bag(rec, stamps, tmp, topics)
        _replace(tmp, path)
    finally:
        shutil.rmtree(tmp_root, ignore_errors=True)
    return path


def _replace(new: Path, dst: Path) -> None:
    """Move ``new`` to ``dst``; an existing ``dst`` is removed only after the move worked."""
    if not dst.exists():
        new.rename(dst)
        return
    backup = dst.with_name(f'.{dst.name}.old-{os.getpid()}')
    dst.rename(backup)
    try:
        new.rename(dst)
    except OSError:
        backup.rename(dst)
        raise
    if backup.is_dir():
        shutil.rmtree(backup)
    else:
        backup.unlink()


def _stamps_ns(rec: Recording) -> np.ndarray:
    t = np.asarray(rec.t, dtype=float)
    if t.size == 0:
        raise BagError('recording has no samples; nothing to write')
    if not np.all(np.isfinite(t)) or t[0] < 0:
        raise BagError(f'recording times must be finite and >= 0 s (t[0]={t[0]!r})')
    stamps = np.round(t * 1e9).astype(np.int64)
    if np.any(np.diff(stamps) <= 0):
        raise BagError('recording times must increase by at least 1 ns per sample')
    return stamps


def _time_grid(t: np.ndarray) -> dict[str, Any] | None:
    """
    Return a formula that reproduces ``t`` bit-exactly (see :func:`grid_times`), or None.

    Tried: ``t0 + k*dt`` ('mul'), ``t0 + k/fs`` ('div') and ``(k0 + k)*dt`` ('idx'), the
    ways simulations build their time vectors.
    """
    if t.size < 2:
        return None
    t0, n = float(t[0]), int(t.size)
    dts = (float(t[1] - t[0]), float(np.median(np.diff(t))), float((t[-1] - t[0]) / (n - 1)))
    candidates: list[dict[str, Any]] = [{'grid': 'mul', 't0': t0, 'dt': dt} for dt in dts]
    for dt in dts:
        fs = 1.0 / dt
        candidates += [{'grid': 'div', 't0': t0, 'fs': f} for f in (fs, float(round(fs)))]
        candidates.append({'grid': 'idx', 'k0': int(round(t0 / dt)), 'dt': dt})
    for cand in candidates:
        if np.array_equal(grid_times(cand, n), t):
            return cand
    return None


def grid_times(spec: dict[str, Any], n: int, start: int = 0) -> np.ndarray:
    """
    Return the float times of samples ``start ..

    start + n - 1`` of a ``_time_grid`` spec (each element identical to the same element of the
    whole grid).
    """
    k = np.arange(start, start + n)
    if spec['grid'] == 'mul':
        return float(spec['t0']) + k * float(spec['dt'])
    if spec['grid'] == 'div':
        return float(spec['t0']) + k / float(spec['fs'])
    if spec['grid'] == 'idx':
        return (int(spec['k0']) + k) * float(spec['dt'])
    raise ValueError(f'unknown time grid {spec["grid"]!r}')


def _experiment_events(rec: Recording, stamps: np.ndarray) -> list[tuple[int, int, str]]:
    """(stamp_ns, order, json) of the recording_meta and segment start/end descriptors."""
    meta = {'event': 'recording_meta'}
    meta.update(rec.meta)
    frf: dict[str, Any] = {'format': BAG_FORMAT, 'n': int(rec.t.size),
                           'joint_names': list(rec.joint_names), 'reference': 'per_sample'}
    grid = _time_grid(rec.t)
    if grid:
        frf['time'] = grid
    meta[FRF_BAG_KEY] = frf
    events = [(int(stamps[0]), 0, json.dumps(meta, sort_keys=True, default=json_default))]
    for seg in rec.segments:
        for event, t, order in (('start', seg.t_start, 2), ('end', seg.t_end, 1)):
            ns = max(int(round(float(t) * 1e9)), 0)
            events.append((ns, order, seg.descriptor(event)))
    events.sort(key=lambda e: (e[0], e[1]))
    return events


def _write_bag(rec: Recording, stamps: np.ndarray, path: Path, topics: BagTopics) -> None:
    ts = typestore()
    writer = CrcWriter(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    try:
        conn = _connections(writer, ts, rec, topics)
        js = cdr.JointStateEncoder(rec.joint_names)
        events = _experiment_events(rec, stamps)
        ev = 0
        ref_ok = (np.all(np.isfinite(rec.reference), axis=1)
                  if rec.reference is not None else None)
        empty = np.empty(0)
        for k, ns in enumerate(stamps.tolist()):
            while ev < len(events) and events[ev][0] <= ns:
                writer.write(conn['exp'], events[ev][0], cdr.encode_string(events[ev][2]))
                ev += 1
            writer.write(conn['js'], ns, js.encode(ns, rec.position[k], rec.velocity[k],
                                                   rec.effort[k]))
            if ref_ok is not None and ref_ok[k]:
                writer.write(conn['ref'], ns, cdr.encode_float64_array(rec.reference[k]))
            writer.write(conn['eff'], ns, cdr.encode_float64_array(rec.effort[k]))
            if rec.excitation is not None:
                writer.write(conn['exc'], ns, js.encode(ns, empty, rec.excitation[k], empty))
        for ns, _, text in events[ev:]:
            writer.write(conn['exp'], ns, cdr.encode_string(text))
    except BaseException:
        writer.abort()
        raise
    writer.close()


def _connections(writer: Writer, ts: Typestore, rec: Recording,
                 topics: BagTopics) -> dict[str, Connection]:
    def add(topic: str, msgtype: str) -> Connection:
        return writer.add_connection(topic, msgtype, typestore=ts,
                                     offered_qos_profiles=[topics.qos(topic)])

    conn = {'js': add(topics.joint_states, JOINT_STATE)}
    if rec.reference is not None:
        conn['ref'] = add(topics.velocity_commands, FLOAT64_ARRAY)
    conn['eff'] = add(topics.effort_commands, FLOAT64_ARRAY)
    if rec.excitation is not None:
        conn['exc'] = add(topics.excitation, JOINT_STATE)
    conn['exp'] = add(topics.experiment, STRING)
    return conn
