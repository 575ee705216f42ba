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
estimator_node: records the experiment topics to a rosbag2 MCAP bag and estimates the FRF.

Recorded (docs/CONTRACT.md §3): /joint_states, /velocity_controller/commands,
/effort_controller/commands, /frf/excitation, /frf/experiment (free-running, a robot: only
around experiments, from 0.5 s before a segment starts to 0.5 s after its procedure ended,
unless ``record_all: true``; the simulation records everything), with
:class:`frf_ident.bag.BagRecorder` (chunks handed to the OS every 64 KiB / 0.5 s, so a crash
loses at most the open chunk; SIGINT/SIGTERM drain every message already delivered and close
the bag cleanly).

Joint states are written as published, as ``ros2 bag record`` writes them: in lockstep the
plant reports in joint state k+1 the torque it applied from t_k, and the excitation node's
descriptors say so (``effort_lag``: 1); the bag reader pairs (docs/CONTRACT.md §3, one rule
for every recorder and replay path).

Log times are sample times: a joint state or excitation message is logged at its header stamp;
a velocity command at the stamp of the /frf/excitation message the excitation node sends right
before it (same sample); an effort command (lockstep) at the stamp of the joint state it answers;
a descriptor at its own t_start / t_end. The bag therefore reads back on the exact sample grid.

The bag is split (as ``ros2 bag record`` splits a bag: the current file is closed with its
index and listed in metadata.yaml, recording goes on in ``<bag>_<k>.mcap``) when a run is
aborted and when a procedure has ended, so ``ros2 bag info`` / ``ros2 bag play`` / ``frf-ident
estimate`` read every finished or aborted run while the nodes run on.

