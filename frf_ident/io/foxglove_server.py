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
The live stream on a Foxglove WebSocket without ROS (``foxglove-sdk``, extra ``[foxglove]``).

:class:`FoxgloveLive` starts the Foxglove SDK's WebSocket server on loopback and serves the
topics of docs/live.md with the same ROS 2 types, CDR-encoded with their ``ros2msg``
definitions (what ``foxglove_bridge`` serves for a ROS graph), so config/foxglove_layout.json
shows the same panels from this server, from ``foxglove_bridge`` and from a bag:
/frf/live/frf, /frf/live/distortion, /frf/live/summary (std_msgs/msg/Float64MultiArray),
/frf/progress and /frf/warnings (std_msgs/msg/String) and /joint_states
(sensor_msgs/msg/JointState, at most :data:`JOINT_RATE_HZ`).

Nothing is encoded while no client subscribes a channel. A client that subscribes late gets
the newest message of the channel at once (as the transient-local ROS topics give it).
The server binds 127.0.0.1 only (docs/CONTRACT.md: no packet leaves loopback); a viewer on
another machine reaches it through an SSH tunnel.
"""
from __future__ import annotations

import json
import threading
from typing import Any, Optional, Sequence

from frf_ident.errors import FrfIdentInputError
from frf_ident.io.live_frame import ArrayFrame
import numpy as np

__all__ = ['FoxgloveLive', 'JOINT_RATE_HZ', 'LIVE_TOPICS']

#: joint states go to the viewer at most this often: a Plot panel draws at screen rate, and
#: every state would cost the 1 kHz loop's thread an encoding per sample
JOINT_RATE_HZ = 100.0
#: topic -> ROS type of everything served (the names docs/live.md and the layout use)
LIVE_TOPICS = {'/frf/live/frf': 'std_msgs/msg/Float64MultiArray',
               '/frf/live/distortion': 'std_msgs/msg/Float64MultiArray',
               '/frf/live/summary': 'std_msgs/msg/Float64MultiArray',
               '/frf/progress': 'std_msgs/msg/String',
               '/frf/warnings': 'std_msgs/msg/String',
               '/joint_states': 'sensor_msgs/msg/JointState'}
LOOPBACK = '127.0.0.1'


def _sdk() -> Any:
    try:
        import foxglove
    except ImportError:
        raise FrfIdentInputError('the Foxglove WebSocket needs the foxglove-sdk package: '
                                 "pip install 'frf_ident[foxglove]'") from None
    return foxglove


class FoxgloveLive:
    """
    Serve the live topics on ws://127.0.0.1:PORT for the Foxglove app (module docstring).

    Parameters
    ----------
    port : int, optional
        TCP port; 0 picks a free one (:attr:`port` tells which).
    name : str, optional
        The server's name the app shows.
    joint_rate_hz : float, optional
        Largest rate of /joint_states.

    Raises
    ------
    FrfIdentInputError
        foxglove-sdk is not installed, or the port cannot be bound.

    """

    def __init__(self, port: int = 8765, name: str = 'frf_ident',
                 joint_rate_hz: float = JOINT_RATE_HZ) -> None:
        from rosbags.typesys import get_typestore, Stores
        fg = _sdk()
        self.store = get_typestore(Stores.ROS2_JAZZY)
        self.types = self.store.types
        self.latest: dict[str, tuple[bytes, int]] = {}
        self.lock = threading.Lock()
        self.channels: dict[str, Any] = {}
        self.by_id: dict[int, str] = {}
        for topic, ros_type in LIVE_TOPICS.items():
            text, _ = self.store.generate_msgdef(ros_type, ros_version=2)
            ch = fg.Channel(topic, message_encoding='cdr', schema=fg.Schema(
                name=ros_type, encoding='ros2msg', data=text.encode()))
            self.channels[topic] = ch
            self.by_id[ch.id()] = topic
        self.min_gap_ns = int(1e9 / joint_rate_hz) if joint_rate_hz > 0 else 0
        self.last_state_ns: Optional[int] = None
        try:
            self.server = fg.start_server(name=name, host=LOOPBACK, port=int(port),
                                          server_listener=_latch(self, fg))
        except Exception as exc:      # the SDK raises RuntimeError for a port in use
            raise FrfIdentInputError(f'foxglove port {port}: cannot serve on {LOOPBACK} '
                                     f'({exc})') from None

    @property
    def port(self) -> int:
        """Return the TCP port served."""
        return int(self.server.port)

    @property
    def url(self) -> str:
        """Return the WebSocket URL the Foxglove app opens ("Open connection")."""
        return f'ws://{LOOPBACK}:{self.port}'

    def _log(self, topic: str, encode: Any, t_ns: int) -> None:
        """Encode (only when a client listens or for the latch) and send one message."""
        ch = self.channels[topic]
        raw = encode()
        with self.lock:
            self.latest[topic] = (raw, t_ns)
        if ch.has_sinks():
            ch.log(raw, log_time=int(t_ns))

    def frame(self, name: str, frame: ArrayFrame, t_ns: int) -> None:
        """
        Serve a live frame on /frf/live/<name>.

        Parameters
        ----------
        name : str
            'frf', 'distortion' or 'summary'.
        frame : ArrayFrame
            Its dims and data (frf_ident/io/live_frame.py).
        t_ns : int
            Its time [ns] (the log time the app plots against).

        """
        def encode() -> bytes:
            t = self.types
            layout = t['std_msgs/msg/MultiArrayLayout'](dim=[
                t['std_msgs/msg/MultiArrayDimension'](label=lab, size=int(n), stride=int(st))
                for lab, n, st in frame.dims], data_offset=0)
            msg = t['std_msgs/msg/Float64MultiArray'](
                layout=layout, data=np.ascontiguousarray(frame.data, dtype=np.float64))
            return bytes(self.store.serialize_cdr(msg, 'std_msgs/msg/Float64MultiArray'))
        self._log(f'/frf/live/{name}', encode, t_ns)

    def text(self, topic: str, event: dict, t_ns: int) -> None:
        """
        Serve a JSON event as std_msgs/String on /frf/progress or /frf/warnings.

        Parameters
        ----------
        topic : str
            '/frf/progress' or '/frf/warnings'.
        event : dict
            JSON-serialisable.
        t_ns : int
            Its time [ns].

        """
        data = json.dumps(event, sort_keys=True, separators=(',', ':'))
        self._log(topic, lambda: bytes(self.store.serialize_cdr(
            self.types['std_msgs/msg/String'](data=data), 'std_msgs/msg/String')), t_ns)

    def joint_state(self, t_ns: int, names: Sequence[str], position: np.ndarray,
                    velocity: np.ndarray, effort: Optional[np.ndarray]) -> None:
        """
        Serve a joint state on /joint_states, at most :data:`JOINT_RATE_HZ` (others dropped).

        Parameters
        ----------
        t_ns : int
            Its stamp [ns].
        names : sequence of str
            Joint names, in the order of the arrays.
        position, velocity : ndarray, shape (n,)
            Position [rad] and velocity [rad/s].
        effort : ndarray, shape (n,) or None
            Torque [N m] (None: not measured).

        """
        ch = self.channels['/joint_states']
        if not ch.has_sinks() or (self.last_state_ns is not None
                                  and 0 <= t_ns - self.last_state_ns < self.min_gap_ns):
            return
        self.last_state_ns = int(t_ns)
        t = self.types
        sec, nsec = divmod(int(t_ns), 1_000_000_000)
        msg = t['sensor_msgs/msg/JointState'](
            header=t['std_msgs/msg/Header'](stamp=t['builtin_interfaces/msg/Time'](
                sec=sec, nanosec=nsec), frame_id=''), name=list(names),
            position=np.asarray(position, np.float64), velocity=np.asarray(velocity, np.float64),
            effort=np.asarray(effort if effort is not None else [], np.float64))
        ch.log(bytes(self.store.serialize_cdr(msg, 'sensor_msgs/msg/JointState')),
               log_time=int(t_ns))

    def resend(self, channel_id: int) -> None:
        """Send the newest message of a channel again (a client just subscribed it)."""
        topic = self.by_id.get(channel_id)
        with self.lock:
            got = self.latest.get(topic) if topic else None
        if got is not None:
            self.channels[topic].log(got[0], log_time=got[1])

    def close(self) -> None:
        """Stop the server and close its channels."""
        self.server.stop()
        for ch in self.channels.values():
            ch.close()


def _latch(owner: FoxgloveLive, fg: Any) -> Any:
    """Return the server listener: a late subscriber gets the channel's newest message."""
    class Latch(fg.ServerListener):
        def on_subscribe(self, client: Any, channel: Any) -> None:
            # called on the server's thread: send from another, the SDK may hold a lock here
            threading.Thread(target=owner.resend, args=(channel.id,), daemon=True).start()
    return Latch()
