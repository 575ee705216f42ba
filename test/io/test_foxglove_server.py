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
The Foxglove WebSocket of the live stream, seen by a client on loopback.

The client speaks the Foxglove WebSocket protocol itself (the ``websockets`` package,
subprotocol ``foxglove.sdk.v1``, the only one foxglove-sdk 0.30 accepts):
serverInfo and advertise arrive as JSON, it subscribes a channel, and each message arrives as
a binary frame (opcode 1, subscription id, log time, CDR payload). The FRF is a known one
(a second-order system's response) and the received magnitude and phase are checked against
numpy's, not against the encoder.
"""
from __future__ import annotations

import asyncio
import json
import struct

from frf_ident.io.foxglove_layout import layout
from frf_ident.io.foxglove_server import FoxgloveLive, LIVE_TOPICS
from frf_ident.io.live_frame import decode_frf, frf_frame
import numpy as np
import pytest
from rosbags.typesys import get_typestore, Stores
import websockets

STORE = get_typestore(Stores.ROS2_JAZZY)


def _known_frf() -> tuple[np.ndarray, np.ndarray]:
    f = np.linspace(1.0, 50.0, 50)
    s = 2j * np.pi * f
    wn, zeta = 2 * np.pi * 20.0, 0.05
    p = wn ** 2 / (s ** 2 + 2 * zeta * wn * s + wn ** 2)
    return f, np.stack([np.stack([p, 0.1 * p]), np.stack([0.2 * p, 2 * p])])


class Client:
    """A Foxglove WebSocket client: channels by topic, subscriptions, binary messages."""

    def __init__(self, ws) -> None:
        self.ws, self.channels, self.subs = ws, {}, {}

    async def handshake(self) -> dict:
        info = json.loads(await self.ws.recv())
        while set(self.channels) != set(LIVE_TOPICS):
            m = json.loads(await self.ws.recv())
            if m['op'] == 'advertise':
                self.channels.update({c['topic']: c for c in m['channels']})
        return info

    async def subscribe(self, topic: str, sub_id: int) -> None:
        self.subs[sub_id] = topic
        await self.ws.send(json.dumps({'op': 'subscribe', 'subscriptions': [
            {'id': sub_id, 'channelId': self.channels[topic]['id']}]}))

    async def message(self, timeout: float = 10.0) -> tuple[str, int, bytes]:
        while True:
            m = await asyncio.wait_for(self.ws.recv(), timeout)
            if isinstance(m, bytes) and m[0] == 1:        # opcode 1: message data
                sub, t = struct.unpack_from('<IQ', m, 1)
                return self.subs[sub], t, m[13:]


def _serve_and_receive(port_server, steps):
    async def run():
        async with websockets.connect(f'ws://127.0.0.1:{port_server.port}',
                                      subprotocols=['foxglove.sdk.v1']) as ws:
            c = Client(ws)
            info = await c.handshake()
            return info, c.channels, await steps(c)
    return asyncio.run(run())


@pytest.fixture
def server():
    s = FoxgloveLive(port=0)
    yield s
    s.close()


def test_client_receives_the_frf_channel(server):
    f, p = _known_frf()
    names = ['joint_1', 'joint_2']
    sd = np.full(p.shape, 0.25)
    frame = frf_frame(f, p, sd, np.full(p.shape, 2.0), np.full((2, f.size), 0.99),
                      names, names)

    async def steps(c):
        await c.subscribe('/frf/live/frf', 3)
        await asyncio.sleep(0.3)                 # the subscription reaches the server
        server.frame('frf', frame, 1_500_000_000)
        return await c.message()

    info, channels, (topic, t, raw) = _serve_and_receive(server, steps)
    assert server.url.startswith('ws://127.0.0.1:')
    ch = channels['/frf/live/frf']
    assert (ch['encoding'], ch['schemaName'], ch['schemaEncoding']) == (
        'cdr', 'std_msgs/msg/Float64MultiArray', 'ros2msg')
    assert 'float64[] data' in ch['schema']
    assert topic == '/frf/live/frf' and t == 1_500_000_000
    msg = STORE.deserialize_cdr(raw, 'std_msgs/msg/Float64MultiArray')
    got = decode_frf([(d.label, d.size, d.stride) for d in msg.layout.dim],
                     np.asarray(msg.data))
    mag = 20 * np.log10(np.abs(p)).reshape(4, -1)
    ph = np.degrees(np.unwrap(np.angle(p), axis=-1)).reshape(4, -1)
    assert np.allclose(got['freq_hz'][0], f, rtol=0, atol=1e-12)
    assert np.allclose(got['magnitude_db'], mag, rtol=1e-12, atol=1e-12)
    assert np.allclose(got['phase_deg'], ph, rtol=0, atol=1e-9)
    # the layout's Bode slice of joint_2's diagonal reads these values from this message
    path = layout(names)['configById']['Plot!bodemag']['paths'][3]['value']
    a, b = (int(x) for x in path.split('[')[1].rstrip(']').split(':'))
    assert path.startswith('/frf/live/frf.data[')
    assert np.allclose(np.asarray(msg.data)[a:b + 1][:f.size], mag[3], rtol=1e-12)


def test_a_late_subscriber_gets_the_newest_message(server):
    server.text('/frf/progress', {'event': 'estimate', 'periods': 2}, 10)
    server.text('/frf/progress', {'event': 'estimate', 'periods': 3}, 20)

    async def steps(c):
        await c.subscribe('/frf/progress', 1)
        return await c.message()

    _info, _channels, (topic, t, raw) = _serve_and_receive(server, steps)
    msg = STORE.deserialize_cdr(raw, 'std_msgs/msg/String')
    assert topic == '/frf/progress' and t == 20
    assert json.loads(msg.data) == {'event': 'estimate', 'periods': 3}


def test_joint_states_are_thinned_to_their_rate(server):
    names = ['joint_1', 'joint_2', 'joint_3']

    async def steps(c):
        await c.subscribe('/joint_states', 5)
        await asyncio.sleep(0.3)
        for k in range(1000):                   # 1 s of states at 1 kHz
            server.joint_state(k * 1_000_000, names, np.full(3, 0.1 * k), np.arange(3.0) + k,
                               np.full(3, -1.0))
        got = []
        try:
            while True:
                got.append(await c.message(timeout=1.0))
        except asyncio.TimeoutError:
            return got

    _info, _channels, got = _serve_and_receive(server, steps)
    assert len(got) == 100                       # JOINT_RATE_HZ over 1 s
    assert [t for _topic, t, _raw in got] == [k * 10_000_000 for k in range(100)]
    msg = STORE.deserialize_cdr(got[7][2], 'sensor_msgs/msg/JointState')
    assert list(msg.name) == names and msg.header.stamp.nanosec == 70_000_000
    assert np.array_equal(msg.velocity, np.arange(3.0) + 70)


def test_a_port_in_use_is_one_clear_error(server):
    from frf_ident.errors import FrfIdentInputError
    with pytest.raises(FrfIdentInputError, match=f'foxglove port {server.port}'):
        FoxgloveLive(port=server.port)