When a ``procedure_end`` descriptor arrives and the joint states up to its end are recorded,
the bag is split and estimated (``read_recording`` + ``estimate_recording``, as
``frf-ident estimate``) into ``output_dir``/frf.json, in a worker thread.
"""
from __future__ import annotations

from collections import deque
import json
from pathlib import Path
import struct
import threading
import time
from typing import Any, Optional, Sequence

from frf_ident import middleware as mw
from frf_ident.nodes import common as c

JS, F64 = 'sensor_msgs/msg/JointState', 'std_msgs/msg/Float64MultiArray'
#: ``record_all: false`` (a robot): joint states and commands this long before a segment's
#: start [s, stamp time] are kept (its descriptor may arrive after them), and this long after
#: a procedure's end or abort
GATE_MARGIN_S = 0.5
#: at shutdown, wall s to wait for a live estimate still running: drain, this and the bag's
#: close stay within the 5 s ``ros2 launch`` grants after Ctrl-C before it sends SIGTERM
ESTIMATE_WAIT_S = 2.0
STR = 'std_msgs/msg/String'


def _cdr(msg: Any) -> bytes:
    """Return the CDR bytes of a message (or the bytes of a raw subscription as they are)."""
    return msg if isinstance(msg, bytes) else c.to_cdr(msg)


def _header_stamp_ns(data: bytes) -> int:
    """Return header.stamp [ns] of a serialised message that starts with a std_msgs/Header."""
    little = data[1] & 1      # encapsulation: CDR_LE = 0x0001, CDR_BE = 0x0000
    sec, nanosec = struct.unpack_from('<iI' if little else '>iI', data, 4)
    return sec * 1_000_000_000 + nanosec


def _stamped(msg: Any) -> tuple[bytes, int]:
    """Return the CDR bytes and header stamp [ns] of a stamped message (or its raw bytes)."""
    if isinstance(msg, bytes):
        return msg, _header_stamp_ns(msg)
    return c.to_cdr(msg), c.stamp_ns(msg)


class ExperimentGate:
    """
    Which messages a robot's recording keeps: those of experiments, not the idle time between.

    Closed until a segment starts (its ``start`` descriptor): the messages stamped from
    ``margin_s`` before its t_start are then written from a buffer; open until ``margin_s``
    of stamp time after the procedure's ``procedure_end`` or ``aborted`` event.
    """

    def __init__(self, margin_s: float, buffered: int) -> None:
        self.margin_ns = int(round(margin_s * 1e9))
        self.open = False
        self.until_ns: Optional[int] = None
        self.buffer: deque = deque(maxlen=buffered)

    def admit(self, item: tuple[str, str, int, bytes]) -> bool:
        """Return whether to write ``item`` (topic, type, stamp, data) now; else buffer it."""
        if self.open and self.until_ns is not None and item[2] > self.until_ns:
            self.open, self.until_ns = False, None
        if not self.open:
            self.buffer.append(item)
        return self.open

    def start(self, t_start_ns: int) -> list[tuple[str, str, int, bytes]]:
        """Open at a segment start; return the buffered items to write (from the margin)."""
        self.until_ns = None
        if self.open:
            return []
        self.open = True
        keep = [it for it in self.buffer if it[2] >= t_start_ns - self.margin_ns]
        self.buffer.clear()
        return keep

    def end(self, t_end_ns: int) -> None:
        """Close the gate ``margin_s`` of stamp time after a procedure ended or aborted."""
        if self.open:
            self.until_ns = t_end_ns + self.margin_ns


class Estimator:
    def __init__(self, node: Any) -> None:
        from frf_ident.bag import BagRecorder
        from frf_ident.bag.topics import BagTopics
        self.node = node
        self.log = node.get_logger()
        bag = c.param(node, 'bag', '') or f'frf_bag_{time.strftime("%Y%m%d_%H%M%S")}'
        self.out_dir = Path(c.param(node, 'output_dir', '') or f'{bag}_frf')
        self.estimate = bool(c.param(node, 'estimate', True))
        self.lockstep = bool(c.param(node, 'lockstep', c.LOCKSTEP))
        # a robot publishes all day: record experiments only, unless asked (the simulated
        # plant is silent while idle, so the simulation records everything)
        self.record_all = bool(c.param(node, 'record_all', self.lockstep))
        self.gate = None if self.record_all else ExperimentGate(GATE_MARGIN_S, 4 * c.DEEP)
        c.refuse_lockstep_without_sim(node, self.lockstep)
        t = c.topics(node, ('joint_states_topic', 'effort_topic', 'velocity_topic',
                            'excitation_topic', 'experiment_topic'))
        self.t = t
        self.rec = BagRecorder(topics=BagTopics(
            joint_states=t['joint_states_topic'], velocity_commands=t['velocity_topic'],
            effort_commands=t['effort_topic'], excitation=t['excitation_topic'],
            experiment=t['experiment_topic']))
        self.rec.open(bag)
        try:
            self._wire(node, t, bag)
        except BaseException:
            self.rec.close()         # a signal during start-up: never a bag without metadata
            raise

    def _wire(self, node: Any, t: dict[str, str], bag: str) -> None:
        self.bag = Path(bag)
        self.last_js = -1
        self.js_stamps: deque = deque()     # joint-state stamps not yet answered by a command
        self.exc_stamps: deque = deque()    # excitation stamps not yet paired with a command
        self.cmd_wait: deque = deque()      # velocity commands waiting for their stamp
        self.eff_wait: deque = deque()      # effort commands waiting for their joint state
        self.counts = {k: 0 for k in t.values()}
        self.pending_end: list[int] = []
        self.worker: Optional[threading.Thread] = None
        self.estimated = 0
        self.lock = threading.Lock()
        deep = mw.qos_default(c.DEEP)
        # rclpy hands over the CDR bytes themselves (raw=True) where only bytes and the header
        # stamp are needed: no deserialise + serialise per message (the recorder is the graph's
        # busiest node)
        raw = {'raw': True} if mw.backend_name() == 'rclpy' else {}
        raw['drain'] = True     # every queued message per wake (rclpy takes one per wait)
        node.create_subscription(mw.msg(JS), t['joint_states_topic'], self._on_js, deep, **raw)
        node.create_subscription(mw.msg(JS), t['excitation_topic'], self._on_exc, deep, **raw)
        node.create_subscription(mw.msg(F64), t['velocity_topic'], self._on_vel, deep, **raw)
        node.create_subscription(mw.msg(F64), t['effort_topic'], self._on_eff, deep, **raw)
        node.create_subscription(mw.msg(STR), t['experiment_topic'], self._on_exp,
                                 mw.qos_transient_local(100))
        # the live estimate, its warnings and the excitation's progress with its status line
        # (docs/live.md): a replay of the bag shows them in the Foxglove layout, logged at the
        # newest joint state's stamp (when they were made)
        live = c.topics(node, ('live_topic', 'warnings_topic', 'progress_topic'))
        for k in c.LIVE_FRAMES:
            self._record_as_is(node, f'{live["live_topic"]}/{k}', F64, raw)
        self._record_as_is(node, live['warnings_topic'], STR, raw)
        self._record_as_is(node, live['progress_topic'], STR, raw)

    def _record_as_is(self, node: Any, topic: str, msg_type: str, raw: dict) -> None:
        self.counts[topic] = 0

        def on(msg: Any) -> None:
            self._write(topic, msg_type, max(self.last_js, 0), _cdr(msg))
        node.create_subscription(mw.msg(msg_type), topic, on, mw.qos_transient_local(50),
                                 **raw)

    def _write(self, topic: str, msg_type: str, stamp: int, data: bytes) -> None:
        self.counts[topic] += 1
        if self.gate is not None and topic != self.t['experiment_topic'] and not \
                self.gate.admit((topic, msg_type, stamp, data)):
            return
        self.rec.write(topic, msg_type, stamp, data)

    def _on_js(self, msg: Any) -> None:
        data, s = _stamped(msg)
        if s <= self.last_js:
            return                      # the plant's idle re-send of the same sample
        self.last_js = s
        self._write(self.t['joint_states_topic'], JS, s, data)   # as published
        if not self.lockstep:
            return
        if self.eff_wait:
            self._write(self.t['effort_topic'], F64, s, self.eff_wait.popleft())
        else:
            self.js_stamps.append(s)
        if self.pending_end:
            self._maybe_estimate()

    def _on_eff(self, msg: Any) -> None:
        data = _cdr(msg)
        if not self.lockstep:
            self._write(self.t['effort_topic'], F64, max(self.last_js, 0), data)
        elif self.js_stamps:
            self._write(self.t['effort_topic'], F64, self.js_stamps.popleft(), data)
        else:
            self.eff_wait.append(data)

    def _on_exc(self, msg: Any) -> None:
        data, s = _stamped(msg)
        self._write(self.t['excitation_topic'], JS, s, data)
        if self.cmd_wait:
            self._write(self.t['velocity_topic'], F64, s, self.cmd_wait.popleft())
        else:
            self.exc_stamps.append(s)

    def _on_vel(self, msg: Any) -> None:
        data = _cdr(msg)
        if self.exc_stamps:
            self._write(self.t['velocity_topic'], F64, self.exc_stamps.popleft(), data)
        else:
            self.cmd_wait.append(data)

    def _on_exp(self, msg: Any) -> None:
        try:
            d = json.loads(msg.data)
        except ValueError:
            d = {}
        event = d.get('event')
        t_key = 't_start' if event == 'start' else 't_end'
        t_s = d.get(t_key)
        stamp = int(round(float(t_s) * 1e9)) if t_s is not None else max(self.last_js, 0)
        self._write(self.t['experiment_topic'], STR, stamp, c.to_cdr(msg))
        if self.gate is not None:
            if event == 'start':
                for item in self.gate.start(stamp):
                    self.rec.write(*item)
            elif event in ('procedure_end', 'aborted'):
                self.gate.end(stamp)
        if event == 'procedure_end':
            self.pending_end.append(stamp)
            self._maybe_estimate()
        elif event == 'aborted':
            self.rec.split()        # the bag is complete and readable now, recording goes on
            self.log.info(f'run aborted: {self.bag} closed up to here (ros2 bag info reads '
                          f'it); later runs go to its next file')

    def _maybe_estimate(self) -> None:
        """Once the joint states up to a procedure's end are in: split, then estimate."""
        if not self.pending_end or self.last_js < self.pending_end[0]:
            return
        if self.worker is not None and self.worker.is_alive():
            return
        t_end = self.pending_end[-1] if self.last_js >= self.pending_end[-1] else \
            self.pending_end[0]
        self.pending_end = [s for s in self.pending_end if s > t_end]
        self.rec.split()            # every finished run is in closed files metadata.yaml lists
        if not self.estimate:
            return
        self.worker = threading.Thread(target=self._estimate, args=(t_end,), daemon=True)
        self.worker.start()

    def _estimate(self, t_end_ns: int) -> None:
        from frf_ident.app.estimate import estimate_bag
        try:   # only what has been recorded up to the end of the procedure
            estimate_bag(self.bag, self.out_dir, t_range=(0.0, t_end_ns * 1e-9),
                         progress=lambda m: None)
            self.estimated += 1
            self.log.info(f'estimated {self.bag} -> {self.out_dir / "frf.json"}')
        except Exception as exc:
            self.log.error(f'estimation of {self.bag} failed: {type(exc).__name__}: {exc}')

    def drain_and_close(self, node: Any) -> None:
        """Take every message already delivered, then finalise the bag."""
        quiet_since = time.monotonic()
        total = sum(self.counts.values())
        deadline = time.monotonic() + 5.0
        while time.monotonic() - quiet_since < 0.2 and time.monotonic() < deadline:
            mw.spin_once(node, 0.02)
            now = sum(self.counts.values())
            if now != total:
                total, quiet_since = now, time.monotonic()
        # unpaired commands (should not happen in a complete run): keep them, at the last stamp
        for q, topic in ((self.cmd_wait, 'velocity_topic'), (self.eff_wait, 'effort_topic')):
            while q:
                self._write(self.t[topic], F64, max(self.last_js, 0), q.popleft())
        if self.worker is not None:
            self.worker.join(ESTIMATE_WAIT_S)
            if self.worker.is_alive():
                self.log.info(f'live estimate still running at shutdown: left out (run '
                              f'`frf-ident estimate {self.bag}`)')
        self.rec.close()
        self.log.info(f'bag closed: {self.bag} ({json.dumps(self.counts)})')

    def close(self) -> None:
        """Drain, finalise the bag and report its path."""
        try:
            self.drain_and_close(self.node)
            print(f'FRF_BAG {self.bag}', flush=True)
        finally:
            self.rec.close()


def main(argv: Optional[Sequence[str]] = None) -> int:
    """``ros2 run frf_ident estimator_node``."""
    return c.run_node('estimator_node', Estimator, argv)


if __name__ == '__main__':
    raise SystemExit(main())
